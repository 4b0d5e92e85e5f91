"""Shared fixtures: composing configs through the one composer, a throw-away run cache, and the
command line run in-process (the process boundary itself is tested in ``test_cli.py``)."""

from __future__ import annotations

import functools
import gc
import itertools
import subprocess
from pathlib import Path

from magexp.run.threads import one_blas_thread

one_blas_thread()  # as magexp's commands do, before numpy is imported: deterministic numbers


import pytest  # noqa: E402
import yaml  # noqa: E402

from magexp.run.compose import compose_config  # noqa: E402


@pytest.fixture
def make_cfg():
    """``make_cfg(*overrides)`` -> the composed run config (:func:`magexp.run.compose.compose_config`)."""

    def _make(*overrides):
        return compose_config(list(overrides))

    return _make


@pytest.fixture
def cli(capsys, monkeypatch):
    """``cli(*args, cwd=folder)`` -> the ``CompletedProcess`` of ``magexp ARGS`` run in-process.

    The same code as ``python -m magexp ARGS`` (:func:`magexp.__main__.main`) in the test's
    own process, from ``cwd``, into the test's run cache: its exit code (a ``SystemExit``, or 0
    on return) and what it printed, without the 0.5-1 s of a fresh interpreter per call.
    """
    from magexp.__main__ import main

    def _run(*args, cwd=None):
        capsys.readouterr()  # what the test printed before is not the command's
        with monkeypatch.context() as m:
            if cwd is not None:
                m.chdir(cwd)
            try:
                main([str(a) for a in args])
                code = 0
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
        out, err = capsys.readouterr()
        return subprocess.CompletedProcess(["magexp", *map(str, args)], code, out, err)

    return _run


def _session_root(tmp_path_factory):
    """The test session's folder, common to its xdist workers."""
    root = tmp_path_factory.getbasetemp()
    return root.parent if root.name.startswith("popen-gw") else root


@pytest.fixture(scope="session")
def _caches(tmp_path_factory):
    """The folder of the run caches of the tests that have no ``tmp_path`` of their own."""
    return tmp_path_factory.getbasetemp() / "caches"


_TESTS = itertools.count()


@pytest.fixture(autouse=True)
def _isolated_cache(request, monkeypatch, _caches):
    """Each test gets its own run cache, so nothing is read from or left in .cache/: ``tmp_path / "cache"``
    for a test with a ``tmp_path``, else a folder of its own that the cache creates if it writes (most
    tests never do: a ``tmp_path`` for each would cost a folder per test)."""
    if "tmp_path" in request.fixturenames:
        folder = request.getfixturevalue("tmp_path") / "cache"
    else:
        folder = _caches / str(next(_TESTS)) / "cache"  # what lives beside it (the figure cache) its own too
    monkeypatch.setattr("magexp.paths.CACHE", folder)
    monkeypatch.setattr("magexp.run.cache.CACHE", folder)


@pytest.fixture
def figures_not_rendered(monkeypatch):
    """Figures built (every artist, from their CSV) and not rendered: four fifths of a figure's cost is
    matplotlib rendering text. Each PNG and PDF file holds a placeholder (the report links them);
    returns ``{figure name: number of axes built}``. For the tests whose subject is not the drawing:
    the rendering, the layout, the PDF twin and the defects of every figure are tests/test_figures.py's
    and tests/test_figure_defects.py's, and the same CSV giving the same figure bytes is
    tests/test_reproduce.py's."""
    from magexp.artifacts.plots import style

    built: dict[str, int] = {}

    def save(fig, path):
        try:
            built[path.stem] = len(fig.axes)
        finally:
            style.plt.close(fig)
        for twin in (path, path.with_suffix(".pdf")):
            twin.write_bytes(b"built, not rendered")
        return [path, path.with_suffix(".pdf")]

    monkeypatch.setattr(style, "save", save)
    return built


LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml's safe loader: 10x faster, the same objects


