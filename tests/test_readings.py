"""Headlines judged under each reading of what a paper leaves unstated (the seeds a verdict needs: tests/test_power.py)."""

from types import SimpleNamespace

import pandas as pd
import pytest

from magexp.artifacts import headlines
from magexp.artifacts.claims import Claim, evaluate
from magexp.artifacts.comparisons import adjust
from magexp.artifacts.schema import build
from magexp.artifacts.paper_spec import Headline, Paper
from magexp.errors import MagexpError


def _table(rates: dict[str, float], n: int) -> pd.DataFrame:
    """``n`` seeds per estimator, the first ``rate * n`` of them successful (a fixed, known table)."""
    rows = [{"cell": ci, "seed": s, "estimator": est, "setting": "scenario=x", "fun": 1.0 + s,
             "succeeded": float(s < round(rate * n))}
            for ci, (est, rate) in enumerate(rates.items()) for s in range(n)]
    return pd.DataFrame(rows)


def _headlines(monkeypatch, heads: list[dict], table: pd.DataFrame, claims: list[Claim]) -> dict:
    specs = [SimpleNamespace(name="art", claims=claims)]
    outcomes = {f"art.{c.id}": evaluate(c, table) for c in claims}
    paper = Paper(title="p", headline=[build(Headline, h, "h") for h in heads])
    monkeypatch.setattr(headlines, "load_paper", lambda name: paper)
    return {r["id"]: r for r in headlines.headlines("p", specs, outcomes, lambda name: table)}


def test_the_primary_reading_decides_and_the_others_give_robustness(monkeypatch):
    """Readings that split never make a verdict of their own: the primary decides (here contradicted,
    although the other reading supports the headline) and the robustness sentence names the other side
    with why it is less plausible; the other reading's claims sit in the sensitivity family."""
    table = _table({"a": 1.0, "b": 0.0}, 10)
    a_ok = Claim(id="a_ok", text="", kind="success", where={"estimator": "a"}, op=">=", value=0.9)
    b_ok = Claim(id="b_ok", text="", kind="success", where={"estimator": "b"}, op=">=", value=0.9)
    head = {"id": "h", "text": "t", "section": "s", "parts": ["art.b_ok"], "primary": "reading B",
            "why": "Sec. 2: the paper's words", "readings": [
                {"label": "reading A", "source": "Smith 1999", "settings": "w = 1", "parts": ["art.a_ok"],
                 "less_plausible": "the paper fixes w below 1"},
                {"label": "reading B", "source": "the paper's own words (Sec. 2)"}]}
    row = _headlines(monkeypatch, [head], table, [a_ok, b_ok])["h"]
    assert row["verdict"] == "contradicted" and row["primary_reading"] == "reading B"
    assert row["robustness"] == ('contradicted under the primary reading; supported under "reading A" '
                                 "(less plausible: the paper fixes w below 1)")
    assert (row["readings_total"], row["readings_holding"]) == (2, 1)
    assert "reading reading A (Smith 1999; w = 1): supported" in row["evidence"]


def test_readings_that_agree_are_robust(monkeypatch):
    table = _table({"a": 1.0, "b": 0.95}, 20)
    a_ok = Claim(id="a_ok", text="", kind="success", where={"estimator": "a"}, op=">=", value=0.9)
    b_ok = Claim(id="b_ok", text="", kind="success", where={"estimator": "b"}, op=">=", value=0.9)
    heads = [{"id": "h", "text": "t", "section": "s", "parts": ["art.a_ok"], "primary": "A", "why": "w",
              "readings": [{"label": "A", "source": "x"},
                           {"label": "B", "source": "y", "parts": ["art.b_ok"], "less_plausible": "z"}]},
             {"id": "plain", "text": "t", "section": "s", "parts": ["art.a_ok"]}]
    rows = _headlines(monkeypatch, heads, table, [a_ok, b_ok])
    assert rows["h"]["verdict"] == "supported" and rows["h"]["robustness"] == "robust under all 2 readings"
    assert (rows["h"]["readings_total"], rows["h"]["readings_holding"]) == (2, 2)
    assert (rows["plain"]["readings_total"], rows["plain"]["readings_holding"]) == (1, 1)


def test_a_claim_about_every_instance_fails_on_the_instance_named(monkeypatch):
    """A universal claim lists each instance as a part: one failing instance makes it partly, and the
    reason names that instance first."""
    table = _table({"a": 1.0, "b": 0.0}, 10)
    a_ok = Claim(id="a_ok", text="instance a recovers", kind="success", where={"estimator": "a"}, op=">=", value=0.9)
    b_ok = Claim(id="b_ok", text="instance b recovers", kind="success", where={"estimator": "b"}, op=">=", value=0.9)
    head = {"id": "h", "text": "any instance", "section": "s", "parts": ["art.a_ok", "art.b_ok"]}
    row = _headlines(monkeypatch, [head], table, [a_ok, b_ok])["h"]
    assert row["verdict"] == "partly" and row["reason"].startswith("Not on: instance b recovers (does not hold: success rate 0")


