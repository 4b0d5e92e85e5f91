"""The schema of ``calibration.json`` (what :meth:`Calibration.save <magexp.calibration.result.Calibration.save>`
and ``magexp calibrate`` write), and the bounded reading that :meth:`Calibration.load
<magexp.calibration.result.Calibration.load>` checks every key of before it builds anything.

Reading a file (:func:`read_json`) is bounded before it starts: the file gate (:func:`magexp.run.files.check_file`:
a regular file, its size, its lines and the memory its parse takes within the limits), then nesting at most
:data:`MAX_DEPTH` deep and each number at most :data:`MAX_DIGITS` characters long.

Every key is then checked (:func:`check_parameters`): the format, the model, the units (those of
:data:`magexp.core.recording.UNITS`), the names (non-empty, one line), the counts (integers in range), ``W``
(3 x 3 finite numbers of magnitude <= :data:`magexp.errors.LARGEST`, invertible, its condition number at most
:data:`MAX_CONDITION`), the offset (3 such numbers), the reference (a finite total > 0), the search box, the
metrics and quality records the summary reads, the fit's outcome, and no key the format does not have.
Every refusal is one :class:`~magexp.errors.MagexpError` line naming the file, the key and what is allowed.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from magexp.calibration.models import ORDER
from magexp.core.recording import RAW_UNITS, UNITS, check_unit
from magexp.errors import LARGEST, MagexpError
from magexp.run.keys import MAX_SEED
from magexp.run.files import check_file

#: the deepest nesting of lists and objects a ``calibration.json`` may have (the format nests four deep)
MAX_DEPTH = 64
#: the most characters of one JSON number (a float64 needs 24)
MAX_DIGITS = 64
#: the largest condition number of ``W`` (ratio of its largest to smallest singular value) a calibration may
#: have: a magnetometer's axes differ in gain by a few times, never by a million
MAX_CONDITION = 1e6
#: the longest name or path (``recording``, ``estimator``...) a calibration holds
MAX_TEXT = 4096
#: the format's keys: those of every readable format, and those ``v3`` added (optional in ``v2``)
KEYS = ("format", "model", "recording", "n_readings", "unit", "estimator", "objective", "seed", "W", "W_form",
        "offset", "reference", "search", "metrics", "quality", "fit")
V3_KEYS = ("field_unit", "config", "provenance")
#: optional in every format: the manifest of the folder's other files (:data:`magexp.calibration.folder.MANIFEST`)
OPTIONAL = ("files",)
#: the metrics the summary reads, each a finite number >= 0
METRICS = ("mean_before", "spread_before", "rms_before", "mean_after", "spread_after", "rms_after",
           "coverage_cells", "coverage_lambda_min")
#: the objectives a calibration records: the two a user chooses, and ``gyro`` (``model=gyro``'s own)
OBJECTIVES = ("scalar", "vector", "gyro")
#: the formats magexp reads (the newest is the one it writes)
FORMATS = ("magexp-calibration v2", "magexp-calibration v3")
MODEL = "B = W (reading - offset)"


class Bad(Exception):
    """A value that breaks the schema: ``str`` of it says what is allowed (made into one line by :func:`_check`)."""


def _shown(value) -> str:
    """``value`` for a message: its ``repr``, at most 40 characters."""
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _number(text: str):
    """A JSON number's token as a Python number, refusing one longer than :data:`MAX_DIGITS` characters."""
    if len(text) > MAX_DIGITS:
        raise Bad(f"a number of {len(text)} characters; at most {MAX_DIGITS}")
    return float(text) if any(c in text for c in ".eE") else int(text)


