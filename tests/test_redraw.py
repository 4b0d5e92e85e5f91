"""Committed results are the code's (issue 39, part 12): ``--redraw`` rebuilds, from the CSVs a
reproduction wrote, exactly the bytes it wrote, and every number of ``summary.csv`` recomputes from the
runs CSV it names."""

import shutil
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from magexp.artifacts import reproduce
from magexp.artifacts.formats import tidy
from magexp.artifacts.plan import ArtifactRuns
from magexp.artifacts.spec import load, parse
from magexp.paths import EXPERIMENTS, RESULTS

#: a cheap artifact whose medians are of two seeds: a median computed before the runs CSV rounds them
#: differs from the one a reader (and ``--redraw``) computes from the CSV in the 6th digit
SMALL = ("yan2022", "--only", "yan2022_fig_noise", "--tiny", "--seeds", "2", "--jobs", "1")


def files_of(root: Path) -> dict[str, bytes]:
    """``{relative path: bytes}`` of every file under ``root``."""
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


@pytest.mark.full  # make test: test_reproduce.py::test_redraw_rebuilds_figures_summary_and_report_without_a_run
def test_redraw_rewrites_to_the_byte_what_a_reproduction_wrote(tmp_path):
    """A reproduction, then ``--redraw --force`` of a copy of what it wrote (every figure drawn again,
    every summary row recomputed from the CSVs, the report rebuilt): no file differs, none is added."""
    out, copy = tmp_path / "out", tmp_path / "copy"
    assert reproduce.main([*SMALL, "--out", str(out)]) == 0
    shutil.copytree(out, copy)
    assert reproduce.main([*SMALL[:3], "--redraw", "--force", "--out", str(copy)]) == 0
    wrote, redrawn = files_of(out), files_of(copy)
    assert {"summary.csv", "REPORT.md", "yan2022/summary.csv", "yan2022/yan2022_fig_noise.png"} <= set(wrote)
    assert sorted(redrawn) == sorted(wrote)
    assert [name for name in wrote if redrawn[name] != wrote[name]] == []


def test_a_ratio_over_round_off_is_the_ratio_of_the_runs_csv(tmp_path):
    """PSO at 360-400 nT over IPSO at 1e-12-3e-12 nT (round-off, which the runs CSV writes as its floor
    1e-9): the summary's ratio is the median of the ratios of the runs CSV (3.6e11), not that of the
    unrounded runs (1.8e14, which no file shows), and so is its interval."""
    spec = parse({"kind": "final", "title": "t", "seeds": 3, "plot": {"x": "scenario.noise"},
                  "ratios": [{"quantity": "r", "metric": "q", "numerator": {"estimator": "pso"},
                              "denominator": {"estimator": "ipso"}}]}, Path("p") / "a.yaml")
    values = {"pso": [360.0, 400.0, 350.0], "ipso": [2e-12, 1e-12, 3e-12]}
    table = pd.DataFrame([{"cell": ci, "seed": s, "estimator": est, "scenario.noise": "0", "objective": "scalar",
                           "setting": "s", "q": v} for ci, est in enumerate(values) for s, v in enumerate(values[est])])
    stored = SimpleNamespace(parameter_names=[], x=np.array([]), truth_x=None, lower=None, upper=None, design=None)
    runs = ArtifactRuns(spec=spec, cells=[{"estimator": e, "scenario.noise": "0"} for e in values], table=table,
                        outputs={(ci, s): stored for ci in range(2) for s in range(3)},
                        overrides=[[f"estimator={e}", "scenario.noise=0"] for e in values])
    row = reproduce.write_artifact(runs, tmp_path).set_index("quantity").loc["r"]
    written = pd.read_csv(tmp_path / "a_runs.csv")
    assert written[written.estimator == "ipso"].q.tolist() == [1e-9] * 3
    ratios = written[written.estimator == "pso"].q.to_numpy() / written[written.estimator == "ipso"].q.to_numpy()
    assert row.value == pytest.approx(np.median(ratios), rel=1e-12) == 3.6e11
    assert ratios.min() <= row.lo <= row.hi <= ratios.max()


