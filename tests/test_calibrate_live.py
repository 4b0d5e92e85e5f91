"""Live calibration (:mod:`magexp.calibration.live`): ``magexp calibrate`` reading a pseudo-terminal with the real
serial reader (pyserial opens the pty's slave as it opens a USB adapter), fed by a thread at a given rate: it
stops by itself with the calibration that the same readings give from a file, shows coverage while it runs and
keeps the stream; a stall, an early end, Ctrl-C and garbage lines give one line each and keep what was read.
"""

from __future__ import annotations

import json
import os
import pty
import re
import signal
import subprocess
import sys
import termios
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from magexp.paths import ROOT, SHARED_DATA

pytest.importorskip("serial", reason="pyserial (magexp[serial]) reads the pseudo-terminal")

needs_data = pytest.mark.skipif(not SHARED_DATA.is_dir(), reason=f"{SHARED_DATA} is not present")
FULL_SPHERE = SHARED_DATA / "hmc5883l_full-sphere_mag.csv"


def synthetic_lines(n: int, seed: int = 0) -> list[str]:
    """``n`` plain ``x y z`` lines (uT) of a distorted sensor turned over the whole sphere."""
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    w_inv = np.array([[1.1, 0.05, 0.0], [0.05, 0.95, 0.02], [0.0, 0.02, 1.03]])
    raw = 50.0 * u @ w_inv.T + np.array([12.0, -7.0, 20.0]) + rng.normal(scale=0.05, size=(n, 3))
    return [f"{x:.4f} {y:.4f} {z:.4f}" for x, y, z in raw]


class Feeder(threading.Thread):
    """Writes ``lines`` into the pty's master at the times ``times`` (seconds from the start), once the
    command's serial reader has opened the slave (pyserial puts it in raw mode, then empties its input)."""

    def __init__(self, master: int, slave: int, lines: list[str], times, *, close: bool = False):
        super().__init__(daemon=True)
        self.master, self.slave, self.lines, self.times, self.close = master, slave, lines, times, close
        self.written = 0

    def run(self):
        deadline = time.monotonic() + 60
        while termios.tcgetattr(self.slave)[3] & termios.ICANON and time.monotonic() < deadline:
            time.sleep(0.01)
        time.sleep(0.2)  # pyserial empties the input after setting the mode
        start = time.monotonic()
        try:
            for k, (line, t) in enumerate(zip(self.lines, self.times)):
                wait = start + t - time.monotonic()
                if wait > 0:
                    time.sleep(wait)
                os.write(self.master, line.encode() + b"\n")
                self.written = k + 1
        except OSError:  # the command closed the port: it stopped
            return
        if self.close:  # the other side hangs up once what it sent has been read (a pty drops unread input)
            time.sleep(1.0)
            os.close(self.master)


def pty_pair():
    """``(master, slave, slave path)``."""
    master, slave = os.openpty()
    return master, slave, os.ttyname(slave)


def printed(text: str, key: str) -> str:
    """The summary's row ``key`` (its value to the printed digits)."""
    return re.search(rf"^{key}\s+(.*)$", text, re.M).group(1)


def test_live_stops_by_itself_with_the_file_calibration(cli, tmp_path):
    """Fast: a small synthetic stream over a pty at 1500 readings/s with garbage lines among them. The command
    stops by itself before the stream's end, said in one line, the garbage in one line; it showed the regions
    and cells as they filled; stream.txt holds the valid lines as sent, and the calibration is the one that
    ``magexp calibrate`` gives on those readings from a file, to the printed digits."""
    lines = synthetic_lines(1500)
    garbage = {40: "MPU init ok", 90: "1.0 2.0", 150: "nan 1 2", 151: "x" * 900}
    fed = list(lines)
    for k in sorted(garbage, reverse=True):
        fed.insert(k, garbage[k])
    master, slave, path = pty_pair()
    feeder = Feeder(master, slave, fed, np.arange(len(fed)) / 1500.0)
    feeder.start()
    out = tmp_path / "live"
    res = cli("calibrate", f"data.serial={path}", "data.unit=uT", f"out={out}", "live.refit_readings=50")
    feeder.join(5)
    os.close(slave)
    assert res.returncode == 0, res.stderr
    stopped = [ln for ln in res.stdout.splitlines() if ln.startswith("stopped after")]
    assert len(stopped) == 1 and "the gate passes with margin 0.5" in stopped[0]
    kept = (out / "stream.txt").read_text().splitlines()
    assert 12 <= len(kept) < len(lines)  # stopped before the stream's end
    assert kept == lines[: len(kept)]  # the valid lines, as sent, in order
    garbage_lines = [ln for ln in res.stdout.splitlines() if "garbage line" in ln]
    assert len(garbage_lines) == 1 and re.match(r"\d+ garbage lines of \d+ skipped", garbage_lines[0])
    assert "(first: line 41 'MPU in" in garbage_lines[0]
    assert re.search(r"regions [0-6]/6: .* \| cells \|.*\| \d+/32 \| held-out", res.stdout)
    file = tmp_path / "same.txt"
    file.write_text("\n".join(kept) + "\n")
    ref = cli("calibrate", f"data.path={file}", "data.unit=uT", f"out={tmp_path / 'file'}")
    assert ref.returncode == 0, ref.stderr
    for key in ("W", "offset", "held-out spread", "spread after", "model"):
        assert printed(res.stdout, key) == printed(ref.stdout, key)
    saved = json.loads((out / "calibration.json").read_text())
    assert saved["config"]["data"]["path"] == str(out / "stream.txt")


