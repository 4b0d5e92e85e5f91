"""Shared fixtures: composing configs through the one composer, a throw-away run cache, and the
command line run in-process (the process boundary itself is tested in ``test_cli.py``)."""

from __future__ import annotations

from magexp.run.threads import one_blas_thread

one_blas_thread()  # as magexp's commands do, before numpy is imported: deterministic numbers

import subprocess  # noqa: E402

import pytest  # noqa: E402

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


@pytest.fixture(autouse=True)
def _isolated_cache(tmp_path, monkeypatch):
    """Each test gets its own run cache, so nothing is read from or left in .cache/."""
    monkeypatch.setattr("magexp.paths.CACHE", tmp_path / "cache")
    monkeypatch.setattr("magexp.run.cache.CACHE", tmp_path / "cache")


def _missing_recording(value) -> str | None:
    """The recording a parametrised scenario or artifact reads, when it is absent from
    :data:`magexp.paths.SHARED_DATA` (the recordings of others are never shipped), else None."""
    import yaml

    from magexp.paths import CONF, EXPERIMENTS, SHARED_DATA

    from pathlib import Path

    if isinstance(value, Path) and value.suffix == ".yaml":  # an artifact file
        value = value.stem
    if not isinstance(value, str):
        return None
    scenario = CONF / "scenario" / f"{value}.yaml"
    if scenario.is_file():
        name = (yaml.safe_load(scenario.read_text()) or {}).get("file")
        files = [] if not name else [name] if "." in name else [f"{name}_mag.csv"]
    else:
        artifacts = list(EXPERIMENTS.glob(f"*/{value}.yaml"))
        files = (yaml.safe_load(artifacts[0].read_text()) or {}).get("requires_data") or [] if artifacts else []
    return next((f for f in files if not (SHARED_DATA / f).is_file()), None)


def pytest_collection_modifyitems(config, items):
    """Tests parametrised over a recorded scenario or artifact skip cleanly without the recordings;
    the ``slow`` tests run first (in two processes with work stealing, the short ones then fill the gaps: no long tail)."""
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)  # stable: slow first, in file order
    for item in items:
        params = getattr(getattr(item, "callspec", None), "params", {})
        for value in params.values():
            missing = _missing_recording(value)
            if missing:
                item.add_marker(pytest.mark.skip(reason=f"{missing} is not in the recordings folder (MAGEXP_DATA)"))
                break
