"""Ding 2024's headlines: every reading is sourced, the primary is argued, the exploratory PSO setting decides
nothing, and each sourced PSO reading runs the settings its source states (experiments/ding2024)."""

import re

import pytest

from magexp.artifacts.paper_spec import load_paper
from magexp.artifacts.spec import load
from magexp.paths import EXPERIMENTS

PAPER = load_paper("ding2024")
READINGS = [(h, r) for h in PAPER.headline for r in h.readings]
#: a checkable source: an author and a year, the paper's own words, or magexp's own construction
SOURCED = re.compile(r"[A-Z][a-z]+[^,;:]*\b(19|20)\d\d\b|the paper's own words|magexp's construction")


def _artifact(name: str):
    """The artifact ``name`` of ding2024."""
    return load(EXPERIMENTS / "ding2024" / f"{name}.yaml")


def _settings(artifact, estimator: str) -> dict[str, str]:
    """The overrides (its ``base:`` and case) under which ``artifact`` runs the estimator named ``estimator``:
    a case that names it, else an estimator of its grid or base (no overrides beyond the base)."""
    base = dict(item.lstrip("?").split("=", 1) for item in artifact.base)
    for case in artifact.cases or [[]]:
        pairs = {**base, **dict(item.split("=", 1) for item in case)}
        if pairs.get("estimator.name", pairs.get("estimator")) == estimator:
            return pairs
    if estimator in artifact.grid.get("estimator", []):
        return {**base, "estimator": estimator}
    raise AssertionError(f"{artifact.name}: no case names its estimator {estimator!r}")


def _estimators(part: str) -> set[tuple[str, str]]:
    """(artifact, estimator) of every cell or selection the claim ``part`` reads."""
    stem, claim_id = part.split(".")
    artifact = _artifact(stem)
    claim = next(c for c in artifact.claims if c.id == claim_id)
    selections = list(claim.cells) + ([claim.where] if claim.where else [])
    return {(stem, s["estimator"]) for s in selections if "estimator" in s}


def _reading_estimators(reading) -> dict[str, dict[str, str]]:
    """The case overrides of every estimator the reading's parts run, by estimator name."""
    out = {}
    for part in reading.parts:
        for stem, estimator in _estimators(part):
            out[estimator] = _settings(_artifact(stem), estimator)
    return out


@pytest.mark.parametrize("headline,reading", READINGS, ids=[f"{h.id}:{r.label}" for h, r in READINGS])
def test_every_reading_names_a_checkable_source_and_its_settings(headline, reading):
    assert SOURCED.search(reading.source), reading.source
    assert reading.settings.strip(), f"{headline.id}: {reading.label!r} states no settings"
    assert "to be argued" not in reading.less_plausible


@pytest.mark.parametrize("headline", PAPER.headline, ids=[h.id for h in PAPER.headline])
def test_every_primary_is_argued_from_the_papers_words(headline):
    assert headline.readings, f"{headline.id}: no readings"
    assert "to be argued" not in headline.why
    assert re.search(r"Sec\. \d", headline.why), "the why names no section of the paper"
    assert re.search(r"[\u4e00-\u9fff]", headline.why), "the why quotes none of the paper's own words"


def test_the_exploratory_pso_setting_is_no_reading_and_decides_nothing():
    pso = _artifact("ding2024_ext_pso_readings")
    exploratory = [c for c in pso.claims if "pso_w04" in str(c.cells) + str(c.where)]
    assert exploratory and all(c.role == "exploratory" for c in exploratory)
    for headline, reading in READINGS:
        assert "0.4, c" not in reading.label and "w = 0.4" not in reading.settings
        for name, settings in _reading_estimators(reading).items():
            inertia = {settings.get("estimator.velocity.inertia.start"), settings.get("estimator.velocity.inertia.end")}
            assert inertia != {"0.4"}, f"{headline.id}: {reading.label!r} runs {name} with w = 0.4"


def test_the_decreasing_inertia_pso_is_no_reading_of_the_traditional_pso():
    for headline, reading in READINGS:
        if headline.id not in ("ipso_more_accurate", "ipso_noise_robust"):
            continue
        for settings in _reading_estimators(reading).values():
            if settings.get("estimator") == "pso":  # the traditional PSO: a constant inertia (eq 10)
                assert (settings.get("estimator.velocity.inertia.start")
                        == settings.get("estimator.velocity.inertia.end")), f"{headline.id}: {reading.label!r}"


