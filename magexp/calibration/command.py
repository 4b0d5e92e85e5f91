"""The command ``magexp calibrate KEY=VALUE ...`` (= ``python -m magexp.calibration.command``): parse and
check the overrides, compose ``conf/calibrate.yaml`` (its keys, types, defaults and sentences:
:mod:`magexp.calibration.options`), read the recording, run the pipeline
(:func:`magexp.calibration.fit.calibrate_recording`), write the output folder and print the summary.
``--help`` prints :func:`magexp.calibration.options.help_text`.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from omegaconf import OmegaConf

from magexp.calibration import models as models_
from magexp.calibration.export import TARGETS as EXPORT_TARGETS, options_of as export_options_of, render as render_export
from magexp.calibration.firmware import check_counts_nt, check_max_rotation
from magexp.calibration.fit import calibrate_recording, check_flag, numpy_path
from magexp.calibration.folder import recording_files
from magexp.calibration.holdout import check_folds
from magexp.calibration.options import CalibrateOptions, help_text
from magexp.calibration.inputs import Reference, check_reference_total
from magexp.calibration.live import is_live, kept, read_live, settings as live_settings
from magexp.calibration.result import Calibration
from magexp.calibration.write import check_out, summary, table, write
from magexp.core.field_model import check_given, check_model, field_of_recording, place_of
from magexp.core.recording import UNITS, Recording
from magexp.core.datafiles import BAG_MARKER
from magexp.core.readers import by_suffix, detect, names
from magexp.core.geometry import axis_map
from magexp.core.recordings import load_recording, resolve
from magexp.core.seeding import run_generators
from magexp.errors import MagexpError, check_positive_int, exit_code
from magexp.problems.kernels import numpy_only
from magexp.run.files import check_recording_file
from magexp.run.compose import GROUPS, check_choice, compose_config, options
from magexp.run.folders import check_destination
from magexp.run.overrides import check_hydra_keys, check_override_targets, check_override_values
from magexp.run.values import check_run_values
from magexp.run.keys import check_duplicates, check_schema, check_seed
from magexp.run.runner import build


def calibrate_config(argv: list[str]):
    """The config of ``conf/calibrate.yaml`` with the ``KEY=VALUE`` overrides ``argv``, composed as every
    command's config is (:func:`magexp.run.compose.compose_config`)."""
    bad = [a for a in argv if "=" not in a]
    if bad:
        raise MagexpError(f"argument {bad[0]!r} is not allowed: magexp calibrate takes KEY=VALUE overrides "
                          "(e.g. data.path=mine.csv data.unit=uT estimator=lm)")
    check_duplicates(argv)
    check_hydra_keys(argv)
    check_override_targets(argv)  # no code from an override, before the recording is read
    argv = check_override_values(argv)
    for arg in argv:
        if arg.partition("=")[0] in GROUPS:
            check_choice(*arg.split("=", 1))
        elif arg.partition("=")[0] == "out" and not arg.partition("=")[2].strip():  # refused as a folder, not a text
            check_destination("", "out")
    cfg = compose_config(argv, config_name="calibrate")
    check_run_values({"estimator": OmegaConf.to_container(cfg.estimator, resolve=True)})  # its numbers, as a run's
    return cfg


def field_keys(cfg) -> dict:
    """``field.*`` of ``cfg``, with the older ``igrf.*`` keys as aliases (``field.model=igrf``)."""
    place = {k: v for k, v in dict(cfg.get("field") or {}).items()}
    old = {k: v for k, v in dict(cfg.get("igrf") or {}).items() if v is not None and k != "altitude_km"}
    if old:
        if place.get("latitude") is not None:
            raise MagexpError(f"igrf.latitude={old.get('latitude')!r} is not allowed with field.latitude: igrf.* is "
                              "the older name of field.* (with field.model=igrf), give field.* only")
        place.update(dict(cfg.igrf), model="igrf")
    check_model(place.get("model"))  # a bad model named even when no place asks for one
    check_given({**dict(cfg.get("igrf") or {}), "model": "igrf"}, "igrf")
    check_given(place)
    return place


def reference_from_field(cfg, rec: Recording) -> Reference | None:
    """The field model's total where and when ``rec`` was recorded (:mod:`magexp.core.field_model`):
    ``field.latitude/longitude/altitude_km/date`` (each, if not given, from the log's GPS), or None
    when neither the command line nor the log gives a place. In the recording's unit; a raw-count
    recording is calibrated to the model's total in nT (``W`` then maps counts to nT)."""
    place = field_keys(cfg)
    given = unplaced(place, place_of(rec))
    if given:
        raise MagexpError(f"{given} is not allowed without a place: give field.latitude and field.longitude "
                          f"({rec.path.name} has no GPS place)")
    if place.get("latitude") is None and not {"latitude", "date"} <= set(place_of(rec)):
        return None
    ref = field_of_recording(rec, model=place.get("model") or "igrf", latitude=place.get("latitude"),
                             longitude=place.get("longitude"), altitude_km=place.get("altitude_km"),
                             date=place.get("date"), prefix="field")
    unit = rec.unit if rec.unit in UNITS else "nT"
    inputs = ref.record()
    where = f"{ref.generation} at {inputs['latitude']:g}, {inputs['longitude']:g}, {inputs['date']}"
    return Reference(np.full(rec.n, ref.total / UNITS[unit]), where, unit=None if unit == rec.unit else unit,
                     record=inputs)


