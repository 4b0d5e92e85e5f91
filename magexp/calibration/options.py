"""The options of ``magexp calibrate``: one typed schema, the one home of each key's type, default and sentence.

:class:`CalibrateOptions` (with :class:`DataOptions`, :class:`FieldOptions`, :class:`IgrfOptions` and
:class:`GateOptions`) is a tree of dataclasses. From it come:

* ``magexp calibrate --help`` (:func:`help_text`): every key, dotted, its type, default and sentence;
* ``conf/calibrate.yaml``, the command's primary config (:func:`yaml_text`), generated and checked equal to
  the schema by the tests (``python -m magexp.calibration.options --write`` rewrites it);
* the defaults of :func:`magexp.calibration.api.calibrate`'s keyword parameters (:data:`DEFAULTS`).

The gate's thresholds are :data:`magexp.calibration.checks.GATE`'s and ``auto_margin``'s
:data:`magexp.calibration.models.MARGIN`: the schema reads them, it does not repeat them.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import textwrap
import types
import typing
from dataclasses import dataclass, field

from magexp.calibration.checks import GATE
from magexp.calibration.models import MARGIN
from magexp.core.readers import formats, names, summary

#: ``live.margin``: the live stop rule's margin on the gate (:mod:`magexp.calibration.live`)
LIVE_MARGIN = 0.5
from magexp.paths import CONF

#: the estimator of ``conf/calibrate.yaml``'s defaults list (``estimator=<name>`` chooses another)
ESTIMATOR = "ellipsoid"
#: the command's primary config, generated from the schema (:func:`yaml_text`)
CONFIG = CONF / "calibrate.yaml"


def option(default, text: str, *, factory=None):
    """A schema field: its ``default`` (or ``factory`` for a group) and its sentence ``text``."""
    if factory is not None:
        return field(default_factory=factory, metadata={"help": text})
    return field(default=default, metadata={"help": text})


def _gate(key: str, text: str):
    """The option of ``gate.<key>``, its default :data:`magexp.calibration.checks.GATE`'s: one home for the thresholds."""
    return option(GATE[key], text)


@dataclass
class GateOptions:
    """``gate.*``: the acceptance gate's thresholds (:func:`magexp.calibration.checks.gate`)."""

    heldout_vs_raw: float = _gate("heldout_vs_raw", "the held-out spread must be below this times the raw spread")
    max_anisotropy: float = _gate("max_anisotropy", "largest / smallest singular value of W (real sensors: at most "
                                                    "2.25, docs/calibrate.md)")
    scale_range: tuple[float, float] = _gate("scale_range", "each singular value of W / (reference / raw radius) "
                                                    "(ArduPilot's diagonal range)")
    radius_mG: tuple[float, float] = _gate("radius_mG", "radius of the raw readings' sphere, physical units (ArduPilot's "
                                                "accepted field)")
    radius_vs_reference: tuple[float, float] = _gate("radius_vs_reference", "raw radius / the reference total, when a "
                                                                    "reference is given")
    max_rms_mG: float = _gate("max_rms_mG", "RMS of |calibrated| - reference (ArduPilot's COMPASS_CAL_FIT default)")
    max_rms_fraction: float = _gate("max_rms_fraction", "the same relative to the reference, for a raw-count unit "
                                                        "(16 of 500 mGauss)")
    min_region: float = _gate("min_region", "each of the 6 regions of directions holds this fraction of the readings "
                                            "(else untested)")
    max_heading_deg: float = _gate("max_heading_deg", "level worst heading error the calibration leaves on directions "
                                                      "it was not fitted to (held out), degrees (14 CFR 25.1327(b): 10 "
                                                      "on any heading)")


@dataclass
class DataOptions:
    """``data.*``: the recording (:func:`magexp.core.recordings.load_recording`)."""

    path: str | None = option(None, "a recording in any format of data.format (two-stream: either file or their "
                                    "stem)")
    format: str = option("auto", "auto (told from the file) or a format's name: magexp calibrate --help lists them "
                                 "(docs/calibrate.md#file-formats)")
    unit: str | None = option(None, "unit of a file that does not name it (nT | uT | mG | G | T | counts)")
    mag_axes: str | None = option(None, 'signed axis map of the magnetometer onto the body axes, e.g. "-x,y,z" '
                                        "(null: the format's)")
    gyro_axes: str | None = option(None, 'the same for the gyroscope (two-stream default: "-x,y,z")')
    reference_total: float | None = option(None, "reference total field (recording's unit); null: the field "
                                                 "model's, else the file's, else estimated")
    serial: str | None = option(None, "read a live stream from this serial port (e.g. /dev/ttyUSB0, COM3; pyserial) "
                                      "instead of data.path (data.path=-: standard input): docs/calibrate.md#live-calibration")
    baud: int = option(115200, "the serial port's baud rate")