def _run_live(args: list[str], cwd: Path, *, stdout=subprocess.PIPE):
    """``python -m magexp calibrate ARGS`` in a process of its own, from ``cwd`` (this checkout imported)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen([sys.executable, "-m", "magexp", "calibrate", *args], cwd=cwd, env=env, stdout=stdout,
                            stderr=subprocess.PIPE, text=stdout is subprocess.PIPE)


def _recording_lines(path: Path) -> tuple[str, list[str], np.ndarray]:
    """The header, the data lines and their times (``t_s``, from 0) of a header-row recording."""
    header, *rows = path.read_text().splitlines()
    times = np.array([float(r.split(",", 1)[0]) for r in rows])
    return header, rows, times - times[0]


@needs_data
@pytest.mark.full
@pytest.mark.parametrize("speed", [1.0, 8.0])
def test_live_real_recording_at_its_rate(tmp_path, speed):
    """The HMC5883L full-sphere recording (header row ``t_s, mx_G, ...``) fed at its own timestamps (speed 1)
    and 8 times faster: the command stops by itself, before the recording ends, with the calibration the same
    readings give from a file (the recording's first lines, to the printed digits); the stream kept is those
    lines; the progress lines show the regions and cells filling."""
    header, rows, times = _recording_lines(FULL_SPHERE)
    master, slave, path = pty_pair()
    feeder = Feeder(master, slave, [header, *rows], np.concatenate([[0.0], times / speed]))
    feeder.start()
    start = time.monotonic()
    proc = _run_live([f"data.serial={path}", "out=live"], tmp_path)
    out, err = proc.communicate(timeout=300)
    took = time.monotonic() - start
    os.close(slave)
    assert proc.returncode == 0, err
    kept = (tmp_path / "live" / "stream.txt").read_text().splitlines()
    assert kept[0] == header and kept[1:] == rows[: len(kept) - 1]
    assert len(kept) - 1 < len(rows)
    assert "the gate passes with margin" in out
    progress = [ln for ln in out.splitlines() if "| cells |" in ln]
    assert len(progress) >= 3 and "regions 6/6" in progress[-1] and "regions 6/6" not in progress[0]
    (tmp_path / "same_mag.csv").write_text("\n".join(kept) + "\n")
    ref = subprocess.run([sys.executable, "-m", "magexp", "calibrate", "data.path=same_mag.csv", "data.format=header-row",
                          "out=file"], cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True,
                         text=True)
    assert ref.returncode == 0, ref.stderr
    for key in ("W", "offset", "held-out spread"):
        assert printed(out, key) == printed(ref.stdout, key)
    print(f"speed {speed}: stopped after {len(kept) - 1} readings, {times[len(kept) - 2]:.1f} s of the recording, "
          f"{took:.1f} s wall; W {printed(out, 'W')[:60]}")


@pytest.mark.full
def test_live_terminal_redraws_in_place(tmp_path):
    """On a terminal the status line is redrawn in place (carriage return, ANSI erase-line), not printed anew."""
    lines = synthetic_lines(1500, seed=1)
    master, slave, path = pty_pair()
    feeder = Feeder(master, slave, lines, np.arange(len(lines)) / 200.0)
    feeder.start()
    screen_master, screen_slave = os.openpty()
    proc = _run_live([f"data.serial={path}", "data.unit=uT", "out=live", "live.refit_readings=20"], tmp_path,
                     stdout=screen_slave)
    os.close(screen_slave)
    shown = b""
    while True:
        try:
            chunk = os.read(screen_master, 4096)
        except OSError:
            break
        if not chunk:
            break
        shown += chunk
    assert proc.wait(timeout=60) == 0
    os.close(slave)
    text = shown.decode()
    assert text.count("\r\x1b[K") >= 2 and "| cells |" in text
    assert (tmp_path / "live" / "calibration.json").is_file()


def _fault(tmp_path, lines, args, *, close=False, interrupt_after=None):
    """Run the command on a pty fed ``lines`` at 500/s; ``close``: end the stream after them; ``interrupt_after``:
    send Ctrl-C (SIGINT) that many seconds after the start. Its ``(exit code, stdout, stderr)``."""
    master, slave, path = pty_pair()
    feeder = Feeder(master, slave, lines, np.arange(len(lines)) / 500.0, close=close)
    feeder.start()
    proc = _run_live([f"data.serial={path}", "data.unit=uT", "out=live", *args], tmp_path)
    if interrupt_after is not None:
        time.sleep(interrupt_after)
        proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    os.close(slave)
    if not close:
        os.close(master)
    return proc.returncode, out, err


@pytest.mark.full
@pytest.mark.parametrize("fault", ["stall", "end", "interrupt"])
def test_live_faults_keep_what_was_read(tmp_path, fault):
    """A stream that stalls, ends early, or is stopped by Ctrl-C: one line says so, the stream read is kept, and
    the gate decides on it (accepted: the files written; refused: one line naming the kept stream, exit 2)."""
    few = synthetic_lines(60, seed=2)  # too few for the stop rule: it waits for more
    if fault == "stall":
        code, out, err = _fault(tmp_path, few, ["live.stall_seconds=1"])
        assert "no valid reading for 1 s (live.stall_seconds)" in out
    elif fault == "end":
        code, out, err = _fault(tmp_path, few, [], close=True)
        assert "the stream ended" in out
    else:
        code, out, err = _fault(tmp_path, few, ["live.stall_seconds=100"], interrupt_after=4)
        assert "Ctrl-C: the gate decides on what was read" in out
    assert len([ln for ln in out.splitlines() if ln.startswith("stopped after")]) == 1
    kept = (tmp_path / "live" / "stream.txt").read_text().splitlines()
    assert kept == few[: len(kept)] and len(kept) > 12
    if code == 0:
        assert (tmp_path / "live" / "calibration.json").is_file()
    else:
        assert code == 2 and len(err.strip().splitlines()) == 1 and "stream read is kept in live/stream.txt" in err


@pytest.mark.full
def test_live_nothing_valid_is_refused(tmp_path):
    """Only garbage, then the end: one line, exit 2, nothing written (no output folder)."""
    code, out, err = _fault(tmp_path, ["hello", "1 2", "a b c"], [], close=True)
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "no valid reading arrived (the stream ended)" in err and "3 garbage lines" in err
    assert not (tmp_path / "live").exists()


@pytest.mark.full
def test_live_standard_input(tmp_path):
    """``data.path=-`` reads standard input: the FXOS8700 recording piped in calibrates as from the file."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"{SHARED_DATA} is not present")
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    data = (SHARED_DATA / "fxos8700_mag_readings.txt").read_text()
    live = subprocess.run([sys.executable, "-m", "magexp", "calibrate", "data.path=-", "data.unit=uT", "out=live"],
                          cwd=tmp_path, env=env, input=data, capture_output=True, text=True)
    assert live.returncode == 0, live.stderr
    kept = (tmp_path / "live" / "stream.txt").read_text().splitlines()
    (tmp_path / "same.txt").write_text("\n".join(kept) + "\n")
    ref = subprocess.run([sys.executable, "-m", "magexp", "calibrate", "data.path=same.txt", "data.unit=uT", "out=file"],
                         cwd=tmp_path, env=env, capture_output=True, text=True)
    assert printed(live.stdout, "W") == printed(ref.stdout, "W")
    assert printed(live.stdout, "offset") == printed(ref.stdout, "offset")
