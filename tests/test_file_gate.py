"""The one gate of every file read (issue 41, item 1; :mod:`magexp.run.files`): what passes, what is refused
through each path a file enters by, in how long and how much memory, and the readers' memory per byte read."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from magexp.artifacts.verify import results_folder
from magexp.core.limits import LIMITS, check_limits
from magexp.errors import MagexpError
from magexp.paths import DATA, ROOT, SHARED_DATA
from magexp.run import files
from magexp.run.files import check_recording_file
from magexp.run.files import READ_MEMORY, check_file, recording_files, scan_lines

ONE_LINE = "1," * 5_000_000  # 10 MB of one line: read whole by a reader, it took 2.4 GB (issue 41)


def test_every_recording_of_others_and_of_magexp_passes():
    """The defaults are generous: every recording shipped or shared (and its two-stream stems) passes the gate."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"{SHARED_DATA} is absent")
    paths = [p for p in [*SHARED_DATA.iterdir(), *DATA.iterdir()] if p.is_file() and p.suffix != ".md"]
    stems = {Path(str(p)[: -len("_mag.csv")]) for p in paths if p.name.endswith("_mag.csv")}
    for path in [*paths, *stems]:
        check_recording_file(path, "data.path")
        assert files.check_recording(path, "data.path") > 0, path
    assert len(recording_files(next(iter(stems)))) == 2  # a stem is both its files


@pytest.mark.parametrize("text, longest", [(b"", 0), (b"abc\n", 3), (b"a\nbb\nccc", 3), (b"\n\n", 0),
                                           (b"x" * 10 + b"\n" + b"y" * 3, 10), (b"ab\ncdefghij\nk", 8)])
def test_the_line_scan_measures_lines_across_blocks(tmp_path, monkeypatch, text, longest):
    path = tmp_path / "f.txt"
    path.write_bytes(text)
    for chunk in (1, 3, 4, 1 << 20):
        monkeypatch.setattr(files, "CHUNK", chunk)
        assert scan_lines(path, "x", len(text)) == longest


def test_a_long_line_is_refused_and_the_scan_holds_one_block(tmp_path, monkeypatch):
    """A 10 MB line is refused after its first block; allowed, it is scanned holding about one block."""
    path = tmp_path / "one_line.txt"
    path.write_text(ONE_LINE)
    with pytest.raises(MagexpError, match=r"data.path=.*one_line.txt.*longer than 64 KiB.*MAGEXP_MAX_LINE"):
        check_file(path, "data.path")
    short = tmp_path / "short.txt"
    short.write_text("1,2,3\n" * 2_000_000)  # the most line ends a block can hold
    monkeypatch.setenv("MAGEXP_MAX_LINE", "100MB")
    for file in (path, short):
        tracemalloc.start()
        scan_lines(file, "x", file.stat().st_size)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        assert peak < 6 * files.CHUNK, (file.name, peak)  # the block, a byte a byte, 16 a line end


def test_special_and_unknown_size_files_are_refused_unread(tmp_path):
    os.mkfifo(tmp_path / "pipe")
    cases = {"/dev/zero": "character device", str(tmp_path / "pipe"): "a FIFO", "/proc/self/status": "size is unknown",
             str(tmp_path): "a folder"}
    for path, words in cases.items():
        for kind in ("text", "json", "ulog"):
            with pytest.raises(MagexpError, match=words):
                check_file(path, "x", kind=kind)
    assert check_file(tmp_path, "x", folder=True) == 0 and check_file(tmp_path / "absent", "x") == 0


def test_the_size_and_memory_limits_hold_for_every_kind(tmp_path, monkeypatch):
    path = tmp_path / "log.ulg"
    path.write_bytes(bytes(range(256)) * 400)  # 100 KiB, no line end: a log has no line limit
    assert check_file(path, "x", kind="ulog") == path.stat().st_size
    monkeypatch.setenv("MAGEXP_MAX_FILE", "50KiB")
    with pytest.raises(MagexpError, match=r"x=.*log.ulg.*100 KiB, over the limit 50 KiB \(MAGEXP_MAX_FILE"):
        check_file(path, "x", kind="ulog")
    monkeypatch.delenv("MAGEXP_MAX_FILE")
    monkeypatch.setenv("MAGEXP_MAX_RUN_MEMORY", "500KiB")  # 100 KiB at 8 bytes a byte: 800 KiB
    with pytest.raises(MagexpError, match=r"reading its 100 KiB needs about 800 KiB.*MAGEXP_MAX_RUN_MEMORY"):
        check_file(path, "x", kind="ulog")