@functools.lru_cache(maxsize=None)
def _missing_recording(value) -> str | None:
    """The recording a parametrised scenario or artifact reads, when it is absent from
    :data:`magexp.paths.SHARED_DATA` (the recordings of others are never shipped), else None."""
    from magexp.paths import CONF, EXPERIMENTS, SHARED_DATA

    if isinstance(value, Path) and value.suffix == ".yaml":  # an artifact file
        value = value.stem
    if not isinstance(value, str):
        return None
    scenario = CONF / "scenario" / f"{value}.yaml"
    if scenario.is_file():
        name = (yaml.load(scenario.read_text(), Loader=LOADER) or {}).get("file")
        files = [] if not name else [name] if "." in name else [f"{name}_mag.csv"]
    else:
        artifacts = list(EXPERIMENTS.glob(f"*/{value}.yaml"))
        files = (yaml.load(artifacts[0].read_text(), Loader=LOADER) or {}).get("requires_data") or [] if artifacts else []
    return next((f for f in files if not (SHARED_DATA / f).is_file()), None)


def pytest_collection_modifyitems(config, items):
    """Tests parametrised over a recorded scenario or artifact skip cleanly without the recordings;
    the ``slow`` tests run first (in two processes with work stealing, the short ones then fill the gaps: no long tail)."""
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)  # stable: slow first, in file order
    for item in items:
        params = getattr(getattr(item, "callspec", None), "params", {})
        for value in params.values():
            try:
                missing = _missing_recording(value)  # each value's files read once, not once per test
            except TypeError:  # a value that is not hashable: no recording named by it
                missing = None
            if missing:
                item.add_marker(pytest.mark.skip(reason=f"{missing} is not in the recordings folder (MAGEXP_DATA)"))
                break


def pytest_collection_finish(session):
    """The objects every test shares (the modules imported, the items collected) frozen out of the garbage
    collector's passes, and its youngest generation collected every 20 000 allocations instead of 700: the
    collector took 5.5 s of the suite's CPU time in two processes, 2.4 s so (measured with ``gc.callbacks``).
    Only when collection is due changes: what a test keeps alive or frees is the same."""
    gc.collect()
    gc.freeze()
    gc.set_threshold(20_000, 10, 10)


#: a small whole reproduction (6 runs of the mock-up: ls, kf and the paper's values, 2 seeds; 2 tasks)
MOCKUP_ARGS = ("yan2022", "--only", "yan2022_table_mockup", "--seeds", "2", "--tiny", "--jobs", "1")


def reproduce_into(out, cache_dir, args=MOCKUP_ARGS) -> int:
    """``python -m magexp.artifacts.reproduce ARGS --out out`` in this process, on the run cache ``cache_dir``."""
    from magexp import paths
    from magexp.artifacts.reproduce import main
    from magexp.run import cache

    saved = cache.CACHE, paths.CACHE
    cache.CACHE = paths.CACHE = cache_dir
    try:
        return main([*args, "--out", str(out)])
    finally:
        cache.CACHE, paths.CACHE = saved


@pytest.fixture(scope="session")
def mockup_reproduction(tmp_path_factory):
    """One clean reproduction of :data:`MOCKUP_ARGS` shared by the tests that compare with it or start
    from it, made once for all xdist workers (read-only: copy before changing anything): ``args``,
    ``runs`` (its run cache), ``out`` (its output folder), ``files`` (every file it wrote, by relative
    path, with its bytes) and ``reproduce_into``."""
    import fcntl
    from types import SimpleNamespace

    root = _session_root(tmp_path_factory) / "mockup"  # one for every xdist worker: the first makes it
    root.mkdir(exist_ok=True)
    with open(root / "lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (root / "done").exists():
            assert reproduce_into(root / "out", root / "runs") == 0
            (root / "done").touch()
    files = {p.relative_to(root / "out").as_posix(): p.read_bytes()
             for p in sorted((root / "out").rglob("*")) if p.is_file()}
    return SimpleNamespace(args=list(MOCKUP_ARGS), runs=root / "runs", out=root / "out", files=files,
                           reproduce_into=reproduce_into)


def pytest_terminal_summary(terminalreporter):
    """The architecture report (the largest modules, the deepest import chains) at the end of a session that
    ran ``tests/test_architecture.py``, in one process or several: signals a reviewer reads, not limits."""
    ran = any("test_architecture.py::" in getattr(r, "nodeid", "")
              for reports in terminalreporter.stats.values() for r in reports)
    if ran:
        from test_architecture import report  # the test module's own measure, imported only when it ran

        terminalreporter.write_sep("-", "architecture report (tests/test_architecture.py)")
        for line in report():
            terminalreporter.write_line(line)
