"""Headlines judged under each reading of what a paper leaves unstated, and the seeds a verdict needs."""

from types import SimpleNamespace

import pandas as pd
import pytest

from magexp.artifacts import headlines
from magexp.artifacts.claims import Claim, evaluate
from magexp.artifacts.plan import ArtifactPlan, grow_stage, next_seeds
from magexp.artifacts.schema import build
from magexp.artifacts.spec import Grow
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
    with pytest.raises(MagexpError, match="start=50, step=10, cap=40"):
        Grow(claims=["c"], start=50, step=10, cap=40, margin=0.1)


RULE = Grow(claims=["more"], start=30, step=20, cap=70, margin=0.1)


def test_next_seeds_grows_in_steps_and_stops_at_the_cap_or_a_decision():
    undecided = SimpleNamespace(p=0.2, p_contra=0.9, detectable=0.3)
    assert next_seeds(30, undecided, RULE) == 50
    assert next_seeds(60, undecided, RULE) == 70  # capped
    assert next_seeds(70, undecided, RULE) == 70  # at the cap: stops
    assert next_seeds(30, SimpleNamespace(p=0.01, p_contra=1.0, detectable=float("nan")), RULE) == 30  # decided
    assert next_seeds(30, SimpleNamespace(p=1.0, p_contra=0.01, detectable=0.3), RULE) == 30  # decided the other way
    assert next_seeds(30, SimpleNamespace(p=0.2, p_contra=0.9, detectable=0.05), RULE) == 30  # fine enough
    strict = Grow(claims=["more"], start=30, step=20, cap=70, margin=0.1, alpha=0.001)
    assert next_seeds(30, SimpleNamespace(p=0.01, p_contra=1.0, detectable=0.3), strict) == 50  # not at 0.001


def _plan(claim: Claim) -> ArtifactPlan:
    spec = SimpleNamespace(grow=RULE, claims=[claim], seeds=30)
    return ArtifactPlan(spec=spec, cells=[{"estimator": "a"}, {"estimator": "b"}, {"estimator": "c"}],
                        overrides=[["estimator=a"], ["estimator=b"], ["estimator=c"]], configs=[], index=[])


def test_grow_stage_is_deterministic_and_grows_only_the_claims_cells():
    more = Claim(id="more", text="", kind="ordering", test="fisher", stat="success_rate", better="higher",
                 cells=[{"estimator": "a"}, {"estimator": "b"}])
    plan = _plan(more)
    close = _table({"a": 0.9, "b": 0.8, "c": 0.1}, 30)  # 27 vs 24 of 30: no difference detected
    stage = grow_stage(plan, close, {0: 30, 1: 30})
    assert stage == {0: 50, 1: 50} and grow_stage(plan, close, {0: 30, 1: 30}) == stage
    apart = _table({"a": 1.0, "b": 0.2, "c": 0.1}, 30)  # decided at the start: the rule stops
    assert grow_stage(plan, apart, {0: 30, 1: 30}) is None
    assert grow_stage(plan, _table({"a": 0.9, "b": 0.8, "c": 0.1}, 70), {0: 70, 1: 70}) is None  # at the cap


def test_the_committed_headlines_carry_their_readings_and_the_report_names_each_split():
    from magexp.paths import RESULTS

    claims = pd.read_csv(RESULTS / "claims.csv")
    heads = claims[claims.role == "headline"].set_index(["paper", "id"])
    for head in ("ipso_more_accurate", "ipso_noise_robust"):  # Ding's traditional PSO is unstated
        assert heads.loc[("ding2024", head), "readings_total"] >= 4
    assert heads.loc[("yuan2018", "global_search"), "readings_total"] >= 3  # equal and unequal clamps
    assert heads.loc[("yan2022", "convergence_300"), "readings_total"] >= 4  # P(0)
    assert (heads.readings_holding <= heads.readings_total).all()
    text = (RESULTS / "REPORT.md").read_text()
    for reason in heads[heads.verdict == "depends"].reason:
        assert reason.startswith("depends: ") and " under " in reason
        assert " ".join(reason.split()).replace("|", "\\|") in text  # on the first screen, uncut