@dataclass
class LiveOptions:
    """``live.*``: reading a live stream (``data.serial`` or ``data.path=-``; :mod:`magexp.calibration.live`)."""

    margin: float = option(LIVE_MARGIN, "stop when the gate passes with its held-out limit times (1 - margin) and "
                                        "every region of directions held out")
    refit_readings: int = option(100, "a live check (closed-form fit, held-out spread, coverage) every this many new "
                                      "readings")
    refit_seconds: float = option(1.0, "... or every this many seconds, whichever comes first (and never sooner than "
                                       "4 times the last check's duration after it)")
    check_readings: int = option(10000, "a live check fits at most this many readings, evenly spaced (bounded work; "
                                        "fewer: the readings' noise is no longer measured from neighbours)")
    stall_seconds: float = option(10.0, "stop when no valid reading has arrived for this many seconds")
    max_readings: int = option(1_000_000, "stop after this many lines (valid or not)")
    max_line: int = option(512, "a longer line is garbage (bytes)")


@dataclass
class FieldOptions:
    """``field.*``: the reference total from a field model (:mod:`magexp.core.field_model`)."""

    model: str = option("igrf", "igrf (IGRF-14, 1900-2030) | wmm (WMM2010-WMM2025, 2010-2030; what ArduPilot and "
                                "PX4 use)")
    latitude: float | None = option(None, "degrees north (null: the log's GPS, else no field model)")
    longitude: float | None = option(None, "degrees east (null: the log's GPS)")
    altitude_km: float | None = option(None, "above the WGS84 ellipsoid (null: the log's GPS, else 0)")
    date: str | None = option(None, "YYYY-MM-DD (null: the log's GPS date)")


@dataclass
class IgrfOptions:
    """``igrf.*``: the older names of ``field.*`` (with ``field.model=igrf``)."""

    latitude: float | None = option(None, "= field.latitude")
    longitude: float | None = option(None, "= field.longitude")
    altitude_km: float = option(0.0, "= field.altitude_km")
    date: str | None = option(None, "= field.date")


@dataclass
class CalibrateOptions:
    """Every key of ``magexp calibrate`` but ``estimator`` (a config group: ``conf/estimator/*.yaml``)."""

    seed: int = option(0, "the estimator's random draws derive from it")
    objective: str = option("scalar", "scalar (total field) | vector (needs attitudes and a '# field:' line)")
    model: str = option("auto", "auto (the model the held-out spread supports) | sphere (offset, one scale) | "
                                "diagonal (offset, one scale per axis) | full (symmetric W and offset, by the "
                                "estimator) | gyro (whole W and offset with the gyroscope's attitude, field direction "
                                "and gyro bias; by lm): magexp/calibration/models.py")
    auto_margin: float = option(MARGIN, "model=auto: a richer model must cut the simpler's held-out spread by this "
                                        "fraction")
    accept: bool = option(False, "true: write a calibration that fails the acceptance gate, its failures recorded")
    gate: GateOptions = option(None, "the acceptance gate (magexp/calibration/checks.py): a calibration failing one "
                                     "is refused (exit 2)", factory=GateOptions)
    folds: int = option(6, "held-out check: each of the 6 regions of directions calibrated by the fit on the others, "
                           "or for a few static shots each reading by the fit without its neighbours (0: none)")
    out: str | None = option(None, "output folder (null: calibration_<recording stem> in the working folder)")
    overwrite: bool = option(False, "true: replace the earlier calibration in out, its whole set (what it wrote "
                                          "and this one does not is removed and named); never a file no calibration wrote")
    figure: bool = option(False, "true: draw calibration.png and .pdf (drawing takes longer than the calibration "
                                 "itself)")
    export: str | None = option(None, "also write the firmware's file beside calibration.json: ardupilot | px4 | "
                                      "ros | c")
    counts_nt: float | None = option(None, "nT per count of the firmware's magnetometer driver (exporting a counts "
                                           "calibration needs it)")
    max_rotation_deg: float | None = option(None, "export=ardupilot|px4: the largest rotation R of W = R S exported "
                                                  "as S alone, or left beside the orientation exported for model=gyro "
                                                  "(null: 1 deg)")
    instance: int | None = option(None, "a DataFlash log's compass (and IMU) instance read, 0 first, and the "
                                        "parameter slot exported (ardupilot COMPASS_OFS2_* for 1; px4 CAL_MAGn); "
                                        "null: 0, for px4 a ULog's calibration slot")
    data: DataOptions = option(None, "the recording (magexp/core/recordings.py)", factory=DataOptions)
    live: LiveOptions = option(None, "a live stream (data.serial or data.path=-): when to check and to stop, what "
                                     "is read at most", factory=LiveOptions)
    field: FieldOptions = option(None, "the reference total from a field model where and when recorded "
                                       "(magexp/core/field_model.py)", factory=FieldOptions)
    igrf: IgrfOptions = option(None, "the older names of field.* (with field.model=igrf); kept working",
                               factory=IgrfOptions)


