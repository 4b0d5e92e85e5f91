"""Live calibration: ``magexp calibrate`` reading a stream (a serial port, ``data.serial=/dev/ttyUSB0
data.baud=115200``, or standard input, ``data.path=-``) while the sensor is turned, showing the coverage as it
grows, and stopping by itself once the readings calibrate well (:func:`read_live`).

Flow::

    source (magexp.calibration.live_stream) ──► lines ──► stream.txt in the output folder (kept lines only)
        every live.refit_readings new readings or live.refit_seconds: the live check (:func:`live_check`)
        ──► the display (magexp.calibration.live_display) ──► stop?
    stop ──► magexp calibrate data.path=<out>/stream.txt (magexp.calibration.command.run): the same outputs

**The live check** reads ``stream.txt`` back with the file readers (:func:`magexp.core.recordings.load_recording`,
the same ``data.*`` options), takes at most ``live.check_readings`` of its readings evenly spaced in time order
(bounded work whatever the stream's length), and runs the pipeline of a calibration from a file
(:func:`magexp.calibration.fit.calibrate_recording`) with the closed-form ellipsoid (``estimator=ellipsoid``;
``model=sphere`` or ``diagonal`` when the command asks for one, else ``full``), the held-out check and the
acceptance gate (:func:`magexp.calibration.checks.gate`) with its limits tightened by ``live.margin`` ``m``
(:func:`stop_thresholds`): the held-out spread below ``(1 - m) · gate.heldout_vs_raw`` times the raw spread
(the check that more directions improve; the others as the gate has them); and every one of the six regions of
directions must hold at least :data:`~magexp.calibration.checks.MIN_READINGS` readings, so that each was held out
(none untested).

**The stop**: the live check passes; or Ctrl-C (SIGINT while reading: the reading stops and the gate decides on
what was read); or the stream ends (end of file, the port gone); or no valid reading for ``live.stall_seconds``;
or ``live.max_readings`` lines. Each is said in one line, and so is the garbage (:mod:`magexp.calibration.live_stream`).
Then the stream kept, ``<out>/stream.txt``, is calibrated as a file is, with every option of the command: the
same calibration as ``magexp calibrate data.path=<out>/stream.txt``, and the same files
(:func:`magexp.calibration.write.write`). A refusal then says that the stream is kept.
"""

from __future__ import annotations

import re
import shutil
import signal
import threading
import time
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from omegaconf import OmegaConf, open_dict

from magexp.calibration.checks import gate_thresholds
from magexp.calibration.export import TARGETS as EXPORT_TARGETS
from magexp.calibration.heading import worst_left
from magexp.calibration.checks import MIN_READINGS
from magexp.calibration.live_display import Display, Progress, axis_names
from magexp.calibration.live_stream import POLL, LineCutter, StreamFile, open_source
from magexp.calibration.write import check_out
from magexp.problems.kernels import numpy_only
from magexp.run.folders import check_destination, first_missing
from magexp.core.ellipsoid import fit_sphere
from magexp.core.identifiability import CELLS, coverage, direction_regions, spread
from magexp.core.recording import evenly_spaced
from magexp.core.recordings import load_recording
from magexp.errors import MagexpError, check_magnitude, check_nonnegative, check_positive_int

from magexp.run.named import estimator_named

#: the stream file in the output folder
STREAM = "stream.txt"
#: a live check starts no sooner than this many times the last one's duration after its end (at most a fifth of
#: the time in checks, whatever the stream's rate; the first check, which imports the readers, excepted)
SHARE = 4
#: the models a live check fits as asked; any other is checked as ``full``
CLOSED = ("sphere", "diagonal")


@dataclass
class Settings:
    """``live.*``, checked (:func:`settings`; their sentences: :class:`magexp.calibration.options.LiveOptions`)."""

    margin: float
    refit_readings: int
    refit_seconds: float
    check_readings: int
    stall_seconds: float
    max_readings: int
    max_line: int


def is_live(cfg) -> bool:
    """Whether the command reads a live stream: ``data.serial`` given, or ``data.path=-``."""
    return cfg.data.get("serial") is not None or str(cfg.data.get("path")).strip() == "-"


def _seconds(value, key: str) -> float:
    """A number of seconds > 0 and < 1e6, else one line."""
    seconds = check_nonnegative(value, f"live.{key}")
    if not 0 < seconds < 1e6:
        raise MagexpError(f"live.{key}={value!r} is not allowed: give a number of seconds > 0 and < 1e6")
    return seconds


