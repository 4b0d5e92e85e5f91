"""Progress of long sweeps: runs done / total, elapsed, estimate — on a terminal only."""

from __future__ import annotations

import os
import sys
import time


class Progress:
    """A one-line progress display, silent when stderr is not a terminal or ``CI`` is set.

    Call the instance with the number of runs just finished.

    Parameters
    ----------
    total : int
        The number of runs.
    label : str
        Printed before the counts.
    stream : file, optional
        Where to write (default: stderr).
    enabled : bool, optional
        Force the display on or off (default: on a terminal outside CI).
    """

    def __init__(self, total: int, label: str = "", stream=None, enabled: bool | None = None):
        self.total, self.label, self.done = total, label, 0
        self.stream = stream or sys.stderr
        self.start = time.perf_counter()
        if enabled is None:
            enabled = self.stream.isatty() and not os.environ.get("CI")
        self.enabled = enabled and total > 0

    def text(self) -> str:
        """The line shown: label, runs done of the total, seconds elapsed and left."""
        elapsed = time.perf_counter() - self.start
        left = elapsed / self.done * (self.total - self.done) if self.done else float("nan")
        eta = f", ~{left:.0f} s left" if self.done else ""
        return f"{self.label} {self.done}/{self.total} runs, {elapsed:.0f} s elapsed{eta}"

    def __call__(self, n: int = 1) -> None:
        """Count ``n`` more finished runs and redraw the line."""
        self.done += n
        if self.enabled:
            end = "\n" if self.done >= self.total else ""
            self.stream.write("\r" + self.text().ljust(70) + end)
            self.stream.flush()
