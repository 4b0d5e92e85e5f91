"""The claims-first report: headline verdicts, size limits, no template residue, no empty table."""

import re

import pandas as pd
import pytest

from magexp.claims import CONTRADICTED, FAILS, HOLDS, NO_DIFFERENCE, NO_RUNS
from magexp.errors import MagexpError
from magexp.paths import RESULTS
from magexp.report import MAX_CELL, MAX_CHARS, MAX_LINES, compared_rows, headline_verdict, markdown_table
from magexp.spec import Headline, build


def test_headline_verdict_aggregates_its_parts():
    assert headline_verdict([HOLDS, HOLDS]) == "supported"
    assert headline_verdict([HOLDS, NO_DIFFERENCE]) == "partly"
    assert headline_verdict([FAILS, CONTRADICTED, NO_DIFFERENCE]) == "contradicted"
    assert headline_verdict([None, None]) == "not testable here"  # no part has runs here
    assert headline_verdict([HOLDS, None]) == "partly"  # one part could not be evaluated


def test_headline_schema():
    h = build(Headline, {"id": "h", "text": "t", "section": "Sec. 4", "parts": ["a.b"], "figure": "p/a"}, "h")
    assert h.parts == ["a.b"]
    for bad, message in [({"parts": ["a.b"], "untestable": "why"}, "either parts"), ({}, "either parts"),
                         ({"parts": ["ab"]}, "artifact>.<claim id"), ({"parts": ["a.b"], "figure": "a"}, "paper folder")]:
        with pytest.raises(MagexpError, match=message):
            build(Headline, {"id": "h", "text": "t", "section": "s", **bad}, "h")
    with pytest.raises(MagexpError, match="missing key 'section'"):
        build(Headline, {"id": "h", "text": "t", "untestable": "why"}, "h")


def test_an_empty_table_is_an_error():
    with pytest.raises(MagexpError, match="empty table"):
        markdown_table(pd.DataFrame(columns=["a"]), ["a"])
    assert markdown_table(pd.DataFrame({"a": ["x|y"]}), ["a"]).splitlines()[2] == "| x\\|y |"


def test_a_parameter_table_is_one_line_naming_what_is_not_reproduced():
    rows = pd.DataFrame({"artifact": "t", "estimator": "rdpso", "setting": "s", "label": [f"RDPSO S{i}, mode4" for i in range(6)],
                         "quantity": [f"S{i}" for i in range(6)], "paper_value": 1.0, "value": 1.0, "lo": 0.9, "hi": 1.1,
                         "verdict": ["reproduced"] * 4 + ["differs", "uninformative"], "reason": "r"})
    out = compared_rows(rows)
    assert len(out) == 1 and "reproduced 4" in out.verdict[0] and "S4 differs" in out.reason[0]
    assert "S5 uninformative" in out.reason[0] and "S0 " not in out.reason[0]
    assert len(compared_rows(rows.iloc[:3])) == 3  # small cells stay one row per number


def _report():
    path = RESULTS / "REPORT.md"
    if not path.exists() or not (RESULTS / "claims.csv").exists():
        pytest.skip("results/ are absent or predate the claims-first report: run make reproduce")
    return path.read_text(), (RESULTS / "APPENDIX.md").read_text()


def _tables(text: str) -> list[list[str]]:
    tables, current = [], []
    for line in text.splitlines() + [""]:
        if line.startswith("|"):
            current.append(line)
        elif current:
            tables.append(current)
            current = []
    return tables


def test_the_report_is_short_and_complete():
    report, appendix = _report()
    assert len(report.splitlines()) <= MAX_LINES and len(report) <= MAX_CHARS
    for text in (report, appendix):
        for table in _tables(text):
            assert len(table) > 2, f"an empty table: {table[0]}"
        assert "[95 % CI nan" not in text and not re.search(r"\bnan\b", text), "nan printed"
        assert NO_RUNS not in text, "a note field printed no value although the canonical runs should have one"
    longest = max(len(c) for t in _tables(report) for row in t for c in re.split(r"(?<!\\)\|", row))
    assert longest <= MAX_CELL + 2  # the cell and its two spaces


def test_each_paper_section_opens_with_its_headline_claims():
    report, _ = _report()
    for section in report.split("\n## ")[1:]:
        lines = section.splitlines()
        assert any(line.startswith("### Headline claims") for line in lines[:6]), lines[0]
    claims = pd.read_csv(RESULTS / "claims.csv", keep_default_na=False)
    assert {"paper", "artifact", "id", "by", "role", "section", "figure", "text", "verdict", "reason",
            "evidence"} <= set(claims.columns)
    heads = claims[claims.role == "headline"]
    assert set(heads.verdict) <= {"supported", "partly", "contradicted", "not testable here"}
    assert set(claims[claims.role != "headline"].verdict) <= {HOLDS, FAILS, CONTRADICTED, NO_DIFFERENCE}
    assert (claims.reason.str.len() <= MAX_CELL).all()
