"""Yan 2022's step of convergence as a censored time-to-event, its readings, and one voice per metric."""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest
from hydra.utils import instantiate

from magexp.artifacts.censoring import cell_quartiles, censor_row, censored_statistic
from magexp.artifacts.claims import Claim, evaluate, interpolate
from magexp.artifacts.selection import values
from magexp.artifacts.paper_spec import artifact_paths, load_paper
from magexp.artifacts.spec import load
from magexp.estimators.kalman import observed_step
from magexp.problems import make_problem

PAPER = "yan2022"


def _fit(make_cfg, *overrides, seed=0):
    cfg = make_cfg("scenario=yan2022_sim", "estimator=kf", *overrides)
    scenario = instantiate(cfg.scenario, _convert_="all")
    problem = make_problem(scenario.objective, scenario.generate(rng=np.random.default_rng(seed)), scenario.search)
    return instantiate(cfg.estimator, _convert_="all").fit(problem, rng=None)


# -- the estimator: a step is observed only when the state stayed within tolerance as long again ------------
def test_observed_step_is_censored_past_half_the_horizon():
    assert observed_step(300.0, 600) == (300.0, 0.0)
    assert observed_step(301.0, 600) == (pytest.approx(np.nan, nan_ok=True), 300.0)
    assert observed_step(np.nan, 600)[1] == 300.0  # apart at the horizon: censored too


def test_an_observed_step_does_not_move_with_a_longer_horizon(make_cfg):
    # magexp's P(0) at 1e-4 / 1 nT: at 600 steps every seed is censored (the state is still swinging
    # in and out of tolerance); an observed step at 2400 is the same at 9600
    for seed in range(3):
        short = _fit(make_cfg, "estimator.horizon=600", seed=seed).metrics
        assert np.isnan(short["steps_to_ls_every_step"]) and short["steps_to_ls_every_step_censored"] == 300
        mid = _fit(make_cfg, "estimator.horizon=2400", seed=seed).metrics
        long = _fit(make_cfg, "estimator.horizon=9600", seed=seed).metrics
        assert np.isfinite(long["steps_to_ls_every_step"]) and long["steps_to_ls_every_step_censored"] == 0
        if np.isfinite(mid["steps_to_ls_every_step"]):
            assert mid["steps_to_ls_every_step"] == long["steps_to_ls_every_step"]


def test_the_horizon_leaves_the_estimate_at_n_steps(make_cfg):
    plain, watched = _fit(make_cfg), _fit(make_cfg, "estimator.horizon=2400")
    np.testing.assert_array_equal(plain.x, watched.x)
    assert watched.trace["x"].shape == (601, 12) and len(watched.history) == 601 and watched.nit == 600


# -- statistics and prose never report a median of the observed steps alone -------------------------
def _runs(steps, censored_at=4800.0) -> pd.DataFrame:
    steps = np.asarray(steps, float)
    return pd.DataFrame({"cell": 0, "seed": range(len(steps)), "estimator": "kf", "setting": "scenario=x",
                         "steps": steps, "steps_censored": np.where(np.isnan(steps), censored_at, 0.0)})


def test_a_censored_median_is_printed_as_censored_never_as_the_observed_median():
    runs = _runs([100, 200, np.nan, np.nan, np.nan])
    assert interpolate("{median:steps@estimator=kf:.0f}", runs) == "> 4800 (censored in 3 of 5 seeds)"
    assert interpolate("{min:steps@estimator=kf:.0f}", runs) == "100"
    assert interpolate("{max:steps@estimator=kf:.0f}", runs).startswith("> 4800")


def test_a_median_among_the_observed_steps_is_exact():
    runs = _runs([100, 200, 300, np.nan, np.nan])  # censored values exceed every observed one
    assert interpolate("{median:steps@estimator=kf:.0f}", runs) == "300"
    assert censored_statistic(values(runs, "steps", "median"), "mean") == np.inf
    q = cell_quartiles(runs, "steps")
    assert q["median"] == 300 and q["q75"] == np.inf and q["n_censored"] == 2 and q["censor_point"] == 4800


def test_a_threshold_on_a_censored_median_does_not_hold_and_says_so():
    runs = _runs([100, np.nan, np.nan])
    claim = Claim(id="c", text="", kind="threshold", metric="steps", stat="median", where={"estimator": "kf"},
                  op=">=", value=1.0)
    out = evaluate(claim, runs)
    assert not out.holds and "censored" in out.evidence
    by_300 = Claim(id="b", text="", kind="threshold", metric="steps <= 300", stat="min", where={"estimator": "kf"},
                   op=">=", value=1)
    assert not evaluate(by_300, runs).holds  # a censored step is later than 300, not dropped