def test_the_kennedy_eberhart_1995_reading_runs_without_inertia_and_c_2():
    readings = [r for _, r in READINGS if "Kennedy & Eberhart 1995" in r.source]
    assert len(readings) == 2  # the accuracy and the robustness headlines
    for reading in readings:
        runs = _reading_estimators(reading)
        traditional = [s for s in runs.values() if s.get("estimator") == "pso"]
        assert traditional
        for s in traditional:
            assert float(s["estimator.velocity.inertia.start"]) == float(s["estimator.velocity.inertia.end"]) == 1.0
            assert {float(s[f"estimator.velocity.{c}.{e}"]) for c in ("c1", "c2") for e in ("start", "end")} == {2.0}


def test_the_primary_pso_reading_runs_shi_eberhart_1998s_fixed_inertia():
    for hid in ("ipso_more_accurate", "ipso_noise_robust"):
        headline = next(h for h in PAPER.headline if h.id == hid)
        assert headline.primary.startswith("Shi & Eberhart 1998")
        runs = [s for part in headline.primary_parts() for stem, est in _estimators(part)
                for s in [_settings(_artifact(stem), est)] if s.get("estimator") == "pso"]
        assert runs and all(s["estimator.velocity.inertia.start"] == s["estimator.velocity.inertia.end"] == "0.9"
                            and s["estimator.velocity.c1.start"] == "2.0" for s in runs)


def test_every_comparison_of_the_pso_readings_declares_its_effect_and_no_seeds_grow():
    pso = _artifact("ding2024_ext_pso_readings")
    assert not hasattr(pso, "grow") and pso.seeds == 30
    comparisons = [c for c in pso.claims if c.kind in ("ordering", "winner")]
    assert comparisons
    for c in comparisons:
        key = "rise" if c.test == "fisher" else "ratio"
        assert key in c.effect, f"{c.id}: no {key} in its effect"


#: the settings each of IPSO's improvements changes (Sec. 2, items 1-3): its schedule's or its start's keys
IMPROVEMENTS = {"paper_inertia_schedule_helps": {"estimator.velocity.inertia.end"},
                "paper_learning_factors_help": {f"estimator.velocity.{c}.{e}" for c in ("c1", "c2") for e in ("start", "end")},
                "paper_circle_start_avoids_failures": {"estimator"}}


def test_the_ablations_primary_adds_each_improvement_alone_to_the_primary_traditional_pso():
    """improvements_avoid_local_optima is judged where each improvement is the one change made to the
    traditional PSO of the accuracy headline's primary reading (Shi & Eberhart 1998: w = 0.9, c = 2), at
    the 800 iterations of the paper's Fig 3."""
    headline = next(h for h in PAPER.headline if h.id == "improvements_avoid_local_optima")
    parts = headline.primary_parts()
    assert {p.split(".")[1] for p in parts} == set(IMPROVEMENTS)
    for part in parts:
        stem, claim_id = part.split(".")
        artifact = _artifact(stem)
        improved, traditional = (_settings(artifact, cell["estimator"])
                                 for cell in next(c for c in artifact.claims if c.id == claim_id).cells)
        assert traditional["estimator"] == "pso" and traditional["estimator.n_iterations"] == "800"
        assert {traditional[f"estimator.velocity.{k}"] for k in ("inertia.start", "inertia.end")} == {"0.9"}
        assert {traditional[f"estimator.velocity.{c}.{e}"] for c in ("c1", "c2") for e in ("start", "end")} == {"2.0"}
        changed = {k for k in improved.keys() | traditional.keys()
                   if k != "estimator.name" and improved.get(k) != traditional.get(k)}
        assert changed - {"estimator.init.form"} == IMPROVEMENTS[claim_id], f"{claim_id}: changes {sorted(changed)}"
    assert all(r.less_plausible for r in headline.readings if r.label != headline.primary)


@pytest.mark.parametrize("stem", ["ding2024_ext_ablation_se98", "ding2024_ext_ablation", "ding2024_ext_ablation_readings"])
def test_every_comparison_of_the_ablations_declares_its_effect_and_no_seeds_grow(stem):
    artifact = _artifact(stem)
    comparisons = [c for c in artifact.claims if c.kind in ("ordering", "winner")]
    assert not hasattr(artifact, "grow") and comparisons and all("rise" in c.effect for c in comparisons)
