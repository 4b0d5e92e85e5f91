"""magexp beside MAGYC on the same data: ``python -m magexp.perf.peers.bench --out DIR`` (``make peers-bench``).

Writes ``DIR/peers.csv`` (long format: one row per dataset, fit, side, method and measure), ``DIR/peers_summary.csv``
(median and 95 % interval over seeds or folds, :func:`magexp.artifacts.tables.interval`), ``DIR/peers.png`` and ``DIR/peers.md``
(the section's text, every number read from the summary). Without the peer's environment (``make peers``) it
prints one line and writes nothing.

The data (:mod:`.data`), each written to a neutral file and read by both sides:

* MAGYC's generator at its paper's settings, motion levels ``--levels`` (WAM ``high``, MAM ``mid``, LAM ``low``),
  seeds ``0 .. --seeds - 1``: truth known; errors, success (:mod:`.measures`) and time. Both sides on the same
  readings with the same budget (:data:`.magexp_side.LM_NFEV`, the peer's), both ways: every reading to both
  (``fit_on`` ``all``), and magexp's ``--n-fit`` readings to both (``fit_on`` :data:`.magexp_side.SUBSET`,
  :func:`.magexp_side.subset`);
* Yuan 2018's scenarios (:data:`.data.YUAN_SCENARIOS`) as 100 Hz streams, seeds ``0 .. --yuan-seeds - 1``;
* the HMC5883L + MPU6050 sequences (:data:`.data.SEQUENCES`) with the axis map ``aligned``: each method fitted
  on every reading (spread in sample) and on each contiguous half (spread on the other half: held out), its gyro
  bias against the rest recording's mean rate; the full sphere also with the maps ``recorded`` and ``authors``,
  fitted on every reading (a sensitivity check of the axis map); every sequence also *retimed*
  (:func:`.data.recording`: the recorded timestamps are the arrival times of buffered bursts).

The peer runs in one subprocess for all datasets (:func:`.exchange.run_peer`); magexp's methods in this process
(:mod:`.magexp_side`). Work is bounded before it starts: the readings of every dataset are counted and the bench
refuses more than :data:`MAX_READINGS` in all.
"""

from __future__ import annotations

import argparse
import csv
import sys
import tempfile
from pathlib import Path

import numpy as np

from magexp.artifacts.tables import interval
from magexp.errors import MagexpError
from magexp.perf.peers import bound, data, exchange, magexp_side, measures
from magexp.perf.peers.magyc_side import METHODS as PEER_METHODS
from magexp.perf.peers.report import figure, section

#: the peer's methods run by default: all but SAR-KF (30 s per 10,000 readings, a per-reading Python loop) and
#: magFactor3 (it needs attitudes and a reference field: not gyro-aided)
PEER_DEFAULT = tuple(m for m in PEER_METHODS if m != "sar_kf")
#: the readings of all datasets together, at most (each is fitted by about ten methods, three times on a recording)
MAX_READINGS = 2_000_000
#: datasets per peer process (each process compiles MAGYC's jax functions once)
CHUNK = 10
COLUMNS = ("kind", "dataset", "seed", "fit_on", "axis_map", "side", "method", "metric", "value")
FULL_SPHERE_MAPS = ("aligned", "recorded", "authors")