def test_a_summary_row_of_a_censored_metric_counts_every_seed():
    runs = _runs([100, 200, np.nan, np.nan, np.nan])
    row = censor_row({"value": 150.0, "judged_value": 150.0, "n_seeds": 2, "reason": ""}, runs, "steps")
    assert row["value"] == np.inf and row["judged_value"] == np.inf and row["n_seeds"] == 5
    assert "3 of 5 seeds censored" in row["reason"] and np.isnan(row["lo"])
    plain = {"value": 150.0}
    assert censor_row(plain, _runs([100, 200]), "steps") is plain


# -- the paper's readings: sourced, argued, no placeholder ----------------------------------------------
def test_every_yan_reading_is_sourced_and_every_primary_argued():
    paper = load_paper(PAPER)
    with_readings = [h for h in paper.headline if h.readings]
    assert {h.id for h in with_readings} >= {"simulation_accuracy", "convergence_300", "mockup_parameters",
                                             "field_computed_precisely"}
    for h in with_readings:
        assert "to be argued" not in h.why and re.search(r"Sec\. \d", h.why) and '"' in h.why, h.id
        for r in h.readings:
            source = str(r.source)
            assert (re.search(r"\b(19|20)\d\d\b", source) or "the paper's own" in source
                    or "magexp's construction" in source), (h.id, r.label)
            assert str(r.settings).strip(), (h.id, r.label)
            assert "Ding" not in source and "numbers point" not in source, (h.id, r.label)  # no borrowed fit
            if r.label != h.primary:
                assert str(r.less_plausible).strip() and "to be argued" not in r.less_plausible, (h.id, r.label)


# -- one voice: no sanity check reads a quantity an open headline judges ---------------------------------
# A sanity check holds by construction; a quantity a headline judges as an open question (not one that
# holds ``construction``) is not settled by construction, so a sanity check on it could only repeat the
# headline or contradict it (as "every seed converges by step 300" once did beside convergence_300).
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def _claims() -> dict:
    """Every claim of the paper's artifacts by ``<artifact>.<id>``, with the quantities it reads."""
    return {f"{spec.name}.{c.id}": (c, _quantities(spec, c)) for spec in map(load, artifact_paths(PAPER))
            for c in spec.claims}


def _quantities(spec, claim) -> set:
    """``(column, estimator, data)`` of every runs column the claim's metric reads: the estimator its
    ``where`` or its artifact's base selects (``*``: any of the artifact's), and the data its ``where``
    selects (its ``scenario*`` items: another noise level is another quantity)."""
    where = dict(claim.where)
    base = [str(o).split("=", 1)[1] for o in spec.base if str(o).startswith("estimator=")]
    estimator = str(where.get("estimator", base[0] if base else "*"))
    data = frozenset((k, str(v)) for k, v in where.items() if k.startswith("scenario"))
    columns = set(_NAME.findall(str(claim.metric))) - {"sqrt", "abs", "log", "log10", "exp"}
    return {(column, estimator, data) for column in columns}


def _same(a: set, b: set) -> set:
    """The quantities of ``a`` that ``b`` reads too (``*`` matches any estimator)."""
    return {(c, e, d) for c, e, d in a for c2, e2, d2 in b if c == c2 and d == d2 and (e == e2 or "*" in (e, e2))}


def test_no_yan_sanity_check_reads_a_metric_an_open_headline_judges():
    claims, paper = _claims(), load_paper(PAPER)
    judged = {}
    for h in (h for h in paper.headline if not str(h.construction).strip()):
        for part in list(h.parts) + [p for r in h.readings for p in r.parts]:
            judged.update({q: h.id for q in claims[part][1]})
    for name, (claim, quantities) in claims.items():
        if claim.role == "sanity":
            shared = _same(quantities, set(judged))
            assert not shared, f"sanity check {name} reads {shared}, which a headline judges"


def test_yan_statements_on_the_step_of_convergence_are_the_headline_s_own():
    # the step of convergence is judged once: every claim that reads it is a part of convergence_300
    claims, paper = _claims(), load_paper(PAPER)
    head = next(h for h in paper.headline if h.id == "convergence_300")
    parts = set(head.parts) | {p for r in head.readings for p in r.parts}
    readers = {n for n, (_, q) in claims.items() if {c for c, _, _ in q} & {"steps_to_ls", "steps_to_ls_every_step"}}
    assert readers and readers <= parts, readers - parts