def run(cfg, *, live: bool = False) -> Calibration:
    """Load, calibrate, check and write as ``cfg`` says; print the summary."""
    data = cfg.data
    check_options(cfg)
    rec = recording_of(cfg)
    out = cfg.get("out")
    out_dir = Path(f"calibration_{rec.path.stem}") if out is None else Path(str(out))
    check_destination(out_dir if out is None else out, "out")
    overwrite, draw = flag(cfg, "overwrite"), flag(cfg, "figure")
    target, options = export_of(cfg, rec)
    protected = [] if live else recording_files(rec)
    check_out(out_dir, overwrite=overwrite, export=target, draw=draw, recording=protected)
    estimator = build(cfg.estimator, f"estimator {cfg.estimator.get('name')!r}")
    seed = check_seed(cfg.seed)
    _, est_rng = run_generators(seed)
    reference = data.get("reference_total")
    if reference is None:
        reference = reference_from_field(cfg, rec)
    with numpy_only(numpy_path(None, estimator)):
        cal = calibrate_recording(rec, estimator, objective=cfg.objective, reference_total=reference,
                                  folds=cfg.folds, rng=est_rng, model=cfg.model, accept=flag(cfg, "accept"),
                                  gate_overrides=cfg.get("gate"), auto_margin=cfg.get("auto_margin", models_.MARGIN))
    cal.seed, cal.config = seed, OmegaConf.to_container(cfg, resolve=True)
    paths = write(cal, out_dir, draw=draw, overwrite=overwrite, export=target, export_options=options,
                  recording=protected)
    print(table({**summary(cal), "written to": ", ".join(str(p) for p in paths.values())
                 + (" (replacing the earlier calibration's files: overwrite=true)" if overwrite else "")
                 + ("" if draw else "; no figure (figure=true draws it)"),
                 **({"removed": ", ".join(str(p) for p in paths.removed) + " (the earlier calibration's, not written "
                                "by this one)"} if paths.removed else {})}))
    return cal


def check_options(cfg) -> None:
    """The keys that a run may not use checked before anything is read: every given ``field.*`` and
    ``igrf.*`` value (used only when a place is known, and not at all beside ``data.reference_total``),
    ``counts_nt`` and ``max_rotation_deg`` (used only by some exports), ``auto_margin`` (only by
    ``model=auto``), ``live.*`` (only by a live stream), ``folds``, ``data.reference_total``: a bad value is
    refused in one line, not ignored. Then every key against its schema
    (:func:`magexp.run.keys.check_schema`: type, number range, non-empty text, a pair's length)."""
    field_keys(cfg)
    if cfg.get("counts_nt") is not None:
        check_counts_nt(cfg.counts_nt)
    if cfg.get("max_rotation_deg") is not None:
        check_max_rotation(cfg.max_rotation_deg)
    models_.check_margin(cfg.get("auto_margin", models_.MARGIN))
    live_settings(cfg)  # live.*, data.serial and data.baud, used only by a live stream
    check_folds(cfg.get("folds"))
    if cfg.data.get("reference_total") is not None:
        check_reference_total(cfg.data.reference_total)
    # then every key by its type, after the checks above that name a key's range
    check_schema(OmegaConf.to_container(cfg, resolve=True), CalibrateOptions)


def recording_of(cfg) -> Recording:
    """The recording ``data.*`` names (its size checked before it is read; ``instance``: a DataFlash log's compass)."""
    data = cfg.data
    if data.get("path") is None or not str(data.path).strip():
        raise MagexpError(f"data.path={data.get('path')!r} is not allowed: give data.path=<recording file>")
    file = resolve(data.path)
    check_data_options(cfg, file)  # its format and options, before the file is opened
    check_recording_file(file, format=data.get("format") or "auto")  # the file gate, before it is read
    instance = cfg.get("instance")
    instance = None if instance is None else check_positive_int(instance, "instance", minimum=0)
    return load_recording(data.path, unit=data.get("unit"), format=data.get("format") or "auto",
                          mag_axes=data.get("mag_axes"), gyro_axes=data.get("gyro_axes"), instance=instance)


#: the formats whose logs may carry a GPS place and date (:func:`magexp.core.field_model.place_of`)
GPS_FORMATS = ("ulog", "dataflash", "rosbag")