#: the schema's defaults (:func:`magexp.calibration.api.calibrate` takes its keyword defaults from them)
DEFAULTS = CalibrateOptions()


def _type_name(annotation) -> str:
    """``int``, ``float or null``, ``[float, float]``: a field's type as the help prints it."""
    hint = eval(annotation, vars(sys.modules[__name__])) if isinstance(annotation, str) else annotation  # noqa: S307
    if isinstance(hint, types.UnionType):
        args = [a for a in typing.get_args(hint) if a is not type(None)]
        return " or ".join(_type_name(a) for a in args) + " or null"
    if typing.get_origin(hint) is tuple:
        return "[" + ", ".join(_type_name(a) for a in typing.get_args(hint)) + "]"
    return "group" if dataclasses.is_dataclass(hint) else hint.__name__


def rows(schema=CalibrateOptions, prefix: str = "") -> list[tuple[str, str, object, str]]:
    """``(dotted key, type, default, sentence)`` of every key of ``schema``, a group before its keys."""
    out = []
    for f in dataclasses.fields(schema):
        kind = _type_name(f.type)
        if kind == "group":
            out.append((prefix + f.name, kind, None, f.metadata["help"]))
            out += rows(f.default_factory, f"{prefix}{f.name}.")
        else:
            out.append((prefix + f.name, kind, f.default, f.metadata["help"]))
    return out


def _yaml_value(value) -> str:
    """A default as YAML writes it (``null``, ``true``, ``[0.2, 5.0]``, ``scalar``)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, tuple):
        return "[" + ", ".join(_yaml_value(v) for v in value) + "]"
    return str(value)


def yaml_text() -> str:
    """``conf/calibrate.yaml``: the defaults list (the estimator), then every key of the schema with its default
    and its sentence as a comment (long sentences continued on comment lines)."""
    lines = ["# magexp calibrate: calibrate a recording (magexp/calibration/command.py). Its own primary config,",
             "# generated from the typed schema magexp/calibration/options.py (python -m magexp.calibration.options "
             "--write):",
             "#   magexp calibrate data.path=../shared/data/fxos8700_mag_readings.txt data.unit=uT estimator=lm "
             "out=calib/",
             "defaults:", f"  - estimator: {ESTIMATOR}      # conf/estimator/*.yaml that applies to the objective",
             "  - _self_", ""]
    for key, kind, default, text in rows():
        depth, name = key.count("."), key.rsplit(".", 1)[-1]
        if kind == "group" and depth == 0 and key != "gate":
            lines.append("")  # the recording and the field model apart, as sections
        head = "  " * depth + f"{name}:" + ("" if kind == "group" else f" {_yaml_value(default)}")
        column = max(len(head) + 2, 29 if key.startswith("gate.") else 19)
        wrapped = textwrap.wrap(text, 120 - column - 2) or [""]
        lines.append(f"{head:<{column}}# {wrapped[0]}")
        lines += [f"{'':<{column}}# {more}" for more in wrapped[1:]]
    return "\n".join(lines) + "\n"


def help_text(estimators=()) -> str:
    """``magexp calibrate --help``: every key of the schema (dotted), its type, default and sentence, then
    the estimators and the recording formats (:mod:`magexp.core.readers`) to choose from."""
    table = [(key, kind, "(group)" if kind == "group" else _yaml_value(default), text)
             for key, kind, default, text in rows()]
    width, kinds = max(len(r[0]) for r in table), max(len(r[1]) for r in table)
    lines = ["magexp calibrate KEY=VALUE ...: calibrate a recording (docs/calibrate.md)", "",
             "e.g. magexp calibrate data.path=mine.csv data.unit=uT", "",
             f"{'key':<{width}}  {'type':<{kinds}}  default: meaning"]
    lines += [f"{k:<{width}}  {t:<{kinds}}  {v}: {s}" for k, t, v, s in table]
    lines += ["", f"estimator: one of {', '.join(estimators)} (conf/estimator/*.yaml; "
              "estimator.<option>=... sets its options)", "", "data.format: auto, or one of (in the order auto tries them):"]
    width = max(map(len, names()))
    for module in formats():
        lines += textwrap.wrap(summary(module), 118, initial_indent=f"  {module.NAME:<{width}}  ",
                               subsequent_indent=" " * (width + 4))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """``python -m magexp.calibration.options [--write]``: print :func:`yaml_text`, or write it to
    ``conf/calibrate.yaml``."""
    parser = argparse.ArgumentParser(description="conf/calibrate.yaml from the calibrate options' schema")
    parser.add_argument("--write", action="store_true", help=f"write {CONFIG} instead of printing it")
    args = parser.parse_args(argv)
    if args.write:
        CONFIG.write_text(yaml_text())
    else:
        print(yaml_text(), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
