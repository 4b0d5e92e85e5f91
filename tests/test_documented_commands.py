"""Every command of README.md and docs/ works as written from a fresh clone after ``make venv``.

The commands are collected from the pages, and each is listed in ``tests/documented_commands.py``
with how it is checked (run as written, in ``make test`` or ``make test-full``; parsed and composed;
a shell step parsed; a recorded command of the past checked against its commits). A command of the
docs missing from that list fails :func:`test_every_documented_command_is_listed`.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import tomllib

import numpy as np
import pytest

from documented_commands import (COMMANDS, COMPOSE, HISTORY, MINE, MINE_ATTITUDES, MOCKUP_COPY, PIP, RUN, RUN_FULL, SHELL,
                                 collect)
from magexp.core.geometry import ship_attitude
from magexp.paths import DATA, ROOT, SHARED_DATA, SOURCE_CHECKOUT

pytestmark = pytest.mark.skipif(not SOURCE_CHECKOUT, reason="the docs' commands run in a source checkout")

VENV_BIN = ROOT / ".venv" / "bin"
#: the prefixes of a magexp command (``python`` being .venv's, as after ``source .venv/bin/activate``)
PROGRAMS = (".venv/bin/python -m ", "python -m ", ".venv/bin/magexp", "magexp")


def by_kind(*kinds: str) -> list[str]:
    return [command for command, (kind, *_) in COMMANDS.items() if kind in kinds]


def options(command: str) -> dict:
    entry = COMMANDS[command]
    return entry[2] if len(entry) > 2 else {}


def test_every_documented_command_is_listed():
    """Every command the docs show has an entry saying how it is checked, and every entry is still shown."""
    documented = collect()
    missing = {c: where for c, where in documented.items() if c not in COMMANDS}
    assert not missing, f"documented commands with no check in tests/documented_commands.py: {missing}"
    stale = sorted(set(COMMANDS) - set(documented))
    assert not stale, f"tests/documented_commands.py lists commands no page shows any more: {stale}"


def test_the_collector_reads_fences_continuations_comments_and_spans(tmp_path, monkeypatch):
    import documented_commands

    page = tmp_path / "page.md"
    page.write_text("Run `magexp --cfg job` or `python -m magexp.perf.bench --help`, not `magexp calibrate`,\n"
                    "`magexp ...` or `magexp calibrate data.format=<format>`.\n\n```bash\n"
                    "make test   # the suite\nmagexp -m seed=1,2 \\\n    hydra.launcher.jobs=1\necho '#no'\n```\n\n"
                    "```console\n$ magexp --help\n```\n\n```python\nimport magexp\n```\n")
    monkeypatch.setattr(documented_commands, "DOCS", [page])
    monkeypatch.setattr(documented_commands, "ROOT", tmp_path)
    assert list(documented_commands.collect()) == [
        "make test", "magexp -m seed=1,2 hydra.launcher.jobs=1", "echo '#no'", "magexp --help", "magexp --cfg job",
        "python -m magexp.perf.bench --help"]


# -- the temporary clone -------------------------------------------------------------------------------

def write_mine(path):
    """A recording of the reader's: 400 readings of a distorted 50 uT sphere, magexp-recording v1 in uT."""
    rng = np.random.default_rng(31)
    u = rng.normal(size=(400, 3))
    u *= 50.0 / np.linalg.norm(u, axis=1, keepdims=True)
    s = np.array([[1.05, 0.02, -0.01], [0.02, 0.97, 0.03], [-0.01, 0.03, 1.01]])
    raw = u @ s.T + [5.0, -3.0, 2.0] + rng.normal(scale=0.05, size=u.shape)
    rows = "".join(f"{x:.4f},{y:.4f},{z:.4f}\n" for x, y, z in raw)
    path.write_text("# magexp-recording v1\n# unit: uT\nbx,by,bz\n" + rows)


def write_with_attitudes(path):
    """A recording of the reader's with attitudes and the field: 400 readings, angles in radians."""
    rng = np.random.default_rng(32)
    field = np.array([34425.0, 1961.0, 35898.0])
    angles = np.column_stack([rng.uniform(0, 2 * np.pi, 400), rng.uniform(-np.pi / 2, np.pi / 2, 400),
                              rng.uniform(-np.pi, np.pi, 400)])
    body = ship_attitude(*angles.T) @ field
    s = np.array([[1.03, 0.01, 0.02], [-0.02, 0.98, 0.01], [0.01, 0.02, 1.02]])
    raw = body @ s.T + [300.0, -200.0, 150.0] + rng.normal(scale=20.0, size=body.shape)
    rows = "".join(f"{b[0]:.2f},{b[1]:.2f},{b[2]:.2f},{a[0]:.6f},{a[1]:.6f},{a[2]:.6f}\n" for b, a in zip(raw, angles))
    path.write_text("# magexp-recording v1\n# unit: nT\n# angles: rad\n# field: 34425, 1961, 35898\n"
                    "bx,by,bz,heading,roll,trim\n" + rows)