def _depth(text: str) -> int:
    """The deepest nesting of ``[`` and ``{`` in the JSON ``text`` (brackets inside strings not counted)."""
    raw = np.frombuffer(text.encode("utf-8", "surrogatepass"), np.uint8)
    quote = raw == ord('"')
    escaped = np.zeros_like(quote)
    backslash = np.flatnonzero(raw == ord("\\"))
    if backslash.size:  # a quote after an odd run of backslashes is inside the string
        escaped = _escaped(raw, backslash)
    inside = np.cumsum(quote & ~escaped) % 2 == 1
    step = (np.isin(raw, (ord("["), ord("{"))).astype(np.int64) - np.isin(raw, (ord("]"), ord("}"))))
    step[inside] = 0
    return int(np.cumsum(step).max(initial=0))


def _escaped(raw: np.ndarray, backslash: np.ndarray) -> np.ndarray:
    """Which bytes of ``raw`` follow an odd run of backslashes (``backslash``: their positions)."""
    escaped = np.zeros(raw.size, bool)
    run_start = np.r_[True, np.diff(backslash) != 1]
    starts = backslash[run_start]
    lengths = np.diff(np.r_[np.flatnonzero(run_start), backslash.size])
    ends = starts + lengths
    odd = (lengths % 2 == 1) & (ends < raw.size)
    escaped[ends[odd]] = True
    return escaped


def read_json(path, what: str = "path"):
    """The content of the JSON file ``path``, read within bounds (module docstring): one line refusing a special
    file, one that does not exist or is a folder, one too large, too deep, with a number too long, or not JSON."""
    if not isinstance(path, (str, Path)) or not str(path).strip():
        raise MagexpError(f"{what}={_shown(path)} is not allowed: give the path of a calibration.json")
    path = Path(path)
    check_file(path, what, kind="json")  # the file gate: no device or FIFO, its size, lines and parse memory bounded
    if not path.is_file():
        raise MagexpError(f"{what}={str(path)!r} is not allowed: it does not exist; give a calibration.json")
    try:
        text = path.read_text(encoding="utf-8")
        if _depth(text) > MAX_DEPTH:
            raise Bad(f"nested deeper than {MAX_DEPTH}")
        return json.loads(text, parse_int=_number, parse_float=_number)
    except (UnicodeDecodeError, json.JSONDecodeError, Bad, RecursionError) as exc:
        why = exc if isinstance(exc, Bad) else type(exc).__name__
        raise MagexpError(f"{path.name}: not a calibration.json ({why}): give a file written by magexp calibrate "
                          "or Calibration.save") from None


# ---------------------------------------------------------------------------------------------
# the checks of one value: each returns nothing or raises Bad saying what is allowed

def _is_number(value) -> bool:
    """Whether ``value`` is a JSON number (not a bool)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _positive(value) -> None:
    """A check of a finite number > 0 of magnitude <= :data:`LARGEST`."""
    if not _is_number(value) or not 0 < value <= LARGEST:
        raise Bad(f"a finite number > 0 and <= {LARGEST:g}")


def ranged(lo: float, hi: float, *, whole: bool = False):
    """A check of a number in ``[lo, hi]`` (not a bool; ``whole``: an integer, not a float)."""
    kind = (int,) if whole else (int, float)

    def check(value):
        if not isinstance(value, kind) or isinstance(value, bool) or not lo <= value <= hi:
            raise Bad(f"an integer in [{lo}, {hi}]" if whole else f"a finite number in [{lo:g}, {hi:g}]")
    return check


def text(empty: bool = False):
    """A check of a one-line string of at most :data:`MAX_TEXT` characters (``empty``: it may be ``""``)."""
    def check(value):
        if not isinstance(value, str) or len(value) > MAX_TEXT or "\n" in value or not (empty or value.strip()):
            raise Bad(f"a {'' if empty else 'non-empty '}one-line string of at most {MAX_TEXT} characters")
    return check


def choice(options):
    """A check of one of ``options``."""
    options = tuple(options)

    def check(value):
        if not isinstance(value, str) or value not in options:
            raise Bad(f"one of {', '.join(map(str, options))}")
    return check


def _flag(value) -> None:
    """A check of ``true`` or ``false``."""
    if not isinstance(value, bool):
        raise Bad("true or false")


def _unit(value) -> None:
    """A check of a unit's name (:func:`magexp.core.recording.check_unit`)."""
    if not isinstance(value, str):
        raise Bad(f"one of {', '.join((*UNITS, *RAW_UNITS))}")
    try:
        check_unit(value, "unit")
    except MagexpError:
        raise Bad(f"one of {', '.join((*UNITS, *RAW_UNITS))}") from None