def runs_of(spec, row, runs: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """Per seed, the value a summary ``row`` of ``spec`` summarises and whether that run succeeded (NaN:
    not judged), read from the artifact's runs CSV ``runs``: the runs of its estimator and setting, or
    for a ratio (``;reference=``) the per-seed ratio of the reference's runs over them."""
    setting, _, reference = row.setting.partition(";reference=")
    den = runs[(runs.estimator == row.estimator) & (runs.setting == setting)].set_index("seed")
    assert den.cell.nunique() == 1, (spec.name, row.setting)
    ok = den.succeeded if "succeeded" in den else pd.Series(np.nan, den.index)
    if not reference:
        item = next(i for i in spec.summarise if i.quantity == row.quantity)
        v = den[item.metric].to_numpy(float)
        censored = f"{item.metric}_censored"  # a step never observed within the horizon counts as beyond it
        if censored in den:
            v = np.where(den[censored].to_numpy(float) > 0, np.inf, v)
        return v, ok.to_numpy(float)
    item = next(r for r in spec.ratios if r.quantity == row.quantity)
    key, _, value = reference.partition("=")
    num = runs[(runs[key].astype(str) == value) & (runs.setting == setting)].set_index("seed")
    assert num.cell.nunique() == 1, (spec.name, row.setting)
    ratio = (num[item.metric].astype(float) / den[item.metric].astype(float)).dropna()
    both = (num.succeeded * den.succeeded).reindex(ratio.index) if "succeeded" in den else ok.reindex(ratio.index)
    return ratio.to_numpy(float), both.to_numpy(float)


def as_written(x: float) -> float:
    """``x`` as a results CSV writes it (6 significant digits, round-off floored)."""
    return float(tidy(pd.DataFrame({"x": [float(x)]})).x.iloc[0])


#: how a row names the runs its verdict was judged on, and which outcome they have (None: all of them)
JUDGED = {"all seeds": None, "successful seeds": 1.0, "failed seeds": 0.0}


def recomputed_rows(paper: str) -> list[tuple]:
    """``(artifact, quantity, setting, column, summary's number, the number from the runs CSV)`` for each
    median row of ``paper`` in ``results/summary.csv`` (a value or a ratio over seeds: not a parameter,
    least-squares, F-test, mean or fixed-tolerance row)."""
    summary = pd.read_csv(RESULTS / "summary.csv", keep_default_na=False, na_values=[""])
    out = []
    for name, rows in summary[summary.paper == paper].groupby("artifact", sort=False):
        spec = load(EXPERIMENTS / paper / f"{name}.yaml")
        medians = {i.quantity for i in spec.summarise if i.mode == "value" and i.interval == "seeds"
                   and i.aggregate == "median"} | {r.quantity for r in spec.ratios}
        runs = pd.read_csv(RESULTS / paper / f"{name}_runs.csv")
        for row in rows[rows.quantity.isin(medians) & rows.judged_runs.isin(list(JUDGED))].itertuples():
            v, ok = runs_of(spec, row, runs)
            finite = ~np.isnan(v)  # a censored step (+inf) is a seed of the row
            outcome = JUDGED[row.judged_runs]
            judged = v[finite & (ok == outcome)] if outcome is not None else v[finite]
            numbers = {"n_seeds": finite.sum(), "value": np.median(v[finite]), "judged_n": judged.size,
                       "judged_value": np.median(judged)}
            if np.isfinite(ok).any():
                numbers["success_rate"] = np.nanmean(ok)
            out += [(name, row.quantity, row.setting, col, getattr(row, col), as_written(x))
                    for col, x in numbers.items()]
    return out


@pytest.mark.parametrize("paper", [pytest.param(p, marks=pytest.mark.full) for p in ("ding2024", "yuan2018", "yan2022")]
                         + ["real"])  # benchmark: no summary row; make test: the cheapest paper
def test_every_summary_median_recomputes_from_the_runs_csv_it_names(paper):
    """Each median row of the committed ``summary.csv`` (the ratios included: Ding's PSO/IPSO ratio at
    A = 0 divides by the round-off floor the runs CSV writes) against the same number recomputed with
    numpy from the runs CSV of its artifact: its seeds, its value, the runs it was judged on and their
    median, its success rate."""
    found = recomputed_rows(paper)
    assert len(found) > 20
    if paper == "ding2024":
        assert sum(1 for f in found if f[1] == "improvement_ratio") >= 8 * 5
    assert [f for f in found if not f[4] == f[5]] == []