def bare_clone(tmp_path):
    """A folder that looks like a fresh clone after ``make venv``: every top-level entry of the checkout
    linked into it (its own writes stay in it), ``../shared/data`` beside it when the recordings exist."""
    clone = tmp_path / "clone"
    clone.mkdir()
    for entry in ROOT.iterdir():
        if entry.name not in (".git", "results", ".cache", "outputs", "multirun", "site", ".pytest_cache"):
            (clone / entry.name).symlink_to(entry)
    if SHARED_DATA.is_dir():
        (tmp_path / "shared").mkdir()
        (tmp_path / "shared" / "data").symlink_to(SHARED_DATA)
    return clone


def make_clone(tmp_path, command: str):
    """:func:`bare_clone` with the reader's files of ``command`` written into it."""
    clone = bare_clone(tmp_path)
    for name, what in options(command).get("files", {}).items():
        target = clone / name
        target.parent.mkdir(parents=True, exist_ok=True)
        if what == MINE:
            write_mine(target)
        elif what == MOCKUP_COPY:
            shutil.copy(DATA / "yan2022_mockup.csv", target)
        elif what == MINE_ATTITUDES:
            write_with_attitudes(target)
        elif name == "results/peers":
            shutil.copytree(ROOT / "results" / "peers", target)
        else:
            raise AssertionError(f"no way to write {name!r} ({what})")
    return clone


def shell_env(tmp_path) -> dict:
    """The environment of ``source .venv/bin/activate``, with a temporary run cache (so a run computes)."""
    return {**os.environ, "PATH": f"{VENV_BIN}{os.pathsep}{os.environ.get('PATH', '')}", "VIRTUAL_ENV": str(ROOT / ".venv"),
            "MAGEXP_CACHE": str(tmp_path / "cache")}