@pytest.mark.parametrize("value", ["", " ", "-5", "0", "abc", "nan", "1e999"])
def test_every_limit_variable_is_checked_whether_or_not_it_is_consulted(monkeypatch, value):
    for lim in LIMITS.values():
        with monkeypatch.context() as m:
            m.setenv(lim.env, value)
            with pytest.raises(MagexpError, match=f"{lim.env}={value!r} is not allowed: give a number > 0"):
                check_limits()
    assert {lim.env for lim in LIMITS.values()} >= {"MAGEXP_MAX_FILE", "MAGEXP_MAX_LINE", "MAGEXP_MAX_READINGS"}


def test_a_results_folder_holds_its_files_and_each_passes_the_gate(tmp_path):
    folder = tmp_path / "r"
    folder.mkdir()
    with pytest.raises(MagexpError, match="not a results folder.*summary.csv and no claims.csv"):
        results_folder(str(folder), "--committed")
    for name in ("summary.csv", "claims.csv"):
        (folder / name).write_text("a,b\n1,2\n")
    assert results_folder(str(folder), "--committed") == folder
    os.mkfifo(folder / "sub.csv")
    with pytest.raises(MagexpError, match="--committed=.*sub.csv.*a FIFO"):
        results_folder(str(folder), "--committed")
    (folder / "sub.csv").unlink()
    (folder / "long.csv").write_text(ONE_LINE)
    with pytest.raises(MagexpError, match="long.csv.*MAGEXP_MAX_LINE"):
        results_folder(str(folder), "--against")


def test_verify_says_where_it_reproduces_and_never_into_a_users_folder(tmp_path):
    """The default folder of a reproduction (beside the run cache) holding a user's file is refused, not emptied."""
    cache = tmp_path / "cache"
    (tmp_path / "verify").mkdir()
    (tmp_path / "verify" / "notes.txt").write_text("mine\n")
    done = subprocess.run([sys.executable, "-m", "magexp", "verify"], cwd=ROOT, capture_output=True, text=True,
                          env={**os.environ, "MAGEXP_CACHE": str(cache)}, timeout=60)
    if "differs from the committed one" in done.stdout:
        pytest.skip("results/ differs from the committed one: verify checks it, reproducing nothing")
    assert done.returncode == 2 and len(done.stderr.splitlines()) == 1, done.stderr
    assert "verify" in done.stderr and "no reproduction's" in done.stderr and "--into" in done.stderr
    assert (tmp_path / "verify" / "notes.txt").read_text() == "mine\n" and not cache.exists()


# ---------------------------------------------------------------------------------------------
# in processes: every path, in under 5 s and 500 MB

def _paths(work: Path, target: str) -> dict[str, list[str]]:
    """The command or call of each path a file enters by, reading ``target``."""
    api = "import magexp, sys; magexp.calibrate(sys.argv[1], unit='uT')"
    load = "import magexp, sys; magexp.Calibration.load(sys.argv[1])"
    out = {"data.path": ["-m", "magexp", "calibrate", f"data.path={target}", "data.unit=uT", f"out={work / 'o'}"],
           "scenario.path": ["-m", "magexp", "scenario=yan2022_mockup", "estimator=ls", f"scenario.path={target}",
                             f"hydra.run.dir={work / 'run'}"],
           "magexp.calibrate": ["-c", api, target], "Calibration.load": ["-c", load, target]}
    if SHARED_DATA.is_dir():
        out["scenario.file"] = ["-m", "magexp", "scenario=real_fxos8700", "estimator=lm", f"scenario.file={target}",
                                f"hydra.run.dir={work / 'run'}"]
    return out


