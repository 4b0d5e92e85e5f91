"""Does an accepted calibration hold on the same sensor's other recordings? (issue 33, the cross-table)

Every calibration ``magexp calibrate`` accepts from an HMC5883L recording of the shared data (each model,
``auto`` included, by ``estimator=ellipsoid``, and ``model=full`` by ``lm``; the default gate and folds) is
applied to the raw readings of every other HMC5883L recording there, and the total-field spread
(std/mean of ``|W (r - o)|``) is set beside the raw spread of that recording. A refused calibration is
listed with the check that refused it.

A recording made at one attitude (``unmoved-10min``) cannot judge a calibration by its spread: its spread is
the sensor's noise and drift, and any ``W`` that is not a scalar times a rotation reshapes them, the true
calibration included. For such a target the table prints beside the calibrated spread the raw scatter carried
through ``W`` (:func:`carried_noise`, first order: ``sqrt(u^T W Σ W^T u) / |W (m - o)|``, ``Σ`` the raw
readings' covariance, ``m`` their mean, ``u`` the unit calibrated mean) and does not count it as worse or
better: the cross-table judges calibrations on the targets that turn. Nothing is written: a table on stdout (Markdown), and with
``--csv PATH`` the long-format rows.

Usage: ``python -m magexp.perf.crosstable [--csv rows.csv]`` (about a minute on one core).
"""

from __future__ import annotations

import argparse
import csv
import sys
import time

import numpy as np

from magexp.calibration.checks import ONE_ATTITUDE_DEG
from magexp.calibration.fit import calibrate_recording
from magexp.run.named import estimator_named
from magexp.core.identifiability import spread
from magexp.core.recordings import load_recording
from magexp.core.seeding import run_generators
from magexp.errors import MagexpError
from magexp.paths import SHARED_DATA

#: the calibrations tried on each recording: (model, estimator)
TRIED = (("auto", "ellipsoid"), ("sphere", "ellipsoid"), ("diagonal", "ellipsoid"), ("full", "ellipsoid"),
         ("full", "lm"), ("gyro", "lm"))


def recordings() -> dict:
    """``{sequence: Recording}`` of every HMC5883L two-stream recording in the shared data."""
    stems = sorted(p.name[: -len("_mag.csv")] for p in SHARED_DATA.glob("hmc5883l_*_mag.csv"))
    return {stem.removeprefix("hmc5883l_"): load_recording(SHARED_DATA / stem) for stem in stems}


def single_attitude(readings: np.ndarray) -> bool:
    """Whether every raw reading lies within :data:`~magexp.calibration.checks.ONE_ATTITUDE_DEG` of their mean
    direction (the sensor did not turn).
    """
    mean = readings.mean(axis=0)
    cosine = readings @ mean / (np.linalg.norm(readings, axis=1) * np.linalg.norm(mean))
    return bool(np.degrees(np.arccos(np.clip(cosine.min(), -1.0, 1.0))) < ONE_ATTITUDE_DEG)


def carried_noise(cal, readings: np.ndarray) -> float:
    """The total-field spread that the raw scatter of a single-attitude recording has once carried through the
    calibration's linear map (first order).
    """
    w = cal.w
    centre = cal.apply(readings.mean(axis=0))
    u = centre / np.linalg.norm(centre)
    return float(np.sqrt(u @ w @ np.cov(readings.T) @ w.T @ u) / np.linalg.norm(centre))


def rows(recs: dict, tried=TRIED, *, seed: int = 0) -> list[dict]:
    """One row per (source recording, model, estimator, target recording): accepted or refused, the
    spread of the target's readings raw and calibrated (spreads as fractions).
    """
    out = []
    for source, rec in recs.items():
        for model, name in tried:
            _, rng = run_generators(seed)
            start = time.process_time()
            try:
                cal = calibrate_recording(rec, estimator_named(name), model=model, rng=rng)
                status, chosen = "accepted", cal.model
            except MagexpError as exc:
                cal, status, chosen = None, "refused: " + str(exc).split(": ", 1)[-1][:90], ""
            cpu = time.process_time() - start
            for target, other in recs.items():
                row = {"source": source, "model": model, "estimator": name, "chosen": chosen, "status": status,
                       "cpu_s": round(cpu, 2), "target": target, "raw": spread(np.linalg.norm(other.readings, axis=1))}
                row["calibrated"] = None if cal is None else spread(np.linalg.norm(cal.apply(other.readings), axis=1))
                row["single_attitude"] = single_attitude(other.readings)
                row["carried_noise"] = (carried_noise(cal, other.readings)
                                        if cal is not None and row["single_attitude"] else None)
                out.append(row)
    return out


def worse(row: dict) -> bool:
    """An accepted calibration's spread on a target that turns exceeds the target's raw spread."""
    return row["calibrated"] is not None and not row["single_attitude"] and row["calibrated"] > row["raw"]


def _cell(row: dict, raw: float) -> str:
    """One cell of :func:`markdown`: the calibrated spread in %, flagged, or beside the carried noise."""
    text = f"{100 * row['calibrated']:.3f}"
    if row["single_attitude"]:
        return f"{text} (noise through W: {100 * row['carried_noise']:.3f})"
    return text + (" **worse**" if worse(row) else "")


def markdown(table: list[dict]) -> str:
    """The recording × recording table: a row per tried calibration, a column per target recording."""
    targets = list(dict.fromkeys(r["target"] for r in table))
    raw = {r["target"]: r["raw"] for r in table}
    lines = ["| source | model (chosen) | estimator | " + " | ".join(targets) + " |",
             "|---|---|---|" + "---|" * len(targets),
             "| raw | | | " + " | ".join(f"{100 * raw[t]:.3f}" for t in targets) + " |"]
    for key in dict.fromkeys((r["source"], r["model"], r["estimator"]) for r in table):
        cells = {r["target"]: r for r in table if (r["source"], r["model"], r["estimator"]) == key}
        first = next(iter(cells.values()))
        label = f"{key[1]} ({first['chosen']})" if key[1] == "auto" and first["chosen"] else key[1]
        if first["calibrated"] is None:
            lines.append(f"| {key[0]} | {label} | {key[2]} | {first['status']} |" + " |" * (len(targets) - 1))
            continue
        values = [_cell(cells[t], raw[t]) for t in targets]
        lines.append(f"| {key[0]} | {label} | {key[2]} | " + " | ".join(values) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Print the table of the shared recordings (and write its rows to ``--csv``)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--csv", help="also write the long-format rows here")
    args = parser.parse_args(argv)
    recs = recordings()
    if not recs:
        print(f"no HMC5883L recordings in {SHARED_DATA}: nothing to measure")
        return 0
    table = rows(recs)
    print(markdown(table))
    bad = [r for r in table if worse(r)]
    print(f"\n{len({(r['source'], r['model'], r['estimator']) for r in table if r['calibrated'] is not None})} "
          f"accepted calibrations; {len(bad)} (calibration, target that turns) cells worse than raw; on a target at "
          "one attitude the spread is its noise carried through W (not judged)")
    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=list(table[0]))
            writer.writeheader()
            writer.writerows(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
