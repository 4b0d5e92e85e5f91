"""The claims-first report: headline verdicts, size limits, no template residue, no empty table."""

import re

import pandas as pd
import pytest

from magexp.artifacts.claims import FAILS, NO_RUNS
from magexp.artifacts.comparisons import CONTRADICTED, HOLDS, NO_DIFFERENCE, UNDECIDED
from magexp.errors import MagexpError
from magexp.paths import RESULTS
from magexp.artifacts.formats import markdown_table
from magexp.artifacts.headlines import headline_verdict
from magexp.artifacts.paper_spec import HEADLINE_VERDICTS
from magexp.artifacts.formats import LINE_LIMIT
from magexp.artifacts.report import MAX_CHARS, MAX_REPORT_LINES, compared_counts, compared_rows, over_budget
from magexp.artifacts.report_claims import counts
from magexp.artifacts.schema import build
from magexp.artifacts.paper_spec import Headline


def test_headline_verdict_aggregates_its_parts():
    assert headline_verdict([HOLDS, HOLDS]) == "supported"
    assert headline_verdict([HOLDS, NO_DIFFERENCE]) == "partly"
    assert headline_verdict([FAILS, CONTRADICTED, NO_DIFFERENCE]) == "contradicted"
    assert headline_verdict([UNDECIDED, NO_DIFFERENCE]) == "not shown"  # nothing holds, nothing against
    assert headline_verdict([UNDECIDED, FAILS]) == "contradicted"
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
                         "verdict": ["reproduced"] * 4 + ["differs", "uninformative"], "reason": "r",
                         "judged_runs": "successful seeds", "judged_n": 28, "judged_value": 1.0, "judged_lo": 0.9,
                         "judged_hi": 1.1, "rel_difference": 0.002})
    out = compared_rows(rows)
    assert len(out) == 1 and "reproduced 4" in out.verdict[0] and "S4 differs" in out.reason[0]
    assert "S5 uninformative" in out.reason[0] and "S0 " not in out.reason[0]
    assert "S4 differs: paper 1, ours 1 (0.2 % of its scale)" in out.reason[0] and out.ours[0].startswith("successful")
    small = compared_rows(rows.iloc[:3])
    assert len(small) == 3 and small.ours[0] == "1 [0.9, 1.1], successful seeds (28)"  # what the verdict used


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
    assert over_budget(report) == []
    for text in (report, appendix):
        for table in _tables(text):
            assert len(table) > 2, f"an empty table: {table[0]}"
        assert "[95 % CI nan" not in text and not re.search(r"\bnan\b", text), "nan printed"
        assert NO_RUNS not in text, "a note field printed no value although the canonical runs should have one"
    assert "(cut" not in report and "more part" not in report, "a text cut: every setting a verdict turns on is shown"


def test_each_paper_section_opens_with_its_headline_claims():
    report, _ = _report()
    for section in report.split("\n## ")[1:]:
        lines = section.splitlines()
        assert any(line.startswith("### Headline claims") for line in lines[:6]), lines[0]
    claims = pd.read_csv(RESULTS / "claims.csv", keep_default_na=False)
    assert {"paper", "artifact", "id", "by", "role", "section", "figure", "text", "verdict", "reason",
            "evidence"} <= set(claims.columns)
    heads = claims[claims.role == "headline"]
    assert set(heads.verdict) <= set(HEADLINE_VERDICTS)
    assert set(claims[claims.role != "headline"].verdict) <= {HOLDS, FAILS, CONTRADICTED, NO_DIFFERENCE, UNDECIDED}
    # a headline's reason is written whole, decisive evidence first; every headline names its robustness
    assert all(e.startswith(r) for r, e in zip(heads.reason, heads.evidence))
    assert {"primary_reading", "robustness", "family", "level"} <= set(claims.columns) and heads.robustness.str.len().gt(0).all()