def parse(argv) -> argparse.Namespace:
    """The bench's command-line options."""
    p = argparse.ArgumentParser(prog="python -m magexp.perf.peers.bench", description=__doc__.splitlines()[0])
    p.add_argument("--out", required=True, type=Path, help="folder of peers.csv, peers_summary.csv, peers.png, peers.md")
    p.add_argument("--seeds", type=int, default=5, help="seeds of MAGYC's generator per motion level (5)")
    p.add_argument("--levels", default="high,mid,low", help="MAGYC motion levels (high,mid,low: WAM, MAM, LAM)")
    p.add_argument("--nsamples", type=int, default=6000, help="readings per MAGYC simulation (6000: its paper's)")
    p.add_argument("--yuan-seeds", type=int, default=3, help="seeds per Yuan scenario (3)")
    p.add_argument("--n-fit", type=int, default=magexp_side.N_FIT, help="readings of magexp's gyro-aided fit on Yuan's streams and the recordings, and of the subset of MAGYC's data given to both sides")
    p.add_argument("--magexp", default=",".join(magexp_side.DEFAULT),
                   help=f"magexp's methods (of {', '.join(magexp_side.METHODS)})")
    p.add_argument("--peer", default=",".join(PEER_DEFAULT), help=f"MAGYC's methods (of {', '.join(PEER_METHODS)})")
    p.add_argument("--no-real", action="store_true", help="skip the recordings")
    p.add_argument("--no-notebook", action="store_true",
                   help="skip the second run of the peer on MAGYC's data with its example notebook's preprocessing")
    p.add_argument("--redraw", action="store_true",
                   help="no fits: the summary, figure and text again from OUT/peers.csv (pass the run's --nsamples)")
    p.add_argument("--work", type=Path, default=None,
                   help="keep the neutral files and the peer's answers here (default: a temporary folder)")
    args = p.parse_args(argv)
    for name, value, allowed in (("--magexp", args.magexp, magexp_side.METHODS), ("--peer", args.peer, PEER_METHODS),
                                 ("--levels", args.levels, ("high", "mid", "low", "tiny", "cross"))):
        bad = [v for v in value.split(",") if v not in allowed]
        if bad:
            raise MagexpError(f"{name}={bad[0]!r} is not allowed: choose from {', '.join(allowed)}")
    for name in ("seeds", "nsamples", "yuan_seeds", "n_fit"):
        if getattr(args, name) < (0 if "seeds" in name else 100):
            raise MagexpError(f"--{name.replace('_', '-')}={getattr(args, name)} is not allowed: too small")
    return args


#: the peer's example notebook (``example/20241107_sim_calibration.ipynb`` of its repository): a Savitzky-Golay filter
#: (50 samples, order 2) on the magnetometer and the gyroscope before every method. Run for MAGYC-LS and -NLS only:
#: the notebook also gives MAGYC-BFG and -IFG a measurements window of the sample rate (10 instead of 25), with which
#: one BFG fit of 6,000 readings took 768 s (wall, shared machine): beyond the bench's budget
NOTEBOOK = {"savgol_window": 50, "savgol_order": 2}
NOTEBOOK_METHODS = ("magyc_ls", "magyc_nls")


def notebook_side(ds: exchange.NeutralDataset) -> exchange.NeutralDataset:
    """``ds`` with the sidecar of the peer's example-notebook recipe (:data:`NOTEBOOK`)."""
    side = dict(ds.side, **NOTEBOOK, methods=[m for m in NOTEBOOK_METHODS if m in ds.side["methods"]])
    return exchange.NeutralDataset(ds.t, ds.mag, ds.gyro, side, ds.truth)


def simulated_sets(args, work: Path) -> list[exchange.NeutralDataset]:
    """MAGYC's synthetic datasets and Yuan's streams."""
    levels = args.levels.split(",")
    out = []
    for seed in range(args.seeds):
        for path in exchange.synthesise(work / "magyc", seed, args.nsamples):
            ds = data.with_reference(exchange.read(path))
            if ds.name.removeprefix("magyc_") in levels:
                out.append(ds)
    for scenario in data.YUAN_SCENARIOS:
        out.extend(data.yuan_stream(scenario, seed) for seed in range(args.yuan_seeds))
    return out


def recorded_fits(args) -> list[tuple[exchange.NeutralDataset, exchange.NeutralDataset | None, str]]:
    """``(fit on, held out, fit_on label)`` of every recording, axis map and part."""
    fits = []
    variants = [(m, False) for m in FULL_SPHERE_MAPS] + [(FULL_SPHERE_MAPS[0], True)]
    for seq in data.SEQUENCES:
        for axis_map, retime in variants if seq == "full-sphere" else variants[::3]:
            full = data.recording(seq, axis_map, retime=retime)
            fits.append((full, None, "all"))
            if axis_map != FULL_SPHERE_MAPS[0]:  # the other maps: a sensitivity check, in sample only
                continue
            half = len(full.t) // 2
            first, second = full.part(slice(0, half), "_first"), full.part(slice(half, None), "_second")
            fits += [(data.with_reference(first), second, "first_half"), (data.with_reference(second), first, "second_half")]
    return fits


