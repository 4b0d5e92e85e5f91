"""Every shell command the documentation shows, and how ``tests/test_documented_commands.py`` checks it.

The commands are collected from README.md and docs/**/*.md (:func:`collect`): every line of a fenced
``bash``/``console``/``sh``/``shell`` block (``\\`` continuations joined, a trailing ``  # comment``
dropped, a console block's ``$ `` prompt removed), and every inline code span that is a magexp command
with arguments (``magexp ...``, ``python -m magexp...``, ``.venv/bin/...``), except a template with a
``<placeholder>`` or ``...``. A collected command missing from :data:`COMMANDS` fails the test: new
docs must say how their commands are checked.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]

FENCE = re.compile(r"^```(\w*)[^\n]*\n(.*?)^```", re.M | re.S)
SHELLS = {"bash", "console", "sh", "shell"}
SPAN = re.compile(r"(?<!`)`([^`\n]+)`(?!`)")
INLINE = re.compile(r"^(?:\.venv/bin/)?(?:python -m magexp(?:\.[\w.]+)?|magexp)(?:\s|$)")
SUBCOMMANDS = {"calibrate", "reproduce", "-m"}


def _strip_comment(line: str) -> str:
    """``line`` without a trailing shell comment (``#`` after whitespace, outside quotes)."""
    quote = None
    for k, c in enumerate(line):
        if quote:
            quote = None if c == quote else quote
        elif c in "'\"":
            quote = c
        elif c == "#" and (k == 0 or line[k - 1].isspace()):
            return line[:k].rstrip()
    return line.rstrip()


def _is_inline_command(span: str) -> bool:
    if not INLINE.match(span) or re.search(r"<[^>]*>|\.\.\.", span):
        return False
    words = span.split()
    words = words[3:] if "python" in words[0] else words[1:]  # after the program
    if span.split()[0].endswith("python") and span.split()[2] != "magexp":
        return True  # python -m magexp.<module>: a command of its own
    return bool(words) and not (len(words) == 1 and words[0] in SUBCOMMANDS)


def fenced_lines(text: str):
    """``(line number, command, its trailing comment)`` of every line of ``text``'s shell blocks, in order."""
    for fence in FENCE.finditer(text):
        if fence.group(1) not in SHELLS:
            continue
        line0 = text[: fence.start(2)].count("\n") + 1
        body = re.sub(r"\\\n\s*", "", fence.group(2))
        for k, line in enumerate(body.splitlines()):
            line = (line[2:] if fence.group(1) == "console" and line.startswith("$ ") else line).strip()
            command = _strip_comment(line)
            if command:
                yield line0 + k, command, line[len(command):].strip()


def collect() -> dict[str, list[str]]:
    """``{command: [where it is documented, ...]}`` of every documented command (module docstring)."""
    found: dict[str, list[str]] = {}
    for doc in DOCS:
        text = doc.read_text()
        name = doc.relative_to(ROOT).as_posix()
        for number, command, _ in fenced_lines(text):
            found.setdefault(command, []).append(f"{name}:{number}")
        outside = FENCE.sub(lambda m: "\n" * m.group(0).count("\n"), text)
        for span in SPAN.finditer(outside):
            if _is_inline_command(span.group(1)):
                found.setdefault(span.group(1), []).append(f"{name}:{outside[: span.start()].count(chr(10)) + 1}")
    return found


# -- how each is checked -------------------------------------------------------------------------------
#: run as written (``bash -c``) in a temporary clone (every top-level entry of the checkout linked
#: into a fresh folder, ``../shared/data`` beside it when the recordings exist), with ``.venv/bin``
#: first on PATH (what ``source .venv/bin/activate`` does, so a bare ``python``/``magexp`` is magexp's)
#: and a temporary run cache (so it computes); its exit code must be ``exit``. In ``make test``.
RUN = "run"
#: the same, in ``make test-full`` only (seconds to a minute each); a run, sweep or reproduction among
#: them is also composed in ``make test`` (as :data:`COMPOSE`)
RUN_FULL = "run, full"
#: parsed and composed, nothing run (long commands, or ones that write results/): a run or sweep
#: through magexp's own preflight (every job composed with Hydra, its scenario and estimator built,
#: its memory and work within the limits; ``hydra.*`` keys composed with the hydra node); a
#: reproduction's arguments parsed and its artifacts planned; ``make`` as ``make -n`` (the recipe
#: printed); a ``key=value`` naming a path (``*.path``, ``*.file``) must exist
COMPOSE = "compose"
#: a shell step with no magexp in it (an editor, a folder's permissions): ``bash -n`` parses it
SHELL = "shell"
#: ``pip install`` of this checkout: the extras it names exist in pyproject.toml; installing the
#: wheel and running it elsewhere is ``tests/test_install.py`` (make test-full)
PIP = "pip"
#: the walk-through of docs/extending.md ("Start from the scaffold"): it writes into ``experiments/``, so it runs
#: in order in a copy of the repository, in ``tests/test_extending.py`` (make test-full), never in a linked clone
WALKTHROUGH = "walk-through"
#: a command of the past that docs/measurements.md records (it ran at the commits the page names):
#: those commits exist in the clone's history, and a ``python -m magexp.<module>`` existed there
HISTORY = "history"

#: files a command names that are the reader's own: the test writes them into the clone first
MINE = "mine.csv (a simulated magexp-recording v1 in uT, 400 readings)"
MOCKUP_COPY = "a copy of data/yan2022_mockup.csv (the format the page describes)"
MINE_ATTITUDES = "attitudes.csv (a simulated magexp-recording v1 with heading, roll, trim and the field)"

#: ``command: (how, why)`` plus, for some, ``{"exit": code, "shared": True, "files": {...}, "replace": {...}}``:
#: ``shared``: it reads ../shared/data (skipped cleanly without it); ``files``: what the test writes
#: into the clone first; ``replace``: a placeholder of the page and what stands for it
COMMANDS: dict[str, tuple] = {
    # README.md, docs/guide/runs.md: the two commands (minutes and the suite itself: make -n)
    "make reproduce": (COMPOSE, "every run of every paper: about 13 min on 2 cores"),
    "make test": (COMPOSE, "the suite that runs this test"),
    "make reproduce EXECUTOR=dask SCHEDULER=slurm JOBS=50": (COMPOSE, "needs a SLURM cluster"),
    # one run, a sweep, the composed config
    ".venv/bin/python -m magexp scenario=ding2024_exp1 estimator=ipso seed=3": (RUN_FULL, "3 s"),
    ".venv/bin/magexp scenario=ding2024_exp1 estimator=ipso seed=3": (RUN_FULL, "3 s"),
    ".venv/bin/magexp scenario=ding2024_exp2 estimator=lm scenario.noise=5": (RUN_FULL, "2 s"),
    ".venv/bin/python -m magexp -m estimator=pso,ipso scenario.noise=0,2,5,10 seed='range(10)'":
        (COMPOSE, "80 swarm runs"),
    ".venv/bin/magexp -m estimator=pso,ipso scenario.noise=0,2,5,10 seed='range(10)'": (COMPOSE, "80 swarm runs"),
    ".venv/bin/magexp -m estimator=pso,ipso seed='range(40)'": (COMPOSE, "80 swarm runs on every core"),
    ".venv/bin/magexp -m estimator=pso,ipso seed='range(40)' hydra.launcher.jobs=1": (COMPOSE, "80 swarm runs"),
    ".venv/bin/magexp -m estimator=pso,ipso seed='range(40)' hydra.launcher.executor=dask":
        (COMPOSE, "80 swarm runs on a local Dask cluster"),
    ".venv/bin/magexp -m estimator=pso,ipso scenario.noise=0,2,5,10 seed='range(100)' hydra.launcher.executor=dask "
    "hydra.launcher.scheduler=slurm hydra.launcher.jobs=50": (COMPOSE, "needs a SLURM cluster"),
    ".venv/bin/python -m magexp --cfg job estimator=lm": (RUN, "prints the config"),
    ".venv/bin/magexp --cfg job estimator=lm": (RUN_FULL, "prints the config (the console script of the line above)"),
    "magexp --cfg job": (RUN_FULL, "prints the config (the same program as the line above)"),
    ".venv/bin/magexp --help": (RUN, "prints the groups"),
    "magexp --help": (RUN_FULL, "prints the groups (the same program as the line above)"),
    "python -m magexp scenario=ding2024_exp1 estimator=kf": (RUN, "the documented refusal: one line", {"exit": 2}),
    "python -m magexp estimator=my_method": (COMPOSE, "the estimator the page adds: composed with the page's "
                                             "conf/estimator/my_method.yaml beside conf/ (its mypackage is the reader's)"),
    # reproductions
    ".venv/bin/magexp reproduce all --only ding2024_fig3 --seeds 20 --out scratch/": (RUN_FULL, "20 s"),
    ".venv/bin/magexp reproduce all --only ding2024_fig3": (COMPOSE, "writes the canonical results/"),
    "magexp reproduce all --force": (COMPOSE, "every run of every paper, into results/"),
    "magexp reproduce yan2022 --out scratch": (RUN_FULL, "30 s"),
    "magexp reproduce --help": (RUN_FULL, "prints the options"),
    # docs/extending.md: a new paper from the scaffold, and its reproduction (seconds: closed-form fits)
    "magexp new-paper smith2025": (WALKTHROUGH, "writes experiments/smith2025/"),
    "magexp reproduce smith2025 --out scratch": (WALKTHROUGH, "the scaffolded paper, then the completed one"),
    "magexp reproduce --limits": (RUN_FULL, "20 s: plans every artifact"),
    "magexp reproduce all --limits": (RUN_FULL, "20 s: plans every artifact (the paper is not read)"),
    # checking a reproduction (README.md, docs/results.md): reproduces what the cache lacks, then compares
    "make verify": (COMPOSE, "every run of every paper that the cache lacks"),
    "python -m magexp verify": (COMPOSE, "every run of every paper that the cache lacks"),
    "python -m magexp verify --paper yan2022": (COMPOSE, "the runs of yan2022 that the cache lacks"),
    # the installed wheel (docs/guide/runs.md): the same console script, from another folder
    "pip install .": (PIP, "installs into the reader's environment"),
    "pip install -e '.[cluster]'": (PIP, "installs dask-jobqueue"),
    "cd ~/anywhere": (SHELL, "the reader's folder"),
    "magexp scenario=yan2022_mockup estimator=ls": (RUN_FULL, "12 readings, closed form: a process of 1 CPU-s"),
    "magexp -m estimator=ellipsoid,lm scenario.noise=0,5": (RUN_FULL, "4 closed-form runs: 2.4 s"),
    # calibrate your own recording
    ".venv/bin/python -m magexp calibrate --help": (RUN, "every key"),
    ".venv/bin/python -m magexp calibrate data.path=../shared/data/fxos8700_mag_readings.txt data.unit=uT estimator=lm "
    "out=calib/": (RUN_FULL, "a recording", {"shared": True}),
    ".venv/bin/python -m magexp calibrate data.path=../shared/data/fxos8700_mag_readings.txt data.unit=uT estimator=ipso "
    "estimator.n_iterations=3000 seed=1 out=calib_ipso/": (RUN_FULL, "ipso and its held-out fits", {"shared": True}),
    ".venv/bin/python -m magexp calibrate data.path=../shared/data/fxos8700_mag_readings.txt data.unit=uT "
    "field.latitude=52.2 field.longitude=0.1 field.date=2024-05-01 out=calib_igrf/": (RUN_FULL, "a recording",
                                                                                     {"shared": True}),
    ".venv/bin/python -m magexp calibrate data.path=../shared/data/hmc5883l_full-sphere export=ardupilot figure=true "
    "out=calib_ardupilot/": (RUN_FULL, "draws the figure", {"shared": True}),
    ".venv/bin/python -m magexp calibrate data.path=../shared/data/hmc5883l_full-sphere field.latitude=52.2 "
    "field.longitude=0.1 field.date=2024-05-01": (RUN_FULL, "a recording", {"shared": True}),
    ".venv/bin/python -m magexp.calibration.simulate attitudes.csv": (RUN_FULL, "writes a recording with attitudes: 1.5 s"),
    ".venv/bin/python -m magexp calibrate data.path=attitudes.csv objective=vector estimator=lm":
        (RUN_FULL, "2 s", {"files": {"attitudes.csv": MINE_ATTITUDES}}),
    ".venv/bin/python -m magexp scenario=yan2022_mockup scenario.path=/path/to/mine.csv estimator=kf":
        (RUN_FULL, "1 s", {"replace": {"/path/to/mine.csv": "mine_mockup.csv"},
                           "files": {"mine_mockup.csv": MOCKUP_COPY}}),
    ".venv/bin/python -m magexp scenario=yan2022_mockup estimator=kf estimator.p0=1000 estimator.n_steps=120":
        (RUN_FULL, "12 readings, a filter"),
    "python -m magexp scenario=yan2022_mockup estimator=kf +analysis=field_kalman": (RUN_FULL, "12 readings, the field filter"),
    # the public recordings (../shared/data)
    ".venv/bin/python -m magexp calibrate data.path=../shared/data/fxos8700_mag_readings.txt data.unit=uT export=px4":
        (RUN_FULL, "a recording", {"shared": True}),
    ".venv/bin/python -m magexp calibrate data.path=../shared/data/fxos8700_mag_readings.txt data.unit=uT estimator=lm":
        (RUN_FULL, "a recording", {"shared": True}),
    ".venv/bin/python -m magexp calibrate data.path=../shared/data/hmc5883l_full-sphere estimator=lm":
        (RUN_FULL, "a two-stream stem relative to the working folder", {"shared": True}),
    ".venv/bin/python -m magexp scenario=real_hmc5883l_full_sphere estimator=lm": (RUN_FULL, "gyro-aided",
                                                                                   {"shared": True}),
    ".venv/bin/python -m magexp scenario=real_hmc5883l_rotate_ccw_around_z scenario.window=null estimator=lm":
        (RUN_FULL, "gyro-aided, the whole recording", {"shared": True}),
    ".venv/bin/python -m magexp calibrate data.path=../shared/data/xio_fusion_sensor_data.csv model=sphere accept=true":
        (RUN_FULL, "a recording", {"shared": True}),
    ".venv/bin/python -m magexp calibrate data.path=../shared/data/qmc5883l_noisy_raw_data.csv":
        (RUN_FULL, "a recording the gate accepts", {"shared": True}),
    # live calibration (docs/calibrate.md): a serial port read as standard input here (the port itself:
    # tests/test_calibrate_live.py, through a pseudo-terminal)
    ".venv/bin/python -m magexp calibrate data.serial=/dev/ttyUSB0 data.baud=115200 data.unit=uT out=calib_live/":
        (RUN_FULL, "the same stream from standard input, the reader's port being absent",
         {"shared": True, "replace": {"data.serial=/dev/ttyUSB0": "data.path=- <../shared/data/fxos8700_mag_readings.txt"}}),
    ".venv/bin/python -m magexp calibrate data.path=- data.unit=uT out=calib_stdin/ < ../shared/data/fxos8700_mag_readings.txt":
        (RUN_FULL, "a recording piped in", {"shared": True}),
    ".venv/bin/python -m magexp calibrate data.path=../shared/data/hmc5883l_roll-and-tilt-at-45-90 model=gyro "
    "accept=true export=ardupilot out=calib_gyro/":
        (RUN_FULL, "the gyro-aided export (test_calibration_gyro_auto applies ArduPilot's equations to it)",
         {"shared": True}),
    # the benches and the warm-up
    # docs/results.md, Sample sizes: the planned seeds of each comparison (planning only, no run: 2 s)
    "python -m magexp.artifacts.sample_sizes yuan2018": (RUN_FULL, "prints each comparison's effect, level, seeds and power"),
    "python -m magexp.perf.bench --help": (RUN_FULL, "prints the options (two interpreters: one BLAS thread)"),
    "python -m magexp.site --screenshot docs/img/explorer.png": (RUN_FULL, "builds the site and photographs the "
                                                                  "explorer in headless Chromium: 20 s",
                                                                  {"replace": {"docs/img/explorer.png": "explorer.png"}}),
    "python -m magexp.artifacts.kinds": (RUN_FULL, "rewrites the table of kinds in docs/extending.md (the same "
                                         "bytes when current, which test_extending checks)"),
    "python -m magexp.core.readers": (RUN_FULL, "rewrites the table of formats in docs/calibrate.md (the same "
                                      "bytes when current, which test_extending checks)"),
    "python -m magexp.perf.warmup": (RUN_FULL, "the kernels compiled once (make venv)"),
    "python -m magexp.perf.autocost": (RUN_FULL, "auto beside full on every shared recording with a gyroscope: 80 s",
                                       {"shared": True}),
    "python -m magexp.perf.crosstable": (RUN_FULL, "every HMC5883L calibration on every HMC5883L recording: 30 s",
                                         {"shared": True}),
    ".venv/bin/python -m magexp.perf.peers.bench --redraw --out results/peers":
        (RUN_FULL, "redraws the clone's copy of results/peers", {"files": {"results/peers": "a copy of results/peers"}}),
    "python -m magexp.perf.peers.bench --redraw --out results/peers":
        (RUN_FULL, "redraws the clone's copy of results/peers", {"files": {"results/peers": "a copy of results/peers"}}),
    "make peers-tools-bench": (COMPOSE, "builds the peer tools' own environment (PyPI) first"),
    # a shared run cache on a cluster (docs/guide/sweeps.md)
    "$EDITOR ~/.config/dask/jobqueue.yaml": (SHELL, "dask-jobqueue's own config, in the reader's editor"),
    "mkdir -p /shared/magexp && chgrp mygroup /shared/magexp && chmod 2775 /shared/magexp":
        (SHELL, "the reader's shared folder and group"),
    "export MAGEXP_CACHE=/shared/magexp/runs": (SHELL, "the reader's shared folder"),
    # docs/measurements.md: how issue 13's speed was measured, at the commits it names
    "git worktree add --detach ../kit 40aaccd": (HISTORY, "the replay and the list"),
    "git worktree add --detach ../old b533850": (HISTORY, "the code before"),
    "(cd ../old && python3 -m venv .venv && .venv/bin/pip install -c ../kit/requirements.lock -e '.[test]')":
        (HISTORY, "the code before, installed"),
    "cd ../kit && make venv": (HISTORY, "the replay's environment"),
    ".venv/bin/python -m magexp.workload replay --jobs 2": (HISTORY, "at 40aaccd"),
    ".venv/bin/python -m magexp.workload compare --old ../old --jobs 2 --rounds 3 --every 10": (HISTORY, "at 40aaccd"),
    ".venv/bin/python -m magexp.sweep_bench --rounds 7": (HISTORY, "at 40aaccd"),
    "python -m magexp.workload replay --jobs 2": (HISTORY, "at 40aaccd"),
    "python -m magexp.sweep_bench": (HISTORY, "at 40aaccd"),
}