def unplaced(place: dict, known: dict | None = None) -> str | None:
    """The first ``field.*`` key given (``longitude``, ``altitude_km``, ``date``) when no latitude is, neither in
    ``place`` nor in ``known`` (a log's GPS), else None: a field model needs a place."""
    if place.get("latitude") is not None or (known or {}).get("latitude") is not None:
        return None
    given = [f"field.{k}={place[k]!r}" for k in ("longitude", "altitude_km", "date") if place.get(k) is not None]
    return given[0] if given else None


def check_data_options(cfg, file: Path) -> None:
    """``data.*`` and ``field.*`` checked before the recording ``file`` is read: ``data.format`` a format of
    :mod:`magexp.core.readers` (``rosbag``: a bag's file or folder), the axis maps, and a field
    model's date or longitude only with a place (a recording of a format that cannot carry a GPS place)."""
    data, fmt = cfg.data, cfg.data.get("format") or "auto"
    if fmt not in ("auto", *names()):
        raise MagexpError(f"data.format={fmt!r} is not allowed: choose one of auto, {', '.join(names())}")
    bag = by_suffix(file) == "rosbag" or (file / BAG_MARKER).is_file()
    if fmt == "rosbag" and not bag:
        raise MagexpError(f"data.format='rosbag' is not allowed for {file.name!r}: a ROS bag is a .bag, .mcap or .db3 "
                          "file or a ROS 2 bag folder (with metadata.yaml); set data.format to the file's format")
    for key in ("mag_axes", "gyro_axes"):
        axis_map(data.get(key), f"data.{key}")
    given = None if data.get("reference_total") is not None else unplaced(field_keys(cfg))
    if given and (fmt if fmt != "auto" else detect(file)) not in GPS_FORMATS:
        raise MagexpError(f"{given} is not allowed without a place: give field.latitude and field.longitude (a "
                          f"{file.suffix or 'text'} recording has no GPS to give them)")


def export_of(cfg, rec: Recording) -> tuple[str | None, dict | None]:
    """``(target, options)`` of ``export=<target>`` (``(None, None)`` without one), checked before the fit:
    the target's name, and its options on an identity calibration (``counts_nt`` for raw counts, the
    rotation limit, the slot: :func:`export_options`)."""
    target = cfg.get("export")
    if target is None:
        return None, None
    if str(target) not in EXPORT_TARGETS:
        raise MagexpError(f"export={target!r} is not allowed: choose one of {', '.join(EXPORT_TARGETS)} (or null)")
    options = export_options(cfg, str(target), rec)
    render_export(str(target), np.eye(3), np.zeros(3), rec.unit, **options)
    return str(target), options


def export_options(cfg, target: str, rec: Recording) -> dict:
    """The options of ``export=<target>`` from the command line (those the target takes,
    :func:`magexp.calibration.export.options_of`): ``counts_nt``, ``max_rotation_deg`` and ``instance``, the
    parameter slot (null: a ULog's calibration slot, else 0; a DataFlash log's instance is the one read)."""
    slot = cfg.get("instance")
    given = {"counts_nt": cfg.get("counts_nt"), "max_rotation_deg": cfg.get("max_rotation_deg"),
             "instance": int(rec.meta.get("calibration_slot", 0)) if slot is None else slot}
    return {k: v for k, v in given.items() if v is not None and k in export_options_of(target)}


def flag(cfg, key: str) -> bool:
    """A true/false key of ``cfg`` (default false), else one line."""
    return check_flag(cfg.get(key, False), key)




def command(argv: list[str]) -> None:
    """``magexp calibrate KEY=VALUE ...``: compose, check, calibrate, write; errors are raised (the
    one error path, :func:`magexp.errors.guarded`, turns them into one line and an exit code).
    ``--help`` (``-h``) prints :func:`help_text`."""
    if any(a in ("--help", "-h") for a in argv):
        print(help_text(options("estimator")))
        return
    cfg = calibrate_config(argv)
    if is_live(cfg):  # a serial port or standard input (magexp.calibration.live): read it, then calibrate what was read
        check_options(cfg)  # and what run() checks later, before the stream is read
        for key in ("overwrite", "figure", "accept"):
            flag(cfg, key)
        models_.check_model(cfg.model, cfg.objective)  # the name (the stream's gyroscope is known once it is read)
        build(cfg.estimator, f"estimator {cfg.estimator.get('name')!r}")
        cfg = read_live(cfg, calibrate_recording)
        with kept(cfg.data.path):
            run(cfg, live=True)
        return
    run(cfg)


def main(argv: list[str] | None = None) -> int:
    """``python -m magexp.calibration.command KEY=VALUE ...`` (= ``magexp calibrate``): 0 on success; one
    line on stderr and exit 2 on bad input or degenerate data (nothing written), 3 on a bug."""
    return exit_code(command, sys.argv[1:] if argv is None else list(argv))


if __name__ == "__main__":
    sys.exit(main())