def test_headlines_take_their_verdict_reason_and_figure_from_the_parts(monkeypatch):
    from types import SimpleNamespace

    from magexp.artifacts import headlines
    from magexp.artifacts.claims import Claim, evaluate
    from magexp.artifacts.paper_spec import Paper

    table = pd.DataFrame({"cell": [0, 0, 1, 1], "seed": [0, 1, 0, 1], "estimator": ["a", "a", "b", "b"],
                          "setting": ["scenario=x"] * 4, "fun": [1.0, 1.2, 5.0, 6.0], "succeeded": [1.0] * 4})
    ok = Claim(id="ok", text="", kind="threshold", where={"estimator": "a"}, op="<", value=2)
    bad = Claim(id="bad", text="", kind="threshold", where={"estimator": "b"}, op="<", value=2)
    specs = [SimpleNamespace(name="art", claims=[ok, bad])]
    outcomes = {"art.ok": evaluate(ok, table), "art.bad": evaluate(bad, table)}
    heads = [build(Headline, h, "h") for h in (
        {"id": "both", "text": "t", "section": "s", "parts": ["art.ok", "art.bad"], "reason": "a at {median:fun@estimator=a:.2g}"},
        {"id": "one", "text": "t", "section": "s", "parts": ["art.ok"], "figure": "p/fig"},
        {"id": "none", "text": "t", "section": "s", "untestable": "the data are not public"})]
    monkeypatch.setattr(headlines, "load_paper", lambda paper: Paper(title="p", headline=heads))
    rows = {r["id"]: r for r in headlines.headlines("p", specs, outcomes, lambda name: table)}
    assert rows["both"]["verdict"] == "partly" and rows["both"]["reason"].endswith(". a at 1.1")
    assert rows["both"]["reason"].startswith("Not on:  (does not hold: median of fun 5.5 (2 seeds); required below 2)")
    assert rows["one"]["verdict"] == "supported" and rows["one"]["figure"] == "p/fig"
    assert rows["both"]["figure"] == "p/art"  # default: the first part's artifact
    assert rows["none"]["verdict"] == "not testable here" and rows["none"]["reason"] == "the data are not public"
    typo = [build(Headline, {"id": "x", "text": "t", "section": "s", "parts": ["art.nope"]}, "h")]
    monkeypatch.setattr(headlines, "load_paper", lambda paper: Paper(title="p", headline=typo))
    with pytest.raises(MagexpError, match="'art.nope' names no claim"):
        headlines.headlines("p", specs, outcomes, lambda name: table)


def test_a_caption_counts_seeds_from_the_runs_never_by_hand():
    """ding2024_ext_boundary's caption said 30 seeds over 100-seed runs, ding2024_fig6's and yuan2018_fig2-4's
    "10 seeds" (their own runs) for the 30-seed tables they point to: ``{seeds}`` counts an artifact's own
    runs, ``{seeds:<artifact>}`` another's (the appendix prints that artifact's count), and no caption
    types a count."""
    from magexp.artifacts.plan import paper_specs
    from magexp.artifacts.report import seed_count
    from magexp.artifacts.paper_spec import papers

    specs = [s for p in papers() for s in paper_specs(p) if s.caption]
    typed = [(s.name, m.group(0)) for s in specs for m in [re.search(r"\b\d+ (seeds|runs)\b", str(s.caption))] if m]
    assert typed == []
    appendix = " ".join((RESULTS / "APPENDIX.md").read_text().split())
    cited = [(s, m) for s in specs for m in re.finditer(r"([^{}]{0,40})\{seeds:(\w+)\}([^{}]{0,20})", " ".join(str(s.caption).split()))]
    assert {m.group(2) for _, m in cited} >= {"ding2024_table_rms", "yuan2018_table3"}
    for spec, m in cited:
        n = seed_count(pd.read_csv(RESULTS / spec.paper / f"{m.group(2)}_runs.csv"))
        own = seed_count(pd.read_csv(RESULTS / spec.paper / f"{spec.name}_runs.csv"))
        assert n != own and f"{m.group(1)}{n}{m.group(3)}" in appendix  # the other's count, not its own


