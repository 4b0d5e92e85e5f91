"""What ``magexp calibrate`` writes: parameters (JSON), calibrated readings (CSV), a before/after figure.

Files, in the output folder (``out=...``, default Hydra's run folder):

* ``calibration.json``: ``W`` and ``offset`` of ``B = W (reading - offset)``, unit, estimator,
  objective, the form ``W`` is given in, the reference used and how it was obtained, the search
  box, the spread metrics (before, after, held out), the quality report (standard errors,
  conditioning, undetermined combinations, direction coverage) and the fit's outcome
  (format ``magexp-calibration v2``);
* ``calibrated.csv``: a ``magexp-recording v1`` file with the calibrated ``bx, by, bz``, their
  ``magnitude``, and the raw ``raw_bx, raw_by, raw_bz, raw_magnitude``;
* ``calibration.png`` and ``calibration.pdf`` (only with ``figure=true``: drawing them takes longer
  than the calibration): plane projections of the raw and calibrated readings with the reference
  circle, the map of the sphere cells the raw directions reach about the fitted centre, and the
  total field per reading and its histogram, before and after;
* with ``export=<target>``, the firmware's file (:mod:`magexp.calibration.export`).

A folder holds one calibration (:mod:`magexp.calibration.folder`): ``calibration.json`` lists the other files
it wrote (``files``, their SHA-256). An existing file is never overwritten; ``overwrite=true`` replaces the
earlier calibration's whole set (what it wrote and this one does not is removed, and named), never a file
no calibration wrote, and a folder holding the recording is refused. Nothing is written under ``results/``.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np

from magexp.calibration.export import FILE_NAMES, firmware_correction, of_calibration
from magexp.calibration.folder import (MANIFEST, Plan, check_file, check_recording, digest, file_path, plan,
                                      recording_files)
from magexp.calibration.heading import curves as heading_curves, summary_lines
from magexp.calibration.holdout import describe as describe_heldout
from magexp.calibration.onboard import onboard_line
from magexp.calibration.schema import FORMATS, check_parameters, read_json
from magexp.core.atomic import _stops_held as stops_held, write_text
from magexp.core.identifiability import CELLS
from magexp.run.folders import check_destination, first_missing
from magexp.core.readers.magexp_v1 import VERSION_LINE
from magexp.errors import MagexpError
from magexp.paths import RESULTS
from magexp.run.provenance import provenance

FILES = {"parameters": "calibration.json", "readings": "calibrated.csv", "figure": "calibration.png",
         "figure_vector": "calibration.pdf"}  # the figure and its vector twin (magexp.artifacts.plots.style.save)
#: every name a calibration may write into its folder (the earlier set of a folder written before the manifest)
KNOWN = (*FILES.values(), *FILE_NAMES.values())


def check_out(out_dir: Path, *, overwrite: bool = False, export: str | None = None, draw: bool = True,
              recording=()) -> Plan:
    """Refuse, in one line, an output folder under ``results/``, one that holds the recording being read, or
    one whose files are in the way (:func:`magexp.calibration.folder.plan`: without ``overwrite`` any output
    file there; with it a file no calibration wrote); else what writing there replaces and removes."""
    out_dir = Path(out_dir).resolve()
    if out_dir == RESULTS.resolve() or RESULTS.resolve() in out_dir.parents:
        raise MagexpError(f"out={str(out_dir)!r} is not allowed: results/ holds the reproduced papers only, "
                          "choose another folder")
    if out_dir.exists() and not out_dir.is_dir():
        raise MagexpError(f"out={str(out_dir)!r} is not allowed: it is a file, not a folder")
    existing = next(p for p in (out_dir, *out_dir.parents) if p.exists())  # checked, nothing created yet
    if not existing.is_dir():
        raise MagexpError(f"out={str(out_dir)!r} is not allowed: {str(existing)!r} is a file, not a folder")
    if not os.access(existing, os.W_OK):
        raise MagexpError(f"out={str(out_dir)!r} is not allowed: {str(existing)!r} is not writable")
    check_recording(out_dir, recording)
    return plan(out_dir, _output_names(draw, export), overwrite=overwrite, known=KNOWN)


def _output_names(draw: bool, export: str | None) -> list[str]:
    """The names of the files :func:`write` writes: the parameters, the readings, the figure (``draw``), the export."""
    return [FILES["parameters"], FILES["readings"], *((FILES["figure"], FILES["figure_vector"]) if draw else ()),
            *([export_name(export)] if export else [])]


#: the format line of ``calibration.json`` (:func:`parameters`); :func:`read_parameters` reads every one of
#: :data:`~magexp.calibration.schema.FORMATS`
FORMAT = FORMATS[-1]


def parameters(cal, *, seed: int | None = None) -> dict:
    """The JSON content of a :class:`~magexp.calibration.result.Calibration` (format :data:`FORMAT`):
    ``W`` and the offset, the units, the reference and the field model it came from (generation,
    latitude, longitude, altitude, date), the metrics, the quality report (with the acceptance
    gate and the model selection), the fit's outcome, the config and the provenance (magexp
    version, commit, libraries: :func:`magexp.run.provenance.provenance`). A loaded calibration
    gives back the JSON it was read from."""
    if cal.saved is not None:
        return cal.saved
    rec, box = cal.recording, cal.search
    return {
        "format": FORMAT,
        "model": "B = W (reading - offset)",
        "recording": str(rec.path or rec.name),
        "n_readings": rec.n,
        "unit": cal.unit,
        "field_unit": cal.field_unit,
        "estimator": cal.estimator,
        "objective": cal.objective,
        "seed": int(cal.seed if seed is None else seed),
        "W": cal.w.tolist(),
        "W_form": cal.report.get("w_form", ""),
        "offset": cal.offset.tolist(),
        "reference": {"total": float(np.mean(cal.reference.total)),
                      "per_reading": bool(np.ptp(cal.reference.total) > 0), "source": cal.reference.source,
                      "estimated": cal.reference.estimated, "unit": cal.reference.unit,
                      "field_model": cal.reference.record, "how": cal.reference.describe()},
        "search": box.record(),
        "metrics": cal.metrics,
        "quality": _finite(cal.report),
        "fit": {"fun": float(cal.fit.fun), "nit": int(cal.fit.nit), "nfev": int(cal.fit.nfev),
                "success": bool(cal.fit.success), "message": cal.fit.message},
        "config": _finite(cal.config),
        "provenance": provenance(cal.config),
    }


def save_parameters(cal, path, *, overwrite: bool = False) -> Path:
    """Write :func:`parameters` of ``cal`` to ``path`` atomically; an existing file is refused in one
    line unless ``overwrite``, and then only a file a calibration wrote
    (:func:`magexp.calibration.folder.is_calibrations`)."""
    path = file_path(path, "path")
    check_destination(path, "path")
    check_file(path, overwrite=overwrite, recording=recording_files(cal.recording), option="path")
    saved = {k: v for k, v in parameters(cal).items() if k != MANIFEST}  # the manifest is its folder's, not copied
    return write_text(path, json.dumps(saved, indent=2) + "\n")


def read_parameters(path) -> dict:
    """The content of a ``calibration.json``, read within bounds and checked against the schema ``save`` writes
    (:mod:`magexp.calibration.schema`: every key's type, range and finiteness, ``W`` invertible and
    well-conditioned; JSON: nothing read can run code); else one line."""
    return check_parameters(read_json(path, "path"), Path(path).name)


def _finite(value):
    """``value`` with infinities as the string ``"inf"`` (JSON has no infinity)."""
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    if isinstance(value, float) and not np.isfinite(value):
        return str(value)
    return value


#: rows of the calibrated readings formatted at a time (:func:`write_readings`)
ROWS_PER_BLOCK = 1 << 16


def write_readings(cal, fh) -> None:
    """The calibrated readings as a ``magexp-recording v1`` CSV, into the text file ``fh``: a block of
    :data:`ROWS_PER_BLOCK` rows at a time, each block one ``%``-format in C (``%.10g`` per value)."""
    raw, cal_b = cal.recording.readings, cal.calibrated
    head = [VERSION_LINE, f"# source: {cal.recording.name} calibrated by magexp "
                          f"(estimator {cal.estimator}, objective {cal.objective})", f"# unit: {cal.field_unit}"]
    if cal.field_unit != cal.unit:
        head.append(f"# raw_unit: {cal.unit}")
    head.append("bx,by,bz,magnitude,raw_bx,raw_by,raw_bz,raw_magnitude")
    fh.write("\n".join(head) + "\n")
    row = ",".join(["%.10g"] * 8) + "\n"
    for lo in range(0, len(raw), ROWS_PER_BLOCK):
        b, r = cal_b[lo:lo + ROWS_PER_BLOCK], raw[lo:lo + ROWS_PER_BLOCK]
        table = np.column_stack([b, np.linalg.norm(b, axis=1), r, np.linalg.norm(r, axis=1)])
        fh.write(row * len(table) % tuple(table.ravel().tolist()))


def figure(cal):
    """The before/after figure of ``cal`` (:func:`magexp.calibration.figure.calibration_figure`)."""
    # lazy: matplotlib only when a figure is drawn; the Python API and magexp calibrate without
    # figure=true never pay for it (these cost 478 ms CPU to import after magexp.calibration.fit, min of 5)
    from magexp.calibration.figure import calibration_figure

    title = f"{cal.name}: {cal.model} by {cal.estimator} ({cal.objective}), spread " \
            f"{100 * cal.metrics['spread_before']:.2f} % -> {100 * cal.metrics['spread_after']:.2f} %"
    record = cal.report.get("heading")
    panel = None if not record else (heading_curves(cal, firmware_correction(cal)),
                                     f"heading error at inclination {record['inclination_deg']:.1f}° "
                                     f"({record['inclination_source'].split(' (')[0]})")  # the summary says why
    return calibration_figure(cal.recording.readings, cal.calibrated, cal.reference.total, unit=cal.field_unit,
                              title=title, centre=cal.offset, heading=panel)


def export_name(target: str) -> str:
    """The file name ``export=<target>`` writes (:data:`magexp.calibration.export.FILE_NAMES`)."""
    return FILE_NAMES[target]


class Written(dict):
    """``{kind: path}`` of the files :func:`write` wrote, and ``removed``: the earlier calibration's files it
    removed (those of its set this one does not write)."""

    removed: tuple = ()


def write(cal, out_dir: Path, *, seed: int | None = None, draw: bool = False, overwrite: bool = False,
          export: str | None = None, export_options: dict | None = None, recording=None) -> Written:
    """Write ``calibration.json``, ``calibrated.csv`` and, with ``draw``, the figure into ``out_dir``
    (checked by :func:`check_out`; ``overwrite`` replaces the earlier calibration's whole set there), and
    with ``export`` the firmware file of that target beside them (:mod:`magexp.calibration.export`,
    ``export_options`` as :func:`magexp.calibration.export.render`); ``calibration.json`` lists the others
    with their SHA-256 (its ``files``); return their paths.

    Never destroys: the export is rendered first (its refusals, e.g. a rotation or a raw unit without
    ``counts_nt``, come before any file is touched); every file is written into a hidden staging folder
    inside ``out_dir``; only once all are complete is the folder checked again and, with Ctrl-C and
    ``kill`` held back, each moved into place (``os.replace``, ``calibration.json`` last) and the earlier
    calibration's files this one does not write removed. A failure removes the staging folder and
    whatever this call created (the folders made for ``out_dir``, a file already moved into place),
    nothing else. The figure draws at most :data:`magexp.calibration.figure.MAX_POINTS` readings."""
    out_dir = Path(out_dir)
    recording = recording_files(cal.recording) if recording is None else recording
    check_out(out_dir, overwrite=overwrite, export=export, draw=draw, recording=recording)
    rendered = None
    if export:
        rendered = of_calibration(cal, export, **(export_options or {}))
    keys = ("parameters", "readings", *(("figure", "figure_vector") if draw else ()))
    paths = Written({key: out_dir / FILES[key] for key in keys})
    if export:
        paths["export"] = out_dir / export_name(export)
    created, placed = first_missing(out_dir), []
    out_dir.mkdir(parents=True, exist_ok=True)
    stage = Path(tempfile.mkdtemp(dir=out_dir, prefix=".magexp-calibrate."))
    try:
        _stage(cal, stage, seed=seed, draw=draw, export=None if rendered is None else (paths["export"].name,
                                                                                        rendered.text))
        with stops_held():  # the swap whole: an interrupted one would leave a mixed folder
            todo = check_out(out_dir, overwrite=overwrite, export=export, draw=draw, recording=recording)
            _place(stage, [*list(paths.values())[1:], paths["parameters"]], placed=placed)
            for name in todo.removes:
                (out_dir / name).unlink(missing_ok=True)
            placed, created = [], None  # done: a stop delivered as the block ends undoes nothing
    except BaseException:  # failed or interrupted: what this call made goes, nothing else
        for path in placed:
            path.unlink(missing_ok=True)
        if created is not None:
            shutil.rmtree(created, ignore_errors=True)
        raise
    finally:
        shutil.rmtree(stage, ignore_errors=True)
    paths.removed = tuple(out_dir / name for name in todo.removes)
    return paths


def _stage(cal, stage: Path, *, seed, draw: bool, export: tuple[str, str] | None) -> None:
    """Write every file of :func:`write` into the folder ``stage``, ``calibration.json`` last with the others'
    digests (its ``files``): ``export`` is ``(name, text)``."""
    with open(stage / FILES["readings"], "w") as fh:
        write_readings(cal, fh)
    if draw:
        from magexp.artifacts.plots.style import save  # lazy: matplotlib (see figure)

        save(figure(cal), stage / FILES["figure"])
    if export is not None:
        write_text(stage / export[0], export[1])
    files = {p.name: digest(p) for p in sorted(stage.iterdir()) if p.is_file() and not p.name.startswith(".")}
    write_text(stage / FILES["parameters"], json.dumps({**parameters(cal, seed=seed), MANIFEST: files}, indent=2)
               + "\n")


def _place(stage: Path, paths: list[Path], *, placed: list[Path]) -> None:
    """Move each staged file onto its path (``os.replace``; what is there was checked just before).
    ``placed`` gets each path this call created."""
    for path in paths:
        existed = path.exists()
        os.replace(stage / path.name, path)
        placed += [] if existed else [path]


def table(rows: dict) -> str:
    """``key  value`` lines, keys aligned (the printed summary)."""
    width = max(len(k) for k in rows)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in rows.items())


def _fit_line(fit, saved) -> str:
    """The fit's outcome in one line (of a loaded calibration: as saved)."""
    success, message = (fit.success, fit.message) if fit is not None else (saved["fit"]["success"],
                                                                              saved["fit"]["message"])
    return f"{'success' if success else 'FAILED'}: {message}"


def _gate_line(record: dict, metrics: dict) -> str:
    """The acceptance gate's outcome in one line, saying what the held-out check measured (``metrics``)."""
    if not record:
        return "not checked"
    if record["passed"]:
        return f"passed ({describe_heldout(metrics, gate=True)}; W's shape, the radius and the residual RMS plausible)"
    return "FAILED, written because accept=true: " + "; ".join(f.get("reason") or f["line"].split(":")[0]
                                                                for f in record["failed"])


def _onboard_lines(report: dict) -> dict:
    """The line of a log's undone onboard calibration (:mod:`magexp.calibration.onboard`; nothing without one)."""
    record = report.get("onboard_calibration")
    return {"onboard calibration": onboard_line(record)} if record else {}


def _gyro_lines(report: dict, unit: str) -> dict:
    """The gyro-aided model's own line (nothing for the other models)."""
    if "gyro_bias_deg_s" not in report:
        return {}
    bias = ", ".join(f"{v:.3g}" for v in report["gyro_bias_deg_s"])
    return {"gyro bias": f"[{bias}] deg/s, fitted with W and the field direction; vector RMS "
                         f"{report['vector_rms']:.3g} {unit} (model=gyro)"}


def _box_lines(box) -> dict:
    """The line of a search box that could not be centred on the closed form (:mod:`magexp.calibration.box`)."""
    return {"search box": box.how} if not getattr(box, "centred", True) else {}


def summary(cal) -> dict:
    """The key numbers to print, in order."""
    m, u, r = cal.metrics, cal.unit, cal.report
    return {
        "recording": (f"{cal.recording.path or cal.recording.name} ({cal.recording.n} readings, {u})"
                      if cal.recording is not None else f"{cal.saved['recording']} ({cal.saved['n_readings']} "
                                                        f"readings, {u}; loaded)"),
        "estimator": f"{cal.estimator} ({cal.objective} objective)",
        "model": (r.get("model_selection") or {}).get("why") or r.get("model", ""),
        "gate": _gate_line(r.get("gate") or {}, m),
        "reference": cal.reference.describe(),
        **_onboard_lines(r),
        "spread before": f"{100 * m['spread_before']:.3f} % (std/mean of |raw|, mean {m['mean_before']:.6g} {u})",
        "spread after": f"{100 * m['spread_after']:.3f} % (std/mean of |calibrated|, mean {m['mean_after']:.6g} {u})",
        "rms before": f"{m['rms_before']:.6g} {u} (|raw| - reference)",
        "rms after": f"{m['rms_after']:.6g} {u} (|calibrated| - reference)" + (
            f"; the readings' own noise {m['noise_after']:.6g} {u} (from neighbouring readings)" if m.get("noise_after")
            else ""),
        **summary_lines(r.get("heading")),
        "held-out spread": (f"{100 * m['heldout_spread']:.3f} % ({describe_heldout(m)})" if "heldout_spread" in m
                            else describe_heldout(m)),
        "W": "[" + "; ".join(", ".join(f"{v:.6g}" for v in row) for row in cal.w) + f"] ({r.get('w_form', '')})",
        "W std errors": "[" + "; ".join(", ".join(f"{float(v):.2g}" for v in row) for row in r["W_standard_errors"]) + "]",
        "offset": "[" + ", ".join(f"{v:.6g}" for v in cal.offset) + f"] {u}",
        "offset std errors": "[" + ", ".join(f"{float(v):.2g}" for v in r["offset_standard_errors"]) + f"] {u}",
        **_gyro_lines(r, u),
        "conditioning": f"{float(r['condition_number']):.3g} (column-scaled Jacobian); weakest combination "
                        f"{r['weakest_combinations'][0]['combination']} "
                        f"(relative singular value {r['weakest_combinations'][0]['relative_singular_value']:.2g})",
        "undetermined": ", ".join(r["undetermined"]) or "none",
        "coverage": f"{100 * m['coverage_cells']:.0f} % of {CELLS} sphere cells; smallest direction-scatter "
                    f"eigenvalue {m['coverage_lambda_min']:.3f} (1/3 = full sphere, 0 = plane)",
        "fit": _fit_line(cal.fit, cal.saved),
        **_box_lines(cal.search),
    }
