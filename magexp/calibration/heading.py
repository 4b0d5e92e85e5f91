"""Heading error in degrees: what a calibration leaves of a compass's heading, before, after and as exported.

A pilot reads a compass in degrees of heading, not in % of ``|B|``. This module turns a calibration
``B = W (r − o)`` (:mod:`magexp.calibration.fit`) into the heading error it leaves at the site's
inclination, worst and RMS over every heading.

**The site.** In the local level frame (north, east, down) the Earth's field is
``f = F [cos I, 0, sin I]``, ``F`` the total and ``I`` the inclination (``tan I = V / H``). ``I``
comes from the field model where the place is known (:mod:`magexp.core.field_model`: ``field.*`` or
the log's GPS), else from a recording's ``# field:`` vector, else :data:`DEFAULT_INCLINATION_DEG`
(:func:`inclination_of`). Only ``|I|`` matters: the set of attitudes below is symmetric under turning the
sensor over, which maps ``I`` to ``−I`` and the heading ``ψ`` to ``−ψ``, so the worst and the RMS are the same.

**The attitudes.** At heading ``ψ`` the field in the heading-level frame (x forward, y right, z down) is

.. math:: \\mathbf h(\\psi) = F [\\cos I \\cos\\psi,\\ -\\cos I \\sin\\psi,\\ \\sin I]

and in the body (the calibrated field's axes) ``b = T_a^T h(ψ)``, ``T_a`` the body's tilt (body to
heading-level). The attitudes ``a`` (:func:`attitudes`): level, rolled by ``±`` :data:`TILT_DEG` and
pitched by ``±`` :data:`TILT_DEG`, each with the sensor's z axis down or up (a board lies flat, either way
up; which horizontal axis points forward does not matter for a level body: it shifts ``ψ``), at
:data:`N_HEADINGS` headings.

**The heading error.** A correction ``C`` applied to what the sensor reads gives ``b̂``; a
tilt-compensated compass (its tilt ``T_a`` known from the accelerometer) reads

.. math:: \\hat{\\mathbf h} = T_a \\hat{\\mathbf b}, \\quad \\hat\\psi = \\operatorname{atan2}(-\\hat h_y, \\hat h_x),
          \\quad e = \\operatorname{wrap}(\\hat\\psi - \\psi) \\in (-180°, 180°]

Every correction here is affine in the true field, ``b̂ = A b + c`` (:func:`errors`, vectorised over
corrections, attitudes and headings); ``e`` does not depend on ``F``'s unit, only on ``c / F``. Taking the
calibration as the truth, the sensor reads ``r = W^{-1} b + o``, and:

* **raw** (before): ``C`` the identity on the raw readings (scaling them to the reference turns no
  heading): ``A = W^{-1}``, ``c = o`` — the raw offset dominates, and beyond ``H = F cos I`` it turns
  the heading through every angle (:func:`raw_errors`);
* **calibrated** (after, held out): the calibration's own uncertainty on directions it has not seen.
  Each held-out fold's calibration ``(W_k, o_k)`` was fitted without one region of directions
  (:func:`magexp.calibration.fit.heldout`); ``C_k(r) = W_k (r − o_k)`` against the full calibration:
  ``A = W_k W^{-1}``, ``c = W_k (o − o_k)``; worst and RMS over folds, attitudes and headings
  (:func:`heldout_errors`). The folds were chosen over the standard errors of ``W`` and ``o``
  (``report["offset_standard_errors"]``): those assume the model holds everywhere and shrink as
  ``1/√N`` with the readings of the directions seen, while a fold measures how far the calibration
  moves when a region of directions is missing — what a direction never recorded does to the heading;
* **as exported** (:func:`export_errors`): the firmware's correction as exported
  (:func:`magexp.calibration.firmware.to_firmware`: ``B_fw = R_n S (r − OFF)``, ``S`` and ``OFF``
  rounded to float32 as the firmware holds them) against the full calibration, whose field is
  ``R_n R S (r − OFF)`` (``R`` the rotation of ``W`` left out of the symmetric matrix and of
  ``COMPASS_ORIENT`` / ``CAL_MAGn_ROT``): ``A = R_n S_{32} S^{-1} R^T R_n^T``,
  ``c = R_n S_{32} (OFF − OFF_{32})``. A rotation ``θ`` about the vertical left out is ``θ`` of heading.

**A scalar (total-field) calibration** determines ``W`` only up to a rotation: ``|R W (r − o)| = |W (r − o)|``.
magexp gives it in the symmetric canonical form (``R = I``), so the heading errors above are those of the
soft iron and the offset, which the scalar calibration fixes; the rotation between the sensor's axes and the
vehicle's (its mounting) must come from the mounting itself (the firmware's orientation parameter, or the
gyro-aided model, which determines it).
"""