@pytest.mark.full
@pytest.mark.parametrize("target", ["/dev/zero", "pipe.fifo", "one_line.txt"])
def test_every_path_refuses_quickly_and_in_little_memory(tmp_path, target):
    """Issue 41: /dev/zero, a FIFO and a 10 MB one-line file through each path that reads a file: one line, exit 2
    (an exception for the API), in under 5 s of the processor (its time on a machine shared with other work may
    be longer: under 15 s) and under 500 MB (the process's peak, /usr/bin/time)."""
    timer = shutil.which("time") or "/usr/bin/time"
    if not os.access(timer, os.X_OK):
        pytest.skip("no /usr/bin/time to measure a process's peak memory")
    os.mkfifo(tmp_path / "pipe.fifo")
    (tmp_path / "one_line.txt").write_text(ONE_LINE)
    path = target if target.startswith("/") else str(tmp_path / target)
    env = {**os.environ, "MAGEXP_CACHE": str(tmp_path / "cache"), "PYTHONPATH": str(ROOT)}
    for name, args in _paths(tmp_path, path).items():
        start = time.perf_counter()
        done = subprocess.run([timer, "-f", "%M %U %S", "-o", str(tmp_path / "peak"), sys.executable, *args],
                              cwd=tmp_path, env=env, capture_output=True, text=True, timeout=30)
        wall = time.perf_counter() - start
        peak_kb, user, system = (tmp_path / "peak").read_text().split()[-3:]
        seconds, peak_mb = float(user) + float(system), int(peak_kb) / 1024
        lines = done.stderr.strip().splitlines()
        assert done.returncode in (1, 2) and ("MagexpError" in done.stderr or len(lines) == 1), (name, done.stderr)
        assert "not allowed" in lines[-1], (name, lines[-1])
        assert seconds < 5 and wall < 15 and peak_mb < 500, (name, target, seconds, wall, peak_mb)


# ---------------------------------------------------------------------------------------------
# the readers' memory: a stated multiple of the bytes they read

MEASURE = """
import json, resource, sys, tracemalloc
from pathlib import Path
from magexp.core.recordings import load_recording
kind, small, big = sys.argv[1], Path(sys.argv[2]), Path(sys.argv[3])
read = (lambda p: json.loads(p.read_text())) if kind == "json" else (lambda p: load_recording(p, unit="uT" if
        kind == "plain" else None))
read(small)
if kind == "dataflash":  # a 64 KiB log: below the resolution of the resident size, its allocations are counted
    tracemalloc.start()
    read(big)
    peak = tracemalloc.get_traced_memory()[1]
else:  # the resident size (tracemalloc's own records would swell it): what pandas' C parser holds counts too
    base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    read(big)
    peak = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - base) * 1024
print(peak / big.stat().st_size)
"""


def _reader_files(folder: Path) -> dict[str, tuple[Path, Path]]:
    """``{reader: (a small file, a big file)}``: the text readers on their shortest lines (the most lines a byte)."""
    out = {}
    for kind, head, row, n in (("plain", "", "1 2 3\n", 3_000_000),
                               ("text", "# magexp-recording v1\n# unit: nT\nbx,by,bz\n", "1,2,3\n", 300_000),
                               ("json", "", "", 1_000_000)):
        for size, count in (("small", 100), ("big", n)):
            path = folder / f"{kind}_{size}.{'json' if kind == 'json' else 'txt'}"
            path.write_text(json.dumps([{}] * count) if kind == "json" else head + row * count)
            out.setdefault(kind, ())
            out[kind] += (path,)
    if SHARED_DATA.is_dir():
        out["ulog"] = (SHARED_DATA / "px4_sample_log_small.ulg", SHARED_DATA / "px4_sample.ulg")
        out["dataflash"] = (SHARED_DATA / "ardupilot_test.bin", SHARED_DATA / "ardupilot_test.bin")
    return out


@pytest.mark.full
def test_each_readers_memory_stays_under_its_stated_multiple(tmp_path):
    """Each reader's peak (the process's resident growth above a small file of its format read first; for the one
    small DataFlash log, Python's traced allocations) over the bytes it read stays under :data:`READ_MEMORY`."""
    measured = {}
    for kind, (small, big) in _reader_files(tmp_path).items():
        done = subprocess.run([sys.executable, "-c", MEASURE, kind, str(small), str(big)], cwd=ROOT,
                              capture_output=True, text=True, timeout=300, env={**os.environ, "PYTHONPATH": str(ROOT)})
        assert done.returncode == 0, done.stderr[-2000:]
        measured[kind] = float(done.stdout.split()[-1])
    assert all(measured[k] < READ_MEMORY[k] for k in measured), measured
    assert np.isfinite(list(measured.values())).all()
