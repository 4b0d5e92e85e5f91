"""Numbers and texts held to a tolerance, as :mod:`magexp.artifacts.compare` holds a reproduction to the
committed results: a number within :data:`RTOL` relative or one unit of its printed precision
(:func:`tolerance`), a text word for word with its numbers held to the same (:func:`compare_text`).
"""

from __future__ import annotations

import math
import re

import numpy as np

from magexp.artifacts.formats import DIGITS
from magexp.core.outcomes import ROUNDOFF_FLOOR


#: relative tolerance of a number. A reproduction elsewhere (another CPU, BLAS or numba target, the numpy
#: path) sums in another order: most numbers move in their 6th significant digit (1e-6 to 1e-5
#: relative, the precision of the CSVs), but a difference of two nearly equal numbers magnifies the
#: round-off of its operands by their ratio. Measured against the committed results: a Kalman estimate's
#: distance from least squares (``yan2022_fig_tuning`` ``k_vs_ls``, 4e-9) moved by 3.9e-4 relative, a
#: calibrated field's error ``|B_cal| - |B_ref|`` (0.003 nT of 50 000 nT, ``ding2024_fig2``) by 4.4e-4.
#: 1e-3 covers those twice over and is at most one unit of the 4th significant digit, the precision
#: REPORT.md prints: a difference it allows can show there only as a flip of a last digit, and never
#: moves a verdict (verdicts are compared exactly).
RTOL = 1e-3
#: a number in a text: not inside a word (``exp1``, ``S11``, ``ding2024``), an optional sign, an exponent
NUMBER = re.compile(r"((?<![\w.])[-+]?(?>\d+(?:\.\d*)?|\.\d+)(?>[eE][-+]?\d+)?(?!\w))")


def tolerance(ours: np.ndarray, committed: np.ndarray, unit: np.ndarray, rtol: float) -> np.ndarray:
    """The largest difference allowed between ``ours`` and ``committed``: ``rtol`` times the larger
    magnitude, or one ``unit`` of the printed precision, whichever is larger.
    """
    return np.maximum(rtol * np.maximum(np.abs(ours), np.abs(committed)), unit)


def csv_unit(values: np.ndarray) -> np.ndarray:
    """One unit of the last digit of floats written with :data:`magexp.artifacts.formats.DIGITS`
    significant digits (``%.6g``: trailing zeros dropped, so the text itself does not tell). Round-off
    is written as ``0`` or ``±ROUNDOFF_FLOOR`` (:func:`magexp.artifacts.formats.tidy`): a value of at most
    that magnitude is printed to within the band ``-floor .. floor``, whose width is its unit.
    """
    mag = np.abs(values)
    with np.errstate(divide="ignore"):
        digit = np.where(mag > 0, 10.0 ** (np.floor(np.log10(np.where(mag > 0, mag, 1))) - (DIGITS - 1)), 0.0)
    return np.where(mag <= ROUNDOFF_FLOOR, 2 * ROUNDOFF_FLOOR, digit)


def text_unit(token: str) -> float:
    """One unit of the last printed digit of a number in a text (``0.254`` -> 0.001, ``1.2e-05`` ->
    1e-06, ``30`` -> 1).
    """
    mantissa, _, exponent = token.lower().partition("e")
    decimals = len(mantissa.partition(".")[2])
    return 10.0 ** (int(exponent or 0) - decimals)


def relative(a: float, b: float) -> float:
    """``|a - b|`` over the larger magnitude (0 when both are 0)."""
    scale = max(abs(a), abs(b))
    return abs(a - b) / scale if scale else 0.0


def compare_text(ours: str, committed: str, rtol: float) -> tuple[bool, float, tuple[str, str]]:
    """Whether two texts agree: the same words, and each number within :func:`tolerance` (its unit
    the finer of the two printed precisions: ``1.5`` beside ``1.501`` is one unit of ``0.001``).
    Returns ``(agrees, largest relative difference of a number, (ours, committed) of the first
    disagreement or of the largest difference)``.
    """
    a, b = NUMBER.split(ours), NUMBER.split(committed)
    if len(a) != len(b) or a[0::2] != b[0::2]:
        return False, math.nan, _first_difference(ours, committed)
    worst, where = 0.0, (ours, committed)
    for x, y in zip(a[1::2], b[1::2]):
        if x == y:
            continue
        fx, fy = float(x), float(y)
        unit = min(text_unit(x), text_unit(y))
        if abs(fx - fy) > tolerance(np.float64(fx), np.float64(fy), unit, rtol) * (1 + 1e-9):
            return False, math.nan, (x, y)
        if relative(fx, fy) >= worst:
            worst, where = relative(fx, fy), (x, y)
    return True, worst, where


def _first_difference(a: str, b: str, context: int = 25) -> tuple[str, str]:
    """The two texts around their first differing character."""
    i = next((k for k, (x, y) in enumerate(zip(a, b)) if x != y), min(len(a), len(b)))
    start = max(0, i - context)
    return a[start:i + context], b[start:i + context]