def test_a_reading_schema_is_checked():
    base = {"id": "h", "text": "t", "section": "s", "parts": ["art.a"]}
    with pytest.raises(MagexpError, match="one reading is no choice"):
        build(Headline, {**base, "primary": "A", "why": "w", "readings": [{"label": "A", "source": "x"}]}, "h")
    two = [{"label": "A", "source": "x"}, {"label": "B", "source": "y", "parts": ["art.b"]}]
    with pytest.raises(MagexpError, match="primary='' is not allowed: name one of its readings"):
        build(Headline, {**base, "readings": two}, "h")
    with pytest.raises(MagexpError, match="why is missing"):
        build(Headline, {**base, "primary": "A", "readings": two}, "h")
    with pytest.raises(MagexpError, match="reading 'B' needs less_plausible"):
        build(Headline, {**base, "primary": "A", "why": "Sec. 1", "readings": two}, "h")
    with pytest.raises(MagexpError, match="at most 40"):
        build(Headline, {**base, "readings": [{"label": "L" * 41, "source": "x"}, {"label": "B", "source": "y"}]}, "h")


def test_the_committed_headlines_name_their_primary_reading_and_robustness_on_the_first_screen():
    """Every committed headline with readings names its primary and its robustness, and both stand uncut on
    the report's first screen of its paper; no verdict is ``depends``."""
    from magexp.paths import RESULTS

    claims = pd.read_csv(RESULTS / "claims.csv", keep_default_na=False)
    heads = claims[claims.role == "headline"].set_index(["paper", "id"])
    for head in ("ipso_more_accurate", "ipso_noise_robust"):  # Ding's traditional PSO is unstated
        assert int(heads.loc[("ding2024", head), "readings_total"]) >= 3
    assert int(heads.loc[("yuan2018", "global_search"), "readings_total"]) >= 3  # the velocity clamps
    assert int(heads.loc[("yan2022", "convergence_300"), "readings_total"]) >= 4  # P(0) and the tolerance
    total = heads.readings_total.astype(int)
    assert (heads.readings_holding.astype(int) <= total).all() and "depends" not in set(heads.verdict)
    text = " ".join((RESULTS / "REPORT.md").read_text().split())
    with_readings = heads[total > 1]
    assert len(with_readings) >= 8 and (with_readings.primary_reading.str.len() > 0).all()
    for robust in with_readings.robustness:
        assert f"*Robustness:* {' '.join(robust.split())}." in text  # on the first screen, uncut


def test_every_reading_of_every_paper_is_sourced_and_argued():
    """Issue 39: a reading's source is checkable (an author and year, the paper's own words, or magexp's
    construction) and states its settings; the primary is argued with the paper's words; nothing is left
    as a placeholder; a setting chosen because its runs resemble the paper's numbers is no reading."""
    import re

    from magexp.artifacts.paper_spec import load_paper, papers

    checked = 0
    for paper in papers():
        for h in load_paper(paper).headline:
            if not h.readings:
                continue
            assert re.search(r"Sec\.|eq|Table|Fig|Abstract|\"|“", h.why), f"{paper}.{h.id}: why quotes no part of the paper"
            for r in h.readings:
                source = " ".join(str(r.source).split())
                assert re.search(r"\b(19|20)\d\d\b|the paper's own|magexp's construction", source), (paper, h.id, r.label)
                assert str(r.settings).strip(), f"{paper}.{h.id}: reading {r.label!r} states no settings"
                assert "to be argued" not in f"{h.why} {r.less_plausible}", (paper, h.id, r.label)
                assert "point to" not in source and "resemble" not in source, (paper, h.id, r.label)
                checked += 1
    assert checked >= 20


def test_a_reading_neither_shown_nor_contradicted_says_what_its_test_could_have_seen(monkeypatch):
    """A reading whose only part detects no difference is "not shown" (not contradicted), and the robustness
    sentence says the difference its test would have seen with 80 % power at its level."""
    table = _table({"a": 1.0, "b": 1.0}, 12)  # the same values on both sides: no difference
    a_ok = Claim(id="a_ok", text="", kind="success", where={"estimator": "a"}, op=">=", value=0.9)
    a_beats_b = Claim(id="a_beats_b", text="", kind="ordering", metric="fun", test="unpaired",
                      cells=[{"estimator": "a"}, {"estimator": "b"}])
    head = {"id": "h", "text": "t", "section": "s", "parts": ["art.a_ok"], "primary": "A", "why": "w",
            "readings": [{"label": "A", "source": "x"},
                         {"label": "B", "source": "y", "parts": ["art.a_beats_b"], "less_plausible": "z"}]}
    specs = [SimpleNamespace(name="art", claims=[a_ok, a_beats_b])]
    outcomes = {f"art.{c.id}": adjust([evaluate(c, table)], ["sensitivity"])[0] for c in (a_ok, a_beats_b)}
    monkeypatch.setattr(headlines, "load_paper", lambda name: Paper(title="p", headline=[build(Headline, head, "h")]))
    row = headlines.headlines("p", specs, outcomes, lambda name: table)[0]
    assert row["verdict"] == "supported"
    assert row["robustness"].startswith('supported under the primary reading; not shown under "B" (no difference '
                                        "detected; a_beats_b would have seen a difference of ")
    assert "with 80 % power at its level 0.05 (observed: 0); less plausible: z)" in row["robustness"]
