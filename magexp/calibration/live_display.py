"""What ``magexp calibrate`` shows while it reads a live stream (:mod:`magexp.calibration.live`): one status line
per live check (:class:`Progress`), in the style of a progress bar (``tqdm``'s): the readings and their rate,
how many readings each of the six regions of directions holds (each named by the sensor axis nearest its
half-axis, :func:`magexp.core.identifiability.direction_regions`), the sphere cells reached
(:func:`magexp.core.identifiability.coverage`) as a bar, the held-out spread beside the raw one, the
worst heading error expected on unseen directions (held out, level), and what
the stop rule still waits for. On a terminal the line is redrawn in place (a carriage return and an ANSI
erase-line); elsewhere (a pipe, a log file) each check prints a line of its own.
"""

from __future__ import annotations

import shutil
import sys
from dataclasses import dataclass, field

import numpy as np

from magexp.core.identifiability import CELLS

#: characters of the coverage bar
BAR = 12
_BLOCKS = " ▏▎▍▌▋▊▉█"


@dataclass
class Progress:
    """One live check: what the display shows.

    Attributes
    ----------
    readings : readings kept so far.
    seconds : seconds since the first byte.
    regions : readings in each of the six regions of directions (of those checked).
    names : each region's nearest sensor axis (``+x``, ``-z``...).
    cells : sphere cells (of :data:`~magexp.core.identifiability.CELLS`) the directions reach.
    heldout, raw : the held-out and the raw spread (std / mean of ``|B|``), NaN when not measured.
    heading : the worst level heading error the calibration so far leaves on directions it was not fitted to
        (held out, degrees: :func:`magexp.calibration.heading.worst_left`), NaN when not measured.
    passed : the stop rule passed.
    waiting : what the stop rule still waits for (empty when passed).
    """

    readings: int
    seconds: float
    regions: list = field(default_factory=lambda: [0] * 6)
    names: list = field(default_factory=lambda: ["?"] * 6)
    cells: int = 0
    heldout: float = float("nan")
    raw: float = float("nan")
    heading: float = float("nan")
    passed: bool = False
    waiting: str = ""


def axis_names(axes: np.ndarray) -> list[str]:
    """The sensor axis nearest each half-axis of ``axes`` (``(6, 3)``): ``+x``, ``-z``..."""
    axes = np.asarray(axes, float)
    k = np.argmax(np.abs(axes), axis=1)
    sign = np.where(axes[np.arange(len(axes)), k] > 0, "+", "-")
    return [f"{s}{'xyz'[j]}" for s, j in zip(sign, k)]


def bar(fraction: float, width: int = BAR) -> str:
    """A progress bar of ``width`` characters, eighths of a block resolved."""
    eighths = int(round(min(max(fraction, 0.0), 1.0) * width * 8))
    full, part = divmod(eighths, 8)
    return ("█" * full + (_BLOCKS[part] if part else "")).ljust(width)


def _percent(value: float) -> str:
    """``1.23 %``, or ``-`` when not measured."""
    return f"{100 * value:.3g} %" if np.isfinite(value) else "-"


def status(p: Progress) -> str:
    """The status line of ``p`` (module docstring)."""
    rate = f"{p.readings / p.seconds:.0f}/s" if p.seconds >= 1 else "-/s"
    regions = " ".join(f"{n} {c}" for n, c in zip(p.names, p.regions))
    reached = sum(c > 0 for c in p.regions)
    state = "gate passes" if p.passed else f"waiting: {p.waiting}"
    heading = f"{p.heading:.2g}°" if np.isfinite(p.heading) else "-"
    return (f"{p.readings} readings {rate} {p.seconds:.0f} s | regions {reached}/6: {regions} | "
            f"cells |{bar(p.cells / CELLS)}| {p.cells}/{CELLS} | held-out {_percent(p.heldout)} "
            f"(raw {_percent(p.raw)}) | heading ±{heading} | {state}")


class Display:
    """Shows :class:`Progress` (module docstring) on ``out``."""

    def __init__(self, out=None):
        self.out = sys.stdout if out is None else out
        self.tty = bool(getattr(self.out, "isatty", lambda: False)())
        self.drawn = False

    def show(self, progress: Progress) -> None:
        """Draw ``progress``: in place on a terminal, else a line of its own."""
        line = status(progress)
        if self.tty:
            width = shutil.get_terminal_size((120, 24)).columns
            self.out.write("\r\x1b[K" + line[: max(width - 1, 20)])
            self.drawn = True
        else:
            self.out.write(line + "\n")
        self.out.flush()

    def say(self, line: str) -> None:
        """A line of its own below the status line (which stays, as a finished bar does)."""
        if self.drawn:
            self.out.write("\n")
            self.drawn = False
        self.out.write(line + "\n")
        self.out.flush()
