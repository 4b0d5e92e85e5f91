"""Yuan 2018's headlines: every reading sourced and argued, and the universal claim judged on every instance."""

import itertools
import re

from magexp.artifacts.paper_spec import load_paper
from magexp.artifacts.spec import load
from magexp.paths import EXPERIMENTS

PAPER = load_paper("yuan2018")
#: a checkable source: an author and year, the paper's own words with their section, or magexp's construction
CHECKABLE = re.compile(r"\b[A-Z][a-z]+( (et al\.|& [A-Z][a-z]+))? (19|20)\d\d\b|the paper's own words \((Sec\.|Abstract)"
                       r"|^magexp's construction")


def _claim(part: str):
    """The claim ``<artifact>.<id>`` of Yuan 2018."""
    stem, cid = part.split(".")
    return next(c for c in load(EXPERIMENTS / "yuan2018" / f"{stem}.yaml").claims if c.id == cid)


def test_every_reading_is_sourced_argued_and_no_placeholder_is_left():
    text = (EXPERIMENTS / "yuan2018" / "paper.yaml").read_text()
    assert "(to be argued" not in text
    for h in PAPER.headline:
        for r in h.readings:
            assert CHECKABLE.search(r.source), (h.id, r.label, r.source)
            assert r.settings.strip(), (h.id, r.label)
        if h.readings:
            assert re.search(r"Sec\. \d|Table \d|eq \d|Abstract", h.why), h.id  # the why quotes where the paper says it


def test_no_reading_is_exploratory():
    """A setting chosen because its runs resemble the paper's numbers (1 mG of noise) is exploratory: its
    claims are role: exploratory and no headline reading rests on them."""
    parts = {p for h in PAPER.headline for r in h.readings for p in r.parts} | {p for h in PAPER.headline for p in h.parts}
    for part in parts:
        assert _claim(part).role != "exploratory", part
    assert all("point to" not in r.source for h in PAPER.headline for r in h.readings)
    for stem in ("yuan2018_ext_noise_readings",):
        assert {c.role for c in load(EXPERIMENTS / "yuan2018" / f"{stem}.yaml").claims} == {"exploratory"}


def test_two_partial_turns_primary_covers_every_pair_and_arc():
    """"Incomplete rotation around any two axes": the primary reading's parts are every (pair, arc) instance,
    S and b each, so one failing instance makes the headline partly at best."""
    h = next(h for h in PAPER.headline if h.id == "two_partial_turns")
    pairs = {"yuan2018_mode3": "xy", "yuan2018_mode3_xz": "xz", "yuan2018_mode3_yz": "yz"}
    seen = set()
    for part in h.primary_parts():
        c = _claim(part)
        if c.where.get("estimator") == "rdpso":
            seen.add((pairs[c.where["scenario"]], float(c.where["scenario.rotation.partial_arc_deg"]), c.metric))
    want = set(itertools.product(("xy", "xz", "yz"), (90.0, 180.0, 270.0), ("param_matrix_error", "param_offset_error")))
    assert seen == want
    assert "yuan2018_table3.mode4_fails" in h.primary_parts()


def test_every_yuan_comparison_declares_its_effect():
    for path in sorted((EXPERIMENTS / "yuan2018").glob("yuan2018_*.yaml")):
        for c in load(path).claims:
            if c.kind in ("ordering", "winner") and c.role == "finding":
                assert set(c.effect) in ({"rise", "baseline"}, {"ratio", "spread"}), (path.stem, c.id)
                if c.stat == "success_rate":
                    assert set(c.effect) == {"rise", "baseline"}, (path.stem, c.id)


def test_the_optimum_of_eq_8_is_judged_by_what_the_readings_identify():
    """At 90 degrees the Cramer-Rao bound of b is near 1 mG: the optimum of eq 8 is judged by magexp's rule for
    an estimator at the bound, fixed before these runs (benchmark_heatmap's lm_vector_yuan), not by the
    paper's 1 mG; RDPSO's miss is attributed to the optimiser by a paired comparison with the optimum on the
    same readings of every 90-degree instance, each with its effect; the headline does not say "not the data"."""
    turns = {c.id: c for c in load(EXPERIMENTS / "yuan2018" / "yuan2018_ext_turns.yaml").claims}
    rule = next(c for c in load(EXPERIMENTS / "benchmark" / "benchmark_heatmap.yaml").claims if c.id == "lm_vector_yuan")
    b = turns["optimum_at_bound_b"]
    assert (b.metric, b.stat, b.op, b.value, b.kind) == (rule.metric, rule.stat, rule.op, rule.value, rule.kind)
    assert not [c.id for c in turns.values() if c.where.get("estimator") == "local" and c.metric == "param_offset_error"]
    for scenario, pair in (("yuan2018_mode3", "xy"), ("yuan2018_mode3_xz", "xz"), ("yuan2018_mode3_yz", "yz")):
        c = turns[f"optimum_beats_rdpso_b_{pair}_90"]
        assert c.kind == "ordering" and c.test == "paired" and set(c.effect) == {"ratio", "spread"}
        assert [dict(cell) for cell in c.cells] == [
            {"scenario": scenario, "scenario.rotation.partial_arc_deg": 90, "estimator": est} for est in ("local", "rdpso")]
    reason = next(h for h in PAPER.headline if h.id == "two_partial_turns").reason
    assert "not the data" not in reason and "offset_bound" in reason and "param_offset_error < 1" in reason