def optional(check):
    """``check``, or ``null``."""
    def either(value):
        if value is not None:
            check(value)
    return either


def matrix(shape: tuple, extra=()):
    """A check of an array of ``shape`` of finite numbers of magnitude <= :data:`LARGEST` (``extra``: the
    strings also allowed in place of a number, e.g. ``"inf"`` for an undetermined standard error)."""
    what = " x ".join(map(str, shape))

    def check(value):
        cells = _cells(value, shape)
        if cells is None or not all((_is_number(c) and abs(c) <= LARGEST) or c in extra for c in cells):
            raise Bad(f"{what} finite numbers of magnitude <= {LARGEST:g}")
    return check


def _cells(value, shape: tuple):
    """The entries of the nested lists ``value`` if it has ``shape``, else None."""
    if not shape:
        return [value]
    if not isinstance(value, list) or len(value) != shape[0]:
        return None
    cells = []
    for item in value:
        inner = _cells(item, shape[1:])
        if inner is None:
            return None
        cells += inner
    return cells


def mapping(schema: dict | None = None, *, exact: bool = True, absent=()):
    """A check of a JSON object whose keys ``schema`` checks (each ``{key: check}``; ``exact``: no other key;
    ``absent``: the keys that may be missing)."""
    schema = schema or {}

    def check(value):
        if not isinstance(value, dict):
            raise Bad("an object {...}")
        for key, each in schema.items():
            if key not in value and key in absent:
                continue
            if key not in value:
                raise Bad(f"an object with the key {key!r}")
            try:
                each(value[key])
            except Bad as exc:
                raise Bad(f"{key}={_shown(value[key])} given; {key} must be {exc}") from None
        extra = sorted(set(value) - set(schema)) if exact and schema else []
        if extra:
            raise Bad(f"an object without {extra[0]!r} (its keys: {', '.join(schema)})")
    return check


def number_or(*names):
    """A check of a finite number or one of the strings ``names`` (``"inf"``: how JSON keeps an infinity)."""
    def check(value):
        if not ((_is_number(value) and math.isfinite(value)) or value in names):
            raise Bad(f"a finite number or one of {', '.join(names)}")
    return check


def _weakest(value) -> None:
    """A check of the quality report's weakest combinations: a non-empty list of ``{combination, value}``."""
    if not isinstance(value, list) or not value:
        raise Bad("a non-empty list")
    each = mapping({"combination": text(), "relative_singular_value": number_or("inf", "nan")})
    for item in value:
        each(item)


def _names(value) -> None:
    """A check of a list of strings."""
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise Bad("a list of strings")


def _search(value) -> None:
    """A check of the search box's record: ``{diag, offdiag, offset}`` each ``[low, high]``, or the calibration
    box's ``{lower, upper, how}`` (:mod:`magexp.calibration.box`)."""
    if not isinstance(value, dict):
        raise Bad("an object {...}")
    if set(value) == {"lower", "upper", "how"}:
        mapping({"lower": _numbers, "upper": _numbers, "how": text(empty=True)})(value)
    elif set(value) == {"diag", "offdiag", "offset"}:
        mapping({key: matrix((2,)) for key in ("diag", "offdiag", "offset")})(value)
    else:
        raise Bad("an object with the keys diag, offdiag, offset or lower, upper, how")


def _numbers(value) -> None:
    """A check of a list of finite numbers of magnitude <= :data:`LARGEST`."""
    if not isinstance(value, list) or not all(_is_number(v) and abs(v) <= LARGEST for v in value):
        raise Bad(f"a list of finite numbers of magnitude <= {LARGEST:g}")