from __future__ import annotations

import numpy as np

from magexp.core.geometry import rot_x, rot_y

#: the inclination (degrees) used when no place is known: mid-latitude, where most drones fly. The IGRF-14
#: (:mod:`magexp.core.field_model`) gives |I| of about 66° in London and Kansas, 68° in Berlin, 59° in Beijing,
#: 64° in Sydney, 50° in Tokyo, 45° in Delhi, 40° in São Paulo (2025). A heading error grows about as
#: ``1 / cos I``: at 70° it is 1.46 times the figure at 60°, at 45° 0.71 times; a place gives the site's own.
DEFAULT_INCLINATION_DEG = 60.0
#: the roll and pitch of the tilted attitudes (degrees): ArduCopter's default largest lean angle
#: (``ANGLE_MAX`` = 3000 centidegrees), the tilt a multicopter flies at
TILT_DEG = 30.0
#: headings evaluated, evenly spaced over 360°
N_HEADINGS = 360


def attitudes(tilt_deg: float = TILT_DEG) -> np.ndarray:
    """The tilts ``T_a`` (body to heading-level frame) the heading error is evaluated at (module docstring)."""
    t = np.radians(tilt_deg)
    tilts = [np.eye(3)] + ([rot_x(t), rot_x(-t), rot_y(t), rot_y(-t)] if tilt_deg else [])
    flip = rot_x(np.pi)
    return np.array([*tilts, *(tilt @ flip for tilt in tilts)])


def errors(matrix, offset, inclination_deg: float, *, tilt_deg: float = TILT_DEG,
           n_headings: int = N_HEADINGS) -> np.ndarray:
    """Heading errors of corrections ``b̂ = A b + c`` of the unit field ``b`` (module docstring), in degrees.

    .. math:: e_{m a k} = \\operatorname{wrap}\\big(\\operatorname{atan2}(-\\hat h_y, \\hat h_x) - \\psi_k\\big),
              \\quad \\hat{\\mathbf h} = T_a (A_m T_a^T \\mathbf h(\\psi_k) + \\mathbf c_m)"""
    a = np.asarray(matrix, float).reshape(-1, 3, 3)
    c = np.asarray(offset, float).reshape(-1, 3)
    tilt = attitudes(tilt_deg)
    psi = np.radians(headings(n_headings))
    inc = np.radians(inclination_deg)
    h = np.stack([np.cos(inc) * np.cos(psi), -np.cos(inc) * np.sin(psi), np.full_like(psi, np.sin(inc))], axis=1)
    body = h @ tilt  # (A, K, 3): b = T_a^T h, as rows
    seen = body[None] @ a.transpose(0, 2, 1)[:, None] + c[:, None, None, :]  # (M, A, K, 3): A b + c
    level = seen @ tilt.transpose(0, 2, 1)[None]  # T_a b̂
    err = np.degrees(np.arctan2(-level[..., 1], level[..., 0])) - np.degrees(psi)
    return -((-err + 180.0) % 360.0 - 180.0)  # wrapped to (-180, 180]


def headings(n_headings: int = N_HEADINGS) -> np.ndarray:
    """The headings evaluated, ``360° k / n`` for ``k = 0 … n − 1`` (degrees)."""
    return 360.0 * np.arange(n_headings) / n_headings


def raw_errors(w, offset, total: float, inclination_deg: float, **kw) -> np.ndarray:
    """Heading errors of the raw readings of a sensor whose calibration is ``(W, o)`` (module docstring):
    ``A = W^{-1}``, ``c = o / F``."""
    return errors(np.linalg.inv(w), np.asarray(offset, float) / total, inclination_deg, **kw)


def heldout_errors(w, offset, fits, total: float, inclination_deg: float, **kw) -> np.ndarray:
    """Heading errors of each held-out fold's calibration ``(W_k, o_k)`` against the full ``(W, o)``:
    ``A = W_k W^{-1}``, ``c = W_k (o − o_k) / F`` (module docstring)."""
    wk = np.array([np.asarray(f[0], float) for f in fits])
    ok = np.array([np.asarray(f[1], float) for f in fits])
    a = wk @ np.linalg.inv(w)
    c = np.einsum("kij,kj->ki", wk, np.asarray(offset, float) - ok) / total
    return errors(a, c, inclination_deg, **kw)


