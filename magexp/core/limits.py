"""The work limits: documented, configurable bounds (environment variables) that every command checks
before it starts work (:mod:`magexp.run.budget` estimates a run's and a sweep's work against them; a
recording reader refuses a log of more readings than :data:`LIMITS` allows before decoding it).

Values take ``k/M/G/T`` and ``KiB/MiB/GiB/TiB`` (:func:`parse_amount`); a bad value is one line.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass

from magexp.errors import MagexpError


@dataclass(frozen=True)
class Limit:
    """A documented, configurable bound: ``env`` overrides ``default``."""

    name: str
    env: str
    default: float
    unit: str  # "bytes" or a count's noun
    what: str

    def value(self) -> float:
        """The limit in force: the environment variable, else the default."""
        text = os.environ.get(self.env)
        if text is None:
            return self.default
        value = parse_amount(text)
        if value is None or not value > 0:
            raise MagexpError(f"{self.env}={text!r} is not allowed: give a number > 0, optionally with k, M, G, T "
                              f"or KiB, MiB, GiB, TiB (or unset it for the default, {show(self.default, self.unit)})")
        return value


#: The limits, by name (README "Limits" lists them).
LIMITS = {limit.name: limit for limit in (
    Limit("run_memory", "MAGEXP_MAX_RUN_MEMORY", 8 * 2 ** 30, "bytes",
          "estimated memory of one run or one calibration fit"),
    Limit("run_work", "MAGEXP_MAX_RUN_WORK", 1e11, "reading-evaluations",
          "work of one run or one calibration fit"),
    Limit("runs", "MAGEXP_MAX_RUNS", 200_000, "runs",
          "runs of one command (the jobs of a sweep, the runs of a reproduction)"),
    Limit("work", "MAGEXP_MAX_WORK", 1e13, "reading-evaluations",
          "work of one command (every run of a sweep or reproduction, every fit of a calibration)"),
    Limit("readings", "MAGEXP_MAX_READINGS", 5e7, "readings",
          "readings of a calibrated recording (counted from the file size before it is read)"),
    Limit("file_size", "MAGEXP_MAX_FILE", 2 * 2 ** 30, "bytes",
          "size of a file read (a recording, a calibration, a results file)"),
    Limit("line", "MAGEXP_MAX_LINE", 2 ** 16, "bytes",
          "length of a line of a text file read (a recording, a calibration, a results file)"),
)}

_AMOUNT = re.compile(r"\s*([0-9.eE+-]+)\s*([KMGT]i?B?|[kMG]|B)?\s*")
_FACTORS = {"": 1, "B": 1, "k": 1e3, "K": 1e3, "M": 1e6, "G": 1e9, "T": 1e12,
            "KB": 1e3, "MB": 1e6, "GB": 1e9, "TB": 1e12,
            "KiB": 2 ** 10, "MiB": 2 ** 20, "GiB": 2 ** 30, "TiB": 2 ** 40, "Ki": 2 ** 10, "Mi": 2 ** 20,
            "Gi": 2 ** 30, "Ti": 2 ** 40}


def parse_amount(text: str) -> float | None:
    """``"4GiB"`` -> 4294967296, ``"2e5"`` -> 200000.0, ``"10M"`` -> 1e7; None if not an amount."""
    m = _AMOUNT.fullmatch(str(text))
    if not m:
        return None
    try:
        number = float(m.group(1))
    except ValueError:
        return None
    return number * _FACTORS[m.group(2) or ""] if math.isfinite(number) else None


def show(value: float, unit: str) -> str:
    """``value`` for a message: bytes in KiB..TiB, counts as integers or in ``e`` notation."""
    if unit == "bytes":
        for name, factor in (("TiB", 2 ** 40), ("GiB", 2 ** 30), ("MiB", 2 ** 20), ("KiB", 2 ** 10)):
            if value >= factor:
                return f"{value / factor:.3g} {name}"
        return f"{value:.0f} bytes"
    return f"{value:.0f} {unit}" if value < 1e9 else f"{value:.3g} {unit}"


def limit(name: str) -> float:
    """The value in force of the limit ``name`` (:data:`LIMITS`)."""
    return LIMITS[name].value()


def check_limits() -> None:
    """Refuse, in one line naming the variable, any limit's environment variable that is set to anything but an
    amount > 0 (an empty value included), at the start of every command, whether or not the command consults it.
    """
    for lim in LIMITS.values():
        lim.value()


def refuse_over(value: float, name: str, subject: str, need: str) -> None:
    """Raise ``"<subject> is not allowed: <need> about X, over the limit L (ENV)"`` if ``value``
    exceeds the limit ``name``.
    """
    lim = LIMITS[name]
    bound = lim.value()
    if value > bound:
        raise MagexpError(f"{subject} is not allowed: {need} about {show(value, lim.unit)}, over the limit "
                          f"{show(bound, lim.unit)} ({lim.env}=... raises it)")
