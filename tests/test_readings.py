"""Headlines judged under each reading of what a paper leaves unstated (the seeds a verdict needs: tests/test_power.py)."""

from types import SimpleNamespace

import pandas as pd
import pytest

from magexp.artifacts import headlines
from magexp.artifacts.claims import Claim, evaluate
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


def test_readings_that_split_read_depends_and_name_both_sides(monkeypatch):
    table = _table({"a": 1.0, "b": 0.0}, 10)
    a_ok = Claim(id="a_ok", text="", kind="success", where={"estimator": "a"}, op=">=", value=0.9)
    b_ok = Claim(id="b_ok", text="", kind="success", where={"estimator": "b"}, op=">=", value=0.9)
    head = {"id": "h", "text": "t", "section": "s", "parts": ["art.a_ok"], "readings": [
        {"label": "reading A", "source": "the literature"},
        {"label": "reading B", "source": "the paper's words", "parts": ["art.b_ok"]}]}
    row = _headlines(monkeypatch, [head], table, [a_ok, b_ok])["h"]
    assert row["verdict"] == "depends"
    assert row["reason"].startswith('depends: supported under "reading A"; contradicted under "reading B"')
    assert (row["readings_total"], row["readings_holding"]) == (2, 1)
    assert "reading B (the paper's words): contradicted" in row["evidence"]


def test_readings_that_agree_keep_the_common_verdict(monkeypatch):
    table = _table({"a": 1.0, "b": 0.95}, 20)
    a_ok = Claim(id="a_ok", text="", kind="success", where={"estimator": "a"}, op=">=", value=0.9)
    b_ok = Claim(id="b_ok", text="", kind="success", where={"estimator": "b"}, op=">=", value=0.9)
    heads = [{"id": "h", "text": "t", "section": "s", "parts": ["art.a_ok"], "readings": [
                 {"label": "A", "source": "x"}, {"label": "B", "source": "y", "parts": ["art.b_ok"]}]},
             {"id": "plain", "text": "t", "section": "s", "parts": ["art.a_ok"]}]
    rows = _headlines(monkeypatch, heads, table, [a_ok, b_ok])
    assert rows["h"]["verdict"] == "supported" and not rows["h"]["reason"].startswith("depends")
    assert (rows["h"]["readings_total"], rows["h"]["readings_holding"]) == (2, 2)
    assert (rows["plain"]["readings_total"], rows["plain"]["readings_holding"]) == (1, 1)


def test_readings_verdict_orders_the_sides():
    verdict, split = headlines.readings_verdict([("x", "contradicted"), ("y", "supported"), ("z", "contradicted")])
    assert verdict == "depends" and split == 'depends: supported under "y"; contradicted under "x", "z"'
    assert headlines.readings_verdict([("x", "partly"), ("y", "partly")]) == ("partly", "")


def test_a_reading_schema_is_checked():
    base = {"id": "h", "text": "t", "section": "s", "parts": ["art.a"]}
    with pytest.raises(MagexpError, match="one reading is no choice"):
        build(Headline, {**base, "readings": [{"label": "A", "source": "x"}]}, "h")
    with pytest.raises(MagexpError, match="at most 40"):
        build(Headline, {**base, "readings": [{"label": "L" * 41, "source": "x"}, {"label": "B", "source": "y"}]}, "h")


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