def export_errors(correction, total: float, inclination_deg: float, **kw) -> np.ndarray:
    """Heading errors of a firmware's correction as exported (:func:`~magexp.calibration.firmware.to_firmware`)
    against the calibration it came from: the rotation ``R`` left out and float32 rounding (module docstring)."""
    s, off = correction.matrix, correction.offset
    s32, off32 = s.astype(np.float32).astype(float), off.astype(np.float32).astype(float)
    turn, rot = correction.orientation_matrix, correction.rotation
    a = turn @ s32 @ np.linalg.inv(s) @ rot.T @ turn.T
    c = turn @ s32 @ (off - off32) / (total * correction.field_scale)
    return errors(a, c, inclination_deg, **kw)


def stats(err: np.ndarray) -> dict:
    """Worst and RMS of heading errors over everything, and over the level attitudes only."""
    level = err[:, [0, err.shape[1] // 2], :]
    return {"worst_deg": float(np.max(np.abs(err))), "rms_deg": float(np.sqrt(np.mean(err ** 2))),
            "level_worst_deg": float(np.max(np.abs(level))), "level_rms_deg": float(np.sqrt(np.mean(level ** 2)))}


def inclination_of(reference, rec=None, gps=None) -> tuple[float, str]:
    """The site's ``|I|`` and where it comes from: the reference's field model, else ``gps`` (the field model at
    the log's GPS place and date, :func:`magexp.core.field_model.gps_field`), else the recording's ``# field:``
    vector (its nav frame, z vertical), else :data:`DEFAULT_INCLINATION_DEG`."""
    record = reference.record or {}
    if "inclination_deg" in record:
        return abs(float(record["inclination_deg"])), (f"{record.get('generation', 'the field model')} at "
                                                       f"{record['latitude']:g}, {record['longitude']:g}, "
                                                       f"{record['date']}")
    if gps is not None:
        place = gps.record()
        return abs(gps.inclination_deg), (f"{gps.generation} at the log's GPS {place['latitude']:g}, "
                                          f"{place['longitude']:g}, {place['date']}")
    field = None if rec is None else rec.field
    if field is not None and np.linalg.norm(field) > 0:
        return abs(float(np.degrees(np.arctan2(field[2], np.hypot(field[0], field[1]))))), "the '# field:' vector"
    return DEFAULT_INCLINATION_DEG, "the default (no place given: field.latitude=..., field.date=...)"


def heading_record(w, offset, total: float, inclination: tuple[float, str], *, exported, fits=(),
                   missing: str = "no held-out check (folds=0)") -> dict:
    """The ``heading`` record of a calibration's report (``cal.report["heading"]``, ``calibration.json``)."""
    inc, source = inclination
    out = {"inclination_deg": float(inc), "inclination_source": source, "tilt_deg": TILT_DEG,
           "n_headings": N_HEADINGS, "raw": stats(raw_errors(w, offset, total, inc))}
    out["calibrated"] = ({**stats(heldout_errors(w, offset, fits, total, inc)), "folds": len(fits)} if len(fits)
                         else {"not_measured": missing})
    if isinstance(exported, str):
        out["exported"] = {"refused": exported}
    else:
        out["exported"] = {**stats(export_errors(exported, total, inc)), "rotation_left_out_deg": exported.rotation_deg,
                           "orientation": exported.orientation}
    return out


def worst_left(record: dict | None) -> float | None:
    """The level worst heading error a calibration leaves on directions it was not fitted to (held out): what the
    gate's ``max_heading_deg`` reads; None when not measured. What an export leaves out is the export's to refuse
    (``max_rotation_deg``): a whole-``W`` target (``ros``, ``c``) leaves nothing out."""
    return ((record or {}).get("calibrated") or {}).get("level_worst_deg")


def _deg(value: float) -> str:
    """Degrees to 3 significant digits, ``<0.001`` below a thousandth (float32 rounding)."""
    return "<0.001" if value < 1e-3 else f"{value:.3g}"


def _pair(part: dict) -> str:
    """``worst/RMS°`` of one stage's record, or why it is missing."""
    if "not_measured" in part:
        return f"not measured ({part['not_measured']})"
    if "refused" in part:
        return "not exportable (a mirrored W)"
    return f"{_deg(part['level_worst_deg'])}/{_deg(part['level_rms_deg'])}°"


def _tilted(part: dict) -> str:
    """``worst`` over every attitude of one stage, or a dash."""
    return f"{_deg(part['worst_deg'])}°" if "worst_deg" in part else "-"


def summary_lines(record: dict | None) -> dict:
    """The printed summary's heading-error lines (nothing for a calibration without a record)."""
    if not record:
        return {}
    raw, cal, exp = (record.get(k) or {} for k in ("raw", "calibrated", "exported"))
    left = "" if not exp.get("rotation_left_out_deg", 0.0) >= 1e-3 else (
        f"; the export leaves out a rotation of {exp['rotation_left_out_deg']:.3g}°"
        + (f" beside orientation {exp['orientation']}" if exp.get("orientation") is not None else "")
        + " (PX4's CAL_MAGn_ROT holds standard orientations only; export=ardupilot carries the rotation whole as its "
          "custom rotation, COMPASS_ORIENT=101, and its file states the heading error it leaves)")
    return {
        "heading error": (f"raw {_pair(raw)} -> calibrated (held out) {_pair(cal)} -> as exported to ArduPilot/PX4 {_pair(exp)} "
                          f"(worst/RMS over {record['n_headings']} headings, level; at inclination "
                          f"{record['inclination_deg']:.1f}° from {record['inclination_source']}){left}"),
        "heading error tilted": (f"raw {_tilted(raw)} -> calibrated {_tilted(cal)} -> as exported {_tilted(exp)} "
                                 f"(worst, also rolled and pitched ±{record['tilt_deg']:g}°, ArduCopter's ANGLE_MAX)"),
    }


def export_line(correction, total: float | None, inclination: tuple[float, str] | None) -> str | None:
    """An export file's comment on the heading error its parameters leave against the calibration
    (:func:`export_errors`), or None without a site."""
    if inclination is None or total is None:
        return None
    s = stats(export_errors(correction, total, inclination[0]))
    return (f"heading error these parameters leave against the calibration (rotation left out, float32): worst "
            f"{_deg(s['level_worst_deg'])} deg, RMS {_deg(s['level_rms_deg'])} deg over headings, level; worst "
            f"{_deg(s['worst_deg'])} deg rolled and pitched +-{TILT_DEG:g} deg; at inclination {inclination[0]:.1f} deg "
            f"from {inclination[1]}")


def heldout_note(record: dict | None) -> dict:
    """An export's note of the heading error the calibration itself leaves (held out), or nothing unmeasured."""
    part = (record or {}).get("calibrated") or {}
    if "folds" not in part:
        return {}
    return {"heading error of the calibration (held out)": (
        f"worst {_deg(part['level_worst_deg'])} deg, RMS {_deg(part['level_rms_deg'])} deg over headings, level; "
        f"worst {_deg(part['worst_deg'])} deg rolled and pitched +-{record['tilt_deg']:g} deg (each of "
        f"{part['folds']} regions of directions calibrated by the fit on the others, against the full calibration)")}



def heading_of(cal, exported, *, gps=None) -> dict:
    """:func:`heading_record` of a fitted calibration: its ``W``, offset, held-out folds' calibrations
    (``cal.heldout_fits``), reference total and site (:func:`inclination_of` its reference and recording)."""
    missing = ("no held-out check (folds=0)" if "heldout_spread" not in cal.metrics
               else "a region of directions held out could not be fitted")
    return heading_record(cal.w, cal.offset, float(np.mean(cal.reference.total)),
                          inclination_of(cal.reference, cal.recording, gps), exported=exported, fits=cal.heldout_fits,
                          missing=missing)


def curves(cal, exported) -> dict:
    """The figure's heading error at each heading (:func:`headings`): the worst ``|e|`` over the attitudes (and
    the folds) of each stage of ``cal.report["heading"]`` (raw, calibrated held out, as exported), at its
    inclination."""
    record, total = cal.report["heading"], float(np.mean(cal.reference.total))
    inc = record["inclination_deg"]
    out = {"raw": raw_errors(cal.w, cal.offset, total, inc)}
    if cal.heldout_fits:
        out["calibrated (held out)"] = heldout_errors(cal.w, cal.offset, cal.heldout_fits, total, inc)
    if not isinstance(exported, str):
        out["as exported"] = export_errors(exported, total, inc)
    return {label: np.abs(err).max(axis=(0, 1)) for label, err in out.items()}
