"""The results website's pages (magexp.site), from the committed results/: every claim and compared number
in the explorer's data, the filters' options taken from the data, every figure on its paper page with its
caption, each headline's readings side by side. The browser's view of the built site: tests/test_site.py."""

from __future__ import annotations

import csv
import json
import re

import pytest

from magexp.paths import RESULTS
from magexp.site.data import CLAIM_FILTERS, explorer_data, options, reading_names, reading_of
from magexp.site.pages import Links, nav, pages, sections

pytestmark = pytest.mark.skipif(not (RESULTS / "REPORT.md").exists(), reason="results/ holds no report")


@pytest.fixture(scope="module")
def site():
    return pages(RESULTS)


def rows(name):
    with (RESULTS / name).open(newline="") as fh:
        return list(csv.DictReader(fh))


def embedded(page: str) -> dict:
    return json.loads(re.search(r'<script type="application/json" id="mx-data">(.*?)</script>', page, re.S).group(1))


def test_every_claim_and_compared_number_is_in_the_explorer(site):
    data = embedded(site["explorer.md"])
    claims = rows("claims.csv")
    assert [(r["paper"], r["artifact"], r["id"], r["family"]) for r in data["claims"]["rows"]] == \
        [(r["paper"], r["artifact"], r["id"], r["family"]) for r in claims]
    assert all(r["evidence"] == c["evidence"] for r, c in zip(data["claims"]["rows"], claims))
    compared = [r for r in rows("summary.csv") if r["paper_value"] != ""]
    assert len(compared) > 0
    assert [(r["artifact"], r["setting"], r["quantity"]) for r in data["numbers"]["rows"]] == \
        [(r["artifact"], r["setting"], r["quantity"]) for r in compared]


def test_the_explorer_links_each_claim_to_its_figure_and_run_csvs():
    data = explorer_data(RESULTS)["claims"]["rows"]
    with_figure = [r for r in data if r["figure"]]
    assert with_figure and all(r["png"] == f"{r['figure']}.png" for r in with_figure)
    assert all((RESULTS / f).is_file() for r in data for f in r["files"])
    assert any(f.endswith("_runs.csv") for r in data for f in r["files"])


def test_the_filters_options_are_the_datas_values():
    made = [{"paper": "a", "role": "headline", "verdict": "holds", "reading": "x"},
            {"paper": "b", "role": "finding", "verdict": "holds", "reading": "y"},
            {"paper": "a", "role": "finding", "verdict": "contradicted", "reading": "x"}]
    assert options(made, CLAIM_FILTERS) == {"paper": ["a", "b"], "role": ["headline", "finding"],
                                            "verdict": ["holds", "contradicted"], "reading": ["x", "y"]}
    filters = explorer_data(RESULTS)["claims"]["filters"]
    claims = rows("claims.csv")
    for key in ("paper", "role", "verdict"):
        assert sorted(filters[key]) == sorted({r[key] for r in claims}), key
    readings = {v for r in explorer_data(RESULTS)["claims"]["rows"] for v in r["reading"].split("; ")}
    assert sorted(filters["reading"]) == sorted(readings)
    assert "Kennedy & Eberhart 1995: w = 1, c = 2" in filters["reading"]  # a headline's other reading, by name


def test_a_claims_reading_is_named_by_the_headline_readings_it_tests():
    names = reading_names(["ding2024"])
    first = rows("claims.csv")[0]
    assert first["role"] == "headline" and reading_of(first, names) == f"{first['primary_reading']} (primary reading)"
    part = next(iter(names))
    row = {"paper": part[0], "artifact": part[1].split(".")[0], "id": part[1].split(".")[1], "family": "sensitivity"}
    assert reading_of(row, names) == names[part]
    assert reading_of({**row, "id": "no_such_claim"}, names) == "other reading (re-test)"
    assert reading_of({"paper": "x", "family": "sanity"}, names) == "none (sanity check)"


def test_each_figure_is_on_its_paper_page_with_its_caption(site):
    """Every PNG of a paper's folder (its readings figure apart) is on the paper's page, with the
    paragraph the appendix writes under it."""
    appendix = (RESULTS / "APPENDIX.md").read_text()
    for s in sections(RESULTS):
        page = site[f"{s.paper}/index.md"]
        pngs = sorted(p.name for p in (RESULTS / s.paper).glob("*.png") if p.name != "readings.png")
        assert pngs, s.paper
        for name in pngs:
            assert f"](../{s.paper}/{name})" in page, f"{s.paper}/{name} is not on its paper's page"
            after = appendix.split(f"]({s.paper}/{name})\n\n", 1)[1].split("\n\n", 1)[0]
            if not after.startswith("Data:"):
                assert Links([]).rewrite(after, 1) in page, f"{name}'s caption is not on its paper's page"


def test_a_paper_page_opens_with_its_headline_claims(site):
    for s in sections(RESULTS):
        page = site[f"{s.paper}/index.md"]
        assert page.startswith(f"# {s.title}\n")
        headings = re.findall(r"^## (.*)$", page, re.M)
        assert headings[0] == "Headline claims", headings
        assert "Findings" in headings or s.paper == "peers"


def test_each_headline_has_its_readings_side_by_side(site):
    for s in sections(RESULTS):
        cells = rows(f"{s.paper}/readings.csv") if (RESULTS / s.paper / "readings.csv").exists() else []
        page = site[f"{s.paper}/readings.md"]
        for c in cells:
            star = "★ " if c["primary"] == "True" else ""
            assert re.search(rf"\| {re.escape(star)}{re.escape(c['reading'].replace('|', chr(92) + '|'))}.*? \| \*\*{re.escape(c['verdict'])}\*\* \|",
                             page), (s.paper, c)
        assert page.count("| ★ ") == len({c["headline"] for c in cells}), s.paper  # one primary per headline


def test_links_from_the_report_point_to_the_pages_they_now_live_on():
    links = Links(sections(RESULTS))
    assert links.target("APPENDIX.md#ding2024-readings", 1) == "../ding2024/appendix.md#ding2024-readings"
    assert links.target("ding2024/ding2024_fig2.png", 1) == "../ding2024/ding2024_fig2.png"
    assert links.target("REPORT.md", 0) == "index.md"
    assert links.target("https://example.org/a.csv", 2) == "https://example.org/a.csv"


def test_no_page_is_long_without_headings(site):
    """A reader jumps by headings: no run of 150 lines without one."""
    for path, text in site.items():
        if path == "explorer.md":
            continue
        gaps = [len(chunk.splitlines()) for chunk in re.split(r"^#+ ", text, flags=re.M)]
        assert max(gaps) < 150, (path, max(gaps))


def test_every_page_is_in_the_nav(site):
    def flat(entries):
        for e in entries:
            for v in e.values():
                yield from flat(v) if isinstance(v, list) else [v]
    assert sorted(flat(nav(RESULTS))) == sorted(f"results/{p}" for p in site)