def jobs_of(args, work: Path) -> list[tuple]:
    """``(dataset, held out, fit_on label, axis map)`` of every fit, each dataset naming the peer's methods; the
    work is counted and bounded (:data:`MAX_READINGS`) first.
    """
    sims = simulated_sets(args, work)
    fits = [] if args.no_real else recorded_fits(args)
    total = sum(len(d.t) for d in sims) + sum(len(f.t) for f, _, _ in fits)
    if total > MAX_READINGS:
        raise MagexpError(f"{total} readings in all is not allowed: at most {MAX_READINGS} (fewer seeds or samples)")
    jobs = [(ds, None, "all", None) for ds in sims]
    jobs += [(magexp_side.subset(ds, args.n_fit), None, magexp_side.SUBSET, None) for ds in sims
             if ds.side["kind"] == "magyc_synthetic"]
    jobs += [(f, h, label, f.side.get("axis_map")) for f, h, label in fits]
    for ds, *_ in jobs:
        ds.side["methods"] = args.peer.split(",")
    return jobs


def answered(datasets: list[exchange.NeutralDataset], work: Path) -> list[dict]:
    """The peer's answer to each of ``datasets``. Files are named by what the answer depends on
    (:func:`.exchange.digest`): a kept work folder (``--work``) keeps the answers, and a dataset whose answer is
    there is not sent again.
    """
    pairs = [(work / "in" / f"{d[:20]}.npz", work / "out" / f"{d[:20]}.json")
             for d in map(exchange.digest, datasets)]
    todo = [k for k, (_, out) in enumerate(pairs) if not out.exists()]
    (work / "out").mkdir(parents=True, exist_ok=True)
    for k in todo:
        exchange.write(datasets[k], pairs[k][0].with_suffix(""))
    print(f"peers: MAGYC on {len(todo)} of {len(pairs)} datasets in processes of {CHUNK}", file=sys.stderr)
    for start in range(0, len(todo), CHUNK):  # chunks: a stopped bench keeps what is done
        exchange.run_peer([pairs[k] for k in todo[start:start + CHUNK]])
    return [exchange.read_answer(out) for _, out in pairs]


def peer_answers(args, jobs: list[tuple], work: Path) -> list[dict]:
    """The peer's answer for every job, computed where ``work`` does not hold it yet; with the example notebook's
    recipe (:data:`NOTEBOOK`) the peer runs once more on its own data and the recordings, those methods named
    ``*_sg`` (not on :data:`.magexp_side.SUBSET`: its 50-sample window is 5 s of the 10 Hz stream, 100 s of readings 2 s apart).
    """
    notebook = [] if args.no_notebook else [(k, notebook_side(ds)) for k, (ds, _, label, _) in enumerate(jobs)
                                            if ds.side["kind"] in ("magyc_synthetic", "recording") and label != magexp_side.SUBSET]
    answers = answered([ds for ds, *_ in jobs] + [ds for _, ds in notebook], work)
    for (k, _), answer in zip(notebook, answers[len(jobs):]):
        answers[k]["results"] += [dict(r, method=r["method"] + "_sg") for r in answer["results"]]
    return answers[:len(jobs)]


def job_rows(args, job: tuple, answer: dict, rests: dict) -> list[dict]:
    """The long rows of one fit: both sides' measures, the raw spread (recordings) or the Cramér-Rao floor
    (simulations).
    """
    ds, held, label, axis_map = job
    estimates = [("magyc", exchange.Estimate.from_peer(r)) for r in answer["results"]]
    n_fit = len(ds.t) if ds.side["kind"] == "magyc_synthetic" else args.n_fit  # MAGYC's data: the peer's readings
    estimates += [("magexp", magexp_side.fit(m, ds, seed=int(ds.side["seed"]), n_fit=n_fit))
                  for m in args.magexp.split(",")]
    base = {"kind": ds.side["kind"], "dataset": ds.name.removesuffix("_first").removesuffix("_second"),
            "seed": ds.side["seed"], "fit_on": label, "axis_map": axis_map or ""}
    rows = []
    if axis_map and label == "all":
        rows.append({**base, "side": "none", "method": "raw", "metric": "spread_in_sample",
                     "value": measures.spread(np.linalg.norm(ds.mag, axis=1))})
    if not axis_map and label == "all":  # the Cramér-Rao floor of the gyro-aided problem on --n-fit readings and on all
        for name, n in (("crb_fit", args.n_fit), ("crb_all", len(ds.t))):
            rows += [{**base, "side": "bound", "method": name, "metric": k, "value": v}
                     for k, v in bound.gyro_floor(ds, n).items()]
    for side_name, est in estimates:
        values = measures.recorded(est, ds, held, rests[axis_map]) if axis_map else measures.simulated(est, ds)
        rows += [{**base, "side": side_name, "method": est.method, "metric": k, "value": v} for k, v in values.items()]
    return rows