def test_the_report_has_no_ellipsis_and_keeps_its_size():
    report, appendix = _report()
    assert "…" not in report and "…" not in appendix, "a cut text: write it to fit, or say where the rest is"
    assert over_budget(report) == []
    long = [(name, n + 1) for name, text in (("REPORT.md", report), ("APPENDIX.md", appendix))
            for n, line in enumerate(text.splitlines()) if len(line) > LINE_LIMIT]
    assert not long, f"lines over {LINE_LIMIT} characters: {long[:5]}"
    assert len(report.splitlines()) <= MAX_REPORT_LINES, f"REPORT.md has {len(report.splitlines())} lines"


def test_counts_keep_the_papers_claims_apart_from_magexps_and_sanity_checks():
    """Each distinct claim counted once: a re-test under another reading (family sensitivity) is never a
    finding of the paper, an exploratory setting and a sanity check are counted apart."""
    claims = [{"role": "headline", "by": "paper", "verdict": "supported"},
              {"role": "headline", "by": "paper", "verdict": "by construction"},
              {"role": "finding", "by": "paper", "verdict": HOLDS, "family": "primary"},
              {"role": "finding", "by": "paper", "verdict": NO_DIFFERENCE, "family": "primary"},
              {"role": "finding", "by": "paper", "verdict": HOLDS, "family": "sensitivity"},
              {"role": "finding", "by": "paper", "verdict": FAILS, "family": "sensitivity"},
              {"role": "exploratory", "by": "paper", "verdict": HOLDS, "family": "exploratory"},
              {"role": "finding", "by": "magexp", "verdict": HOLDS, "family": "magexp"},
              {"role": "sanity", "by": "magexp", "verdict": HOLDS, "family": "sanity"}]
    text = counts(claims, [UNDECIDED])
    assert text.startswith("Headline claims: supported 1, by construction 1;")
    assert "the papers' findings: 1 of 2 hold (no difference detected 1)" in text
    assert "magexp's own statements: 1 of 2 hold (cannot be decided 1)" in text
    assert "(robustness): 1 of 2 hold (does not hold 1)" in text
    assert "exploratory settings (shown, never counted): 1" in text and "sanity checks (true by construction): 1" in text


def test_compared_counts_split_differs_by_scale_and_failed_majority():
    rows = pd.DataFrame({"verdict": ["reproduced", "differs", "differs", "differs", "not compared"],
                         "rel_difference": [0.0, 0.001, 0.5, 0.002, float("nan")],
                         "reason": ["", "outside", "outside", "(a failed majority); inside", ""]})
    assert compared_counts(rows) == ("reproduced 1, differs 3 (2 of them by less than 1 % of their scale; 1 on a failed "
                                     "majority of our runs), uninformative 0; not compared 1")


def test_each_counts_line_agrees_with_the_list_or_table_under_it():
    """The headline counts above a section's headlines count exactly its listed headlines by verdict, and the
    "k of n hold" above a findings table counts exactly its rows (issue 39: "34 of 53" stood above a table
    of 15 rows)."""
    report, _ = _report()
    checked = 0
    for section in report.split("\n## ")[1:]:
        heads = re.search(r"\*\*Headline claims: ([^*]+)\*\*", section)
        if heads:
            said = {k.strip(): int(n) for k, n in re.findall(r"([a-z ]+?) (\d+)(?:,|$)", heads.group(1))}
            listed = re.findall(r"^\d+\. \**([a-z ]+?)\**: ", section, flags=re.M)
            assert said == {v: listed.count(v) for v in set(listed)}, section.splitlines()[0]
            checked += 1
        for block in section.split("### ")[1:]:
            held = re.search(r"^\*\*(\d+) of (\d+) hold", block.split("\n", 2)[2] if block.count("\n") > 1 else "")
            if held:
                tables = _tables(block)
                if tables:
                    rows = tables[0][2:]
                    results = [re.split(r"(?<!\\)\|", r)[3].strip().strip("*") for r in rows]
                else:  # a table with a row over LINE_LIMIT is written as a list (issue 43)
                    rows = [" ".join(item.split()) for item in re.findall(r"^- \*\*.*(?:\n {2,}.*)*", block, flags=re.M)]
                    results = [re.search(r"; result: \**([^;*]+?)\**; evidence:", r).group(1) for r in rows]
                assert (int(held.group(1)), int(held.group(2))) == (results.count(HOLDS), len(rows)), block[:60]
                checked += 1
    assert checked >= 3