def _provenance(value) -> None:
    """A check of the provenance record: an object naming the magexp version, each value a string or null."""
    mapping({"magexp_version": text()}, exact=False)(value)
    if not all(v is None or isinstance(v, str) for v in value.values()):
        raise Bad("an object of strings (the versions that made the calibration)")


#: the checks of each key of the format
SCHEMA = {
    "format": choice(FORMATS),
    "model": choice((MODEL,)),
    "recording": text(),
    "n_readings": ranged(1, 2 ** 53, whole=True),
    "unit": _unit,
    "field_unit": _unit,
    "estimator": text(),
    "objective": choice(OBJECTIVES),
    "seed": ranged(0, MAX_SEED, whole=True),
    "W": matrix((3, 3)),
    "W_form": text(empty=True),
    "offset": matrix((3,)),
    "reference": mapping({"total": _positive, "per_reading": _flag, "source": text(), "estimated": _flag,
                          "unit": optional(_unit), "field_model": optional(mapping(exact=False)), "how": text()},
                         absent=("unit", "field_model")),
    "search": optional(_search),
    "metrics": mapping({key: ranged(0, LARGEST) for key in METRICS}, exact=False),
    "quality": mapping({"W_standard_errors": matrix((3, 3), ("inf", "nan")),
                        "offset_standard_errors": matrix((3,), ("inf", "nan")),
                        "condition_number": number_or("inf", "nan"), "undetermined": _names,
                        "weakest_combinations": _weakest, "model": choice(ORDER),
                        "heading": optional(mapping(exact=False)), "gate": optional(mapping(exact=False))},
                       exact=False, absent=("heading", "gate")),  # none in a file older than them
    "fit": mapping({"fun": number_or("inf", "nan"), "nit": ranged(0, 2 ** 53, whole=True), "nfev": ranged(0, 2 ** 53, whole=True),
                    "success": _flag, "message": text(empty=True)}),
    "config": mapping(exact=False),
    "provenance": _provenance,
    "files": mapping(exact=False),
}


def check_parameters(data, name: str) -> dict:
    """``data``, the parsed ``calibration.json`` called ``name``, checked against :data:`SCHEMA` (module docstring)."""
    if not isinstance(data, dict) or data.get("format") not in FORMATS:
        found = data.get("format") if isinstance(data, dict) else type(data).__name__
        raise MagexpError(f"{name}: format {_shown(found)} is not allowed: magexp reads {', '.join(FORMATS)}")
    required = KEYS + (V3_KEYS if data["format"].endswith("v3") else ())
    missing = [key for key in required if key not in data]
    if missing:
        raise MagexpError(f"{name}: the key {missing[0]!r} is missing: a calibration.json holds "
                          f"{', '.join(required)}")
    extra = sorted(set(data) - set(KEYS + V3_KEYS + OPTIONAL))
    if extra:
        raise MagexpError(f"{name}: the key {extra[0]!r} is not allowed: a calibration.json holds "
                          f"{', '.join(KEYS + V3_KEYS + OPTIONAL)}")
    for key, check in SCHEMA.items():
        if key in data:
            _check(check, data[key], key, name)
    _check(_conditioned, data["W"], "W", name)
    return data


def _check(check, value, key: str, name: str) -> None:
    """Run ``check`` on ``value``, turning its :class:`Bad` into one line naming ``name`` and ``key``."""
    try:
        check(value)
    except Bad as exc:
        raise MagexpError(f"{name}: {key}={_shown(value)} is not allowed: it must be {exc}") from None


def _conditioned(w) -> None:
    """A check of ``W`` invertible, with a condition number at most :data:`MAX_CONDITION`."""
    s = np.linalg.svd(np.array(w, float), compute_uv=False)
    if not s[-1] > 0 or s[0] / s[-1] > MAX_CONDITION:
        raise Bad(f"invertible, with a condition number (largest / smallest singular value) at most "
                  f"{MAX_CONDITION:g}")