def run(args, work: Path) -> list[dict]:
    """Every dataset, both sides: the long-format rows."""
    jobs = jobs_of(args, work)
    answers = peer_answers(args, jobs, work)
    rests = {m: data.rest_bias(m) for m in {j[3] for j in jobs if j[3]}}
    return [row for job, answer in zip(jobs, answers) for row in job_rows(args, job, answer, rests)]


def summarise(rows: list[dict]) -> list[dict]:
    """Mean, median and 95 % interval of the median (:func:`magexp.artifacts.tables.interval`) of every measure over seeds (simulations) or over the
    two held-out halves (recordings), per dataset, axis map and method.
    """
    groups: dict[tuple, list[float]] = {}
    for r in rows:
        fit_on = "halves" if r["fit_on"] in ("first_half", "second_half") else r["fit_on"]
        key = (r["kind"], r["dataset"], r["axis_map"], fit_on, r["side"], r["method"], r["metric"])
        groups.setdefault(key, []).append(float(r["value"]))
    out = []
    for key, values in groups.items():
        v = np.asarray(values, float)
        finite = v[np.isfinite(v)]
        lo, hi = interval(finite, stat="median") if len(finite) > 1 else (float("nan"), float("nan"))
        out.append(dict(zip(("kind", "dataset", "axis_map", "fit_on", "side", "method", "metric"), key),
                        n=len(v), mean=float(np.mean(finite)) if len(finite) else float("nan"),
                        median=float(np.median(finite)) if len(finite) else float("nan"), lo=lo, hi=hi))
    return out


def write_csv(path: Path, rows: list[dict], columns) -> None:
    """Write ``rows`` to ``path`` as CSV with the ``columns`` (floats with 6 significant digits)."""
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(columns), lineterminator="\n")
        writer.writeheader()
        for r in rows:
            writer.writerow({k: (f"{r[k]:.6g}" if isinstance(r[k], float) else r[k]) for k in columns})


def read_rows(path: Path) -> list[dict]:
    """The long rows of a bench's ``peers.csv``."""
    if not path.is_file():
        raise MagexpError(f"--redraw needs {path}: run `make peers-bench` first")
    with open(path, newline="") as fh:
        return [dict(r, value=float(r["value"])) for r in csv.DictReader(fh)]


def measured(args) -> list[dict]:
    """The rows of a bench run, its neutral files and the peer's answers in ``--work`` or a temporary folder."""
    if args.work is not None:
        return run(args, args.work)
    with tempfile.TemporaryDirectory(prefix="magexp-peers-") as tmp:
        return run(args, Path(tmp))


def write(args, rows: list[dict]) -> None:
    """``peers.csv``, ``peers_summary.csv``, ``peers.png`` and ``peers.md`` in ``args.out``; everything after
    ``peers.csv`` is drawn from it as written (rounded), so that ``--redraw`` writes the same bytes.
    """
    args.out.mkdir(parents=True, exist_ok=True)
    write_csv(args.out / "peers.csv", rows, COLUMNS)
    rows = read_rows(args.out / "peers.csv")
    summary = summarise(rows)
    write_csv(args.out / "peers_summary.csv", summary,
              ("kind", "dataset", "axis_map", "fit_on", "side", "method", "metric", "n", "mean", "median", "lo", "hi"))
    figure(summary, args.out / "peers.png")
    (args.out / "peers.md").write_text(section(rows, summary, args))
    print(f"peers: wrote {args.out}/peers.csv, peers_summary.csv, peers.png, peers.md")


def main(argv=None) -> int:
    """Run the bench (or redraw its outputs with ``--redraw``): 0, also when the peer is absent; 2 on a bad value."""
    try:
        args = parse(argv)
        if args.redraw:
            rows = read_rows(args.out / "peers.csv")
            for name, kind in (("seeds", "magyc_synthetic"), ("yuan_seeds", "yuan_stream")):
                setattr(args, name, len({r["seed"] for r in rows if r["kind"] == kind}))
        else:
            reason = exchange.available()
            if reason:
                print(reason)
                return 0
            rows = measured(args)
        write(args, rows)
        return 0
    except MagexpError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