def test_long_prose_is_wrapped_and_a_long_table_becomes_a_list():
    from magexp.artifacts.formats import WRAP, markdown_table, wrap_markdown

    words = " ".join(f"word{i}" for i in range(200))
    text = "\n".join(["# A heading " + words, "Para " + words, "   - *Item:* " + words, "| a | " + words + " |",
                      "short line"])
    out = wrap_markdown(text).splitlines()
    assert out[0].startswith("# A heading") and len(out[0]) > LINE_LIMIT  # a heading is not prose: kept whole
    assert out[-1] == "short line" and any(line.startswith("| a |") and len(line) > LINE_LIMIT for line in out)
    prose = out[1:next(i for i, line in enumerate(out) if line.startswith("| a |"))]
    assert max(map(len, prose)) <= WRAP and " ".join(" ".join(prose).split()) == " ".join(
        ("Para " + words + " - *Item:* " + words).split())  # nothing lost, only line breaks added
    assert prose[-1].startswith("     word") and not prose[1].startswith(" ")  # an item's lines indented, a paragraph's not
    frame = pd.DataFrame({"name": ["x", "y"], "why": ["short", words]})
    table = markdown_table(frame, ["name", "why"])
    assert table.startswith("- **x** — why: short\n- **y** — why: word0")
    assert markdown_table(frame.iloc[:1], ["name", "why"]).startswith("| name | why |")


def test_a_section_over_its_budget_is_named_with_by_how_much():
    """Issue 44: the budget is each section's, and a failing size test says which section and by how much."""
    text = "# magexp report\n\nopening\n\n## Short paper\n\nfine\n\n## Long paper\n\n" + "x" * MAX_CHARS + "\n"
    over = len("Long paper\n\n") + 1  # the section as split: its heading line, the text and its newline
    assert over_budget(text) == [f"section 'Long paper' has {MAX_CHARS + over:,} characters: {over:,} over its budget "
                                 f"of {MAX_CHARS:,} (MAX_CHARS, magexp/artifacts/report.py)"]
    assert over_budget(text, limit=MAX_CHARS + over) == []


def test_the_shared_legends_are_written_once_and_each_section_links_them():
    """Issue 44: the ~1,700 characters of fixed legend each paper's section repeated (the findings', the compared
    numbers', the headlines', the winners') stand once, under "How to read", and each part links there."""
    from magexp.artifacts.formats import PEERS_HEADING
    from magexp.artifacts.report import COMPARED_LEGEND, WINNERS_LEGEND
    from magexp.artifacts.report_claims import FINDINGS_LEGEND, HEADLINES_LEGEND, LEGENDS

    report, appendix = _report()
    flat = " ".join(report.split())
    for legend in (FINDINGS_LEGEND, HEADLINES_LEGEND, COMPARED_LEGEND, WINNERS_LEGEND):
        assert flat.count(" ".join(legend.split())) == 1, legend[:40]
    assert "## How to read\n" in report and "#how-to-read" in report.split("## How to read")[0]
    for section in [s for s in report.split("\n## ")[2:] if not PEERS_HEADING.endswith(s.splitlines()[0])]:
        for part in ("### Findings", "### Compared numbers", "### Headline claims"):
            if part in section and "No headline claim" not in section.split(part, 1)[1][:80]:
                assert LEGENDS in section.split(part, 1)[1].split("\n### ")[0], (section.splitlines()[0], part)
    assert " ".join(FINDINGS_LEGEND.split()) in " ".join(appendix.split())  # the appendix keeps its own