def settings(cfg) -> Settings:
    """``live.*`` and ``data.baud`` of ``cfg``, each checked; ``data.serial`` with ``data.path`` refused."""
    live, data = cfg.live, cfg.data
    if data.get("serial") is not None and data.get("path") is not None:
        raise MagexpError(f"data.path={data.path!r} is not allowed with data.serial={data.serial!r}: give one source")
    if data.get("serial") is not None and not str(data.serial).strip():
        raise MagexpError(f"data.serial={data.serial!r} is not allowed: give the port's device path (e.g. /dev/ttyUSB0)")
    check_positive_int(data.baud, "data.baud")
    margin = check_nonnegative(live.margin, "live.margin")
    if not margin < 1:
        raise MagexpError(f"live.margin={live.margin!r} is not allowed: give a fraction, 0 <= margin < 1")
    return Settings(margin=margin, refit_readings=check_positive_int(live.refit_readings, "live.refit_readings"),
                    refit_seconds=_seconds(live.refit_seconds, "refit_seconds"),
                    check_readings=check_positive_int(live.check_readings, "live.check_readings", minimum=MIN_READINGS * 6),
                    stall_seconds=_seconds(live.stall_seconds, "stall_seconds"),
                    max_readings=check_positive_int(live.max_readings, "live.max_readings"),
                    max_line=check_positive_int(live.max_line, "live.max_line", minimum=16))


def stop_thresholds(gate_overrides, margin: float) -> dict:
    """The gate's thresholds (:func:`magexp.calibration.checks.gate_thresholds` of ``gate.*``) with the held-out
    limit times ``1 - margin``: what the live check passes (module docstring)."""
    t = gate_thresholds(gate_overrides)
    return {**t, "heldout_vs_raw": t["heldout_vs_raw"] * (1 - margin)}


def live_check(rec, calibrate, *, estimator, model: str, thresholds: dict, limit: int, seconds: float,
               reference=None) -> Progress:
    """The live check of the readings so far (module docstring): coverage, held-out spread, the stop rule."""
    sub = rec.subset(evenly_spaced(rec.n, limit))
    centred = sub.readings - fit_sphere(sub.readings)[0]  # about the sphere's centre, as the held-out check cuts them
    labels, axes = direction_regions(centred)
    counts = np.bincount(labels, minlength=6)
    progress = Progress(readings=rec.n, seconds=seconds, regions=counts.tolist(), names=axis_names(axes),
                        cells=round(coverage(centred)["coverage_cells"] * CELLS),
                        raw=spread(np.linalg.norm(sub.readings, axis=1)))
    try:
        with numpy_only(True):  # a closed form: numpy's residuals, not the compiled kernels' load
            cal = calibrate(sub, estimator, reference_total=reference, folds=6, rng=None, model=model, accept=True,
                            gate_overrides=thresholds)
    except MagexpError as exc:
        progress.waiting = _short(str(exc))
        return progress
    progress.heldout, progress.raw = cal.metrics.get("heldout_spread", float("nan")), cal.metrics["spread_before"]
    left = worst_left(cal.report.get("heading"))
    progress.heading = float("nan") if left is None else left
    short = [axis for axis, c in zip(progress.names, counts) if c < MIN_READINGS]
    failed = [f["check"] for f in cal.report["gate"]["failed"]]
    progress.waiting = "; ".join(([f"{MIN_READINGS} readings toward {', '.join(short)}"] if short else [])
                                 + ([f"gate ({', '.join(failed)})"] if failed else []))
    progress.passed = not progress.waiting
    return progress


def _short(text: str) -> str:
    """A refusal's reason without the recording's name, up to its first parenthesis or colon (the status line's width)."""
    reason = text.split(": ", 1)[-1]
    return re.split(r" \(|: ", reason, maxsplit=1)[0]


@contextmanager
def _sigint_stops():
    """While reading: Ctrl-C (SIGINT) stops the reading instead of the command (the list it yields fills)."""
    seen: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield seen
        return
    previous = signal.signal(signal.SIGINT, lambda signum, frame: seen.append(signum))
    try:
        yield seen
    finally:
        signal.signal(signal.SIGINT, previous)