def run_as_written(command: str, tmp_path):
    opts = options(command)
    if opts.get("shared") and not SHARED_DATA.is_dir():
        pytest.skip(f"{SHARED_DATA} is not present")
    clone = make_clone(tmp_path, command)
    for placeholder, value in opts.get("replace", {}).items():
        command = command.replace(placeholder, value)
    proc = subprocess.run(["bash", "-c", command], cwd=clone, env=shell_env(tmp_path), capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == opts.get("exit", 0), (command, proc.stdout[-1500:], proc.stderr[-1500:])
    if opts.get("exit", 0):  # a documented refusal: one line
        assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr


@pytest.mark.parametrize("command", by_kind(RUN))
def test_documented_command_runs(command, tmp_path):
    run_as_written(command, tmp_path)


@pytest.mark.full
@pytest.mark.parametrize("command", by_kind(RUN_FULL))
def test_documented_command_runs_in_full(command, tmp_path):
    run_as_written(command, tmp_path)


# -- parsed and composed -------------------------------------------------------------------------------

def split_program(command: str) -> tuple[str, list[str]]:
    """``(program, arguments)``: ``magexp`` (a run or sweep), ``magexp calibrate``, ``magexp reproduce``,
    ``python -m <module>``, ``make``."""
    words = shlex.split(command)
    if words[0] == "make":
        return "make", words[1:]
    if words[0].endswith("python") and words[1] == "-m":
        module, words = words[2], words[3:]
        if module != "magexp":
            return f"python -m {module}", words
    else:
        words = words[1:]
    if words and words[0] in ("calibrate", "reproduce", "verify"):
        return f"magexp {words[0]}", words[1:]
    return "magexp", words


def check_paths(arguments: list[str], cwd) -> None:
    for arg in arguments:
        key, _, value = arg.partition("=")
        if key.endswith((".path", ".file")):
            assert (cwd / value).exists() or (cwd / f"{value}_mag.csv").exists(), f"{arg}: no such file"


def compose_run(arguments: list[str], tmp_path) -> None:
    """A run or sweep through magexp's preflight: every job composed and checked, nothing run."""
    from magexp.run.compose import hydra_compose
    from magexp.run.preflight import expand_sweep, validate_runs

    sweep = "-m" in arguments
    overrides = [a for a in arguments if a != "-m"]
    if "estimator=my_method" in overrides:  # the page's own example config, beside conf/
        yaml = re.search(r"# conf/estimator/my_method.yaml\n(.*?)```", (ROOT / "docs" / "extending.md").read_text(),
                         re.S).group(1)
        (tmp_path / "estimator").mkdir()
        (tmp_path / "estimator" / "my_method.yaml").write_text("\n".join(line.strip() for line in yaml.splitlines()))
        cfg = hydra_compose((f"hydra.searchpath=[file://{tmp_path}]", *overrides))
        assert cfg.estimator.name == "my_method"
        return
    jobs = [o for o in overrides if not o.startswith("hydra.")]
    validate_runs(expand_sweep(jobs) if sweep else [jobs], keep=False)
    hydra_keys = [o for o in overrides if o.startswith("hydra.")]
    if hydra_keys:
        cfg = hydra_compose(tuple(hydra_keys), with_hydra=True)
        for key in hydra_keys:
            name, _, value = key.partition("=")
            assert str(cfg.hydra.launcher[name.rpartition(".")[2]]) == value


def compose_reproduce(arguments: list[str]) -> None:
    from magexp.artifacts.reproduce import available_papers, check_canonical, check_reproduction, parser, select

    args = parser().parse_args(arguments)
    selected = select(available_papers() if args.paper == "all" else [args.paper], args.only)
    assert check_reproduction(selected, args.seeds) > 0
    check_canonical(args.out, seeds=args.seeds, tiny=args.tiny)


def composable(command: str) -> bool:
    """A run, sweep or reproduction (no ``--help``/``--cfg``/``--limits``) on no file the test writes."""
    opts = options(command)
    program, arguments = split_program(command)
    return (program in ("magexp", "magexp reproduce") and not {"--help", "--cfg", "--limits"} & set(arguments)
            and not opts.get("files")
            and not opts.get("replace") and not (opts.get("shared") and not SHARED_DATA.is_dir()))


@pytest.mark.parametrize("command", by_kind(COMPOSE) + [c for c in by_kind(RUN_FULL) if composable(c)])
def test_documented_command_composes(command, tmp_path):
    program, arguments = split_program(command)
    check_paths(arguments, ROOT)
    if program == "make":
        proc = subprocess.run(["make", "-n", *arguments], cwd=ROOT, capture_output=True, text=True, timeout=60)
        assert proc.returncode == 0, proc.stderr
        settings = dict(a.split("=", 1) for a in arguments if "=" in a)
        for var, flag in (("EXECUTOR", "--executor"), ("SCHEDULER", "--scheduler"), ("JOBS", "--jobs")):
            if var in settings:  # the variable reaches the command make runs
                assert f"{flag} {settings[var]}" in proc.stdout, proc.stdout
    elif program == "magexp reproduce":
        compose_reproduce(arguments)
    elif program == "magexp verify":
        from magexp.artifacts.verify import parser as verify_parser

        verify_parser().parse_args(arguments)
    else:
        assert program == "magexp", f"no composer for {program}"
        compose_run(arguments, tmp_path)


@pytest.mark.parametrize("command", by_kind(SHELL))
def test_documented_shell_step_parses(command):
    proc = subprocess.run(["bash", "-n", "-c", command], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr


@pytest.mark.parametrize("command", by_kind(PIP))
def test_documented_install_names_this_project_and_its_extras(command):
    """``pip install [-e] .[extras]``: the extras exist; the install itself: tests/test_install.py (make test-full)."""
    target = shlex.split(command)[-1]
    assert target.startswith("."), command
    extras = re.findall(r"[\w-]+", target.partition("[")[2])
    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    assert set(extras) <= set(declared), f"{command}: extras {set(extras) - set(declared)} are not in pyproject.toml"


def test_documented_history_is_in_the_clones_history():
    """docs/measurements.md's commands ran at the commits it names: they exist, with the modules run there."""
    if not (ROOT / ".git").exists() or shutil.which("git") is None:
        pytest.skip("not a git clone")
    shallow = subprocess.run(["git", "rev-parse", "--is-shallow-repository"], cwd=ROOT, capture_output=True, text=True)
    if shallow.stdout.strip() == "true":
        pytest.skip("a shallow clone has no history")
    commands = by_kind(HISTORY)
    commits = {c for command in commands for c in re.findall(r"\b[0-9a-f]{7,40}\b", command)}
    assert commits, "docs/measurements.md names no commit"
    modules = {m for command in commands for m in re.findall(r"-m (magexp\.[\w.]+)", command)}
    replay = next(c for c in commits if c in next(cmd for cmd in commands if "../kit" in cmd))
    for commit in commits:
        assert subprocess.run(["git", "cat-file", "-e", f"{commit}^{{commit}}"], cwd=ROOT).returncode == 0, commit
    for module in modules:
        path = module.replace(".", "/") + ".py"
        assert subprocess.run(["git", "cat-file", "-e", f"{replay}:{path}"], cwd=ROOT,
                              capture_output=True).returncode == 0, f"{path} is not in {replay}"