class Reader:
    """One live read (:func:`read_live`): the source, the stream file, the checks and the stop."""

    def __init__(self, cfg, out_dir: Path, display: Display, calibrate):
        self.cfg, self.s, self.display, self.calibrate = cfg, settings(cfg), display, calibrate
        model = str(cfg.get("model"))
        self.model = model if model in CLOSED else "full"
        self.thresholds = stop_thresholds(cfg.get("gate"), self.s.margin)
        self.estimator = estimator_named("ellipsoid")
        self.stream = StreamFile(out_dir / STREAM)
        self.cutter = LineCutter(self.s.max_line)
        self.start = self.last_data = self.last_check = time.monotonic()
        self.checked, self.took, self.progress_shown = 0, 0.0, False
        self.progress: Progress | None = None

    def step(self, data: bytes | None) -> str | None:
        """Take ``data`` (None: the stream ended); the reason to stop, or None."""
        now = time.monotonic()
        if data is None:
            self.stream.add(self.cutter.flush())
            return "the stream ended"
        if data and self.stream.add(self.cutter.feed(data)):
            self.last_data = now
        if self.stream.lines >= self.s.max_readings:
            return f"live.max_readings={self.s.max_readings} lines read"
        if now - self.last_data > self.s.stall_seconds:
            return f"no valid reading for {self.s.stall_seconds:g} s (live.stall_seconds)"
        due = self.stream.rows - self.checked >= self.s.refit_readings or (
            now - self.last_check >= self.s.refit_seconds and self.stream.rows > self.checked)
        if due and self.stream.rows >= MIN_READINGS and now - self.last_check >= SHARE * self.took:
            return self._check(now)
        return None

    def _check(self, now: float) -> str | None:
        """Run the live check on the stream so far and show it; the reason to stop when it passes."""
        self.checked = self.stream.rows
        data = self.cfg.data
        rec = load_recording(self.stream.path, unit=data.get("unit"), format=data.get("format") or "auto",
                             mag_axes=data.get("mag_axes"), gyro_axes=data.get("gyro_axes"))
        self.progress = live_check(rec, self.calibrate, estimator=self.estimator, model=self.model, thresholds=self.thresholds,
                                   limit=self.s.check_readings, seconds=now - self.start,
                                   reference=data.get("reference_total"))
        self.last_check = time.monotonic()
        self.took = self.last_check - now if self.progress_shown else 0.0  # the first one imports the readers
        self.progress_shown = True
        self.display.show(self.progress)
        if self.progress.passed:
            return (f"the gate passes with margin {self.s.margin:g} (held-out spread "
                    f"{100 * self.progress.heldout:.3g} %, raw {100 * self.progress.raw:.3g} %, every region held out)")
        return None

    def run(self, source) -> str:
        """Read ``source`` until a stop (module docstring); the reason."""
        with _sigint_stops() as stopped:
            while True:
                reason = "Ctrl-C: the gate decides on what was read" if stopped else self.step(source.read(POLL))
                if reason:
                    return reason


def out_folder(cfg) -> Path:
    """The output folder of a live read, checked before anything is read: ``out`` (default
    ``calibration_<port name>`` or ``calibration_stdin``), which must not hold a calibration's files nor a
    ``stream.txt`` (unless ``overwrite=true``)."""
    out = cfg.get("out")
    serial = cfg.data.get("serial")
    default = f"calibration_{Path(str(serial)).name}" if serial is not None else "calibration_stdin"
    out_dir = Path(default if out is None else str(out))
    check_destination(out_dir, "out")
    overwrite = cfg.get("overwrite") is True
    export = cfg.get("export")
    check_out(out_dir, overwrite=overwrite, export=export if export in EXPORT_TARGETS else None)
    if (out_dir / STREAM).exists() and not overwrite:
        raise MagexpError(f"out={str(out_dir)!r} is not allowed: it already holds {STREAM} (never overwritten unless "
                          "overwrite=true), choose another folder")
    return out_dir


def read_live(cfg, calibrate, display: Display | None = None):
    """Read the live stream ``cfg`` names into ``<out>/stream.txt`` until a stop (module docstring), saying why in
    one line (and the garbage in one more); return the config that calibrates the stream kept
    (``data.path=<out>/stream.txt``, its format, ``out``)."""
    display = Display() if display is None else display
    settings(cfg)
    reference = cfg.data.get("reference_total")  # checked now, not once the stream is read (the live check uses it)
    if reference is not None and not check_magnitude(reference, "data.reference_total") > 0:
        raise MagexpError(f"data.reference_total={reference!r} is not allowed: it must be a number > 0")
    out_dir = out_folder(cfg)
    replacing = (out_dir / STREAM).exists()  # only with overwrite=true (out_folder)
    source = open_source(cfg.data)  # before anything is made: a port that cannot be opened leaves nothing behind
    created = first_missing(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    reader = Reader(cfg, out_dir, display, calibrate)
    display.say(f"reading {source.name} into {out_dir / STREAM}"
                + (" (replacing the earlier one: overwrite=true)" if replacing else "")
                + " (Ctrl-C stops; the gate then decides)")
    try:
        with kept(reader.stream.path):
            reason = reader.run(source)
    finally:
        source.close()
        reader.stream.close()
    stream = reader.stream
    if stream.rows == 0:
        stream.path.unlink(missing_ok=True)
        if created is not None:
            shutil.rmtree(created, ignore_errors=True)
        raise MagexpError(f"{source.name}: no valid reading arrived ({reason}), nothing written"
                          + (f"; {stream.garbage_line()}" if stream.garbage else ""))
    display.say(f"stopped after {stream.rows} data rows in {time.monotonic() - reader.start:.1f} s: {reason}")
    if stream.garbage:
        display.say(stream.garbage_line())
    final = OmegaConf.create(OmegaConf.to_container(cfg, resolve=True))
    with open_dict(final):
        final.data.path, final.data.serial, final.out = str(stream.path), None, str(out_dir)
        final.data.format = stream.format if (cfg.data.get("format") or "auto") == "auto" else cfg.data.format
    return final


@contextmanager
def kept(path: Path):
    """A :class:`MagexpError` raised inside says, in its one line, that the stream read is kept in ``path``."""
    try:
        yield
    except MagexpError as exc:
        if not Path(path).is_file():
            raise
        raise MagexpError(f"{str(exc).splitlines()[0]} (the stream read is kept in {path}: "
                          f"magexp calibrate data.path={path} reads it again)") from None
