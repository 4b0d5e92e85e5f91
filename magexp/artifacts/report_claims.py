"""The claims half of a report section: the headline claims in words (verdict under the primary reading,
why, the deciding numbers, robustness), their counts, the readings figure and the findings table.

A section object ``p`` (:class:`magexp.artifacts.report.Paper`) carries ``paper``, ``root``, ``meta``,
``headlines`` and ``claims``. Counts count each distinct claim once (:func:`counts`): the headlines under
their primary readings, the papers' findings (the ``primary`` family's ``by: paper`` claims), magexp's own
statements, and apart the re-tests under other readings, the exploratory settings and the sanity checks.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from magexp.artifacts.claims import FAILS
from magexp.artifacts.comparisons import CONTRADICTED, HOLDS, NO_DIFFERENCE, UNDECIDED
from magexp.artifacts.formats import markdown_table, write_csv
from magexp.artifacts.paper_spec import HEADLINE_VERDICTS, NOT_SHOWN
from magexp.artifacts.plots import readings as readings_plot
from magexp.artifacts.plots.style import save


#: where a paper's section of REPORT.md points for the legends it shares with every other (issue 44: written once)
LEGENDS = "[how to read](#how-to-read)"
#: the legend of a findings table (once in REPORT.md, under "How to read"; in each appendix section)
FINDINGS_LEGEND = ("*paper*: the paper's statement, checked; *magexp*: stated by this report, a test fails if one "
                   "does not hold. A comparison holds only where its test separates the two sides, a trend only where its "
                   "bootstrap test puts the slope inside its range, at alpha 0.05 after "
                   "Holm's correction within its family (the paper's findings and the parts of the headlines' primary "
                   "readings; magexp's statements apart; the re-tests under other readings apart, in the readings "
                   "figure); full evidence and p-values: [`claims.csv`](claims.csv).")
#: the legend of the headline claims (once in REPORT.md, under "How to read")
HEADLINES_LEGEND = ("Each headline claim is judged under its primary reading of what the paper leaves unstated; the "
                    "others test its robustness and never decide. *Primary reading*: the reading that decides, with a "
                    "link to its source and why the paper most plausibly meant it (the paper's appendix); "
                    "*Deciding numbers* (or *Why not*, for a claim not testable here): the numbers the verdict turns "
                    "on; *Robustness*: the verdicts under the other readings. Every headline under every reading: "
                    "the paper's readings figure, linked above its list.")


def link(figure: str, root: Path) -> str:
    """A Markdown link to a figure ``<paper>/<artifact>`` (its PNG), or '' if it was not drawn."""
    if not figure:
        return ""
    name = figure.split("/")[-1]
    return f"[{name}]({figure}.png)" if (root / f"{figure}.png").exists() else name


def bold(verdict: str) -> str:
    """A verdict in bold where it is a negative one (a reader's eye goes to it first)."""
    return f"**{verdict}**" if verdict in ("contradicted", "partly", NOT_SHOWN, FAILS, CONTRADICTED, "differs") else verdict


def headline_list(p) -> str:
    """The headline claims of a section, each in words: its verdict under its primary reading, that reading
    and why the paper most plausibly meant it, the deciding numbers, and its robustness under the others;
    above them their counts by verdict.
    """
    if not p.headlines:
        return "No headline claim of this section is declared (`headline:` in its `paper.yaml`).\n"
    lines = [f"**{headline_counts(p.headlines)}** (each under its primary reading; every headline under every "
             f"reading: {link(f'{p.paper}/readings', p.root)}; {LEGENDS}).\n"]
    for i, h in enumerate(p.headlines, 1):
        lines.append(f"{i}. {bold(h['verdict'])}: {h['text']} ({h['section']}; {link(h['figure'], p.root)})")
        primary = next((r for r in h["readings"] if r["primary"]), None)
        if primary:
            settings = f": {primary['settings']}" if primary["settings"] else ""
            lines.append(f"   - *Primary reading:* {primary['label']}{settings} "
                         f"([why](APPENDIX.md#{p.paper}-readings)).")
        lines.append(f"   - *{'Why not' if h['verdict'] == 'not testable here' else 'Deciding numbers'}:* {h['reason']}")
        if h["readings"]:
            lines.append(f"   - *Robustness:* {h['robustness']}.")
    return "\n".join(lines) + "\n"


def headline_counts(rows: list[dict]) -> str:
    """``Headline claims: supported 2, partly 1, ...``: the headline rows by verdict."""
    heads = pd.Series([c["verdict"] for c in rows if c["role"] == "headline"], dtype=object).value_counts()
    if not len(heads):
        return "No headline claim"
    return "Headline claims: " + ", ".join(f"{k} {int(heads[k])}" for k in HEADLINE_VERDICTS if k in heads)


def draw_readings(p) -> None:
    """``<paper>/readings.png``: the verdict of each headline under each reading
    (:mod:`magexp.artifacts.plots.readings`), and the cells it draws in ``readings.csv``; none for a
    paper without headlines.
    """
    if p.headlines:
        (p.root / p.paper).mkdir(parents=True, exist_ok=True)
        write_csv(pd.DataFrame(readings_plot.cells(p.headlines), columns=["headline", "reading", "verdict", "primary"]),
                  p.root / p.paper / "readings.csv")
        save(readings_plot.draw(p.headlines, f"{p.meta.title}: each headline under each reading"),
             p.root / p.paper / "readings.png")


def counts(claims: list[dict], peers: list[str] = ()) -> str:
    """The counts of all papers' claims, each distinct claim once: the headline claims by verdict (under
    their primary readings), the papers' findings (the ``primary`` family's ``by: paper`` claims), magexp's
    own statements (with ``peers``: the outcomes of the MAGYC section's claims), and, counted apart, the
    re-tests under other readings (robustness), the exploratory claims and the sanity checks.
    """
    paper = [c["verdict"] for c in claims if _is_finding(c)]
    own = [c["verdict"] for c in claims if _is_statement(c)] + list(peers)
    retests = [c["verdict"] for c in claims if c.get("family") == "sensitivity"]
    explored = sum(c.get("family") == "exploratory" for c in claims)
    sanity = sum(c["role"] == "sanity" for c in claims)
    text = headline_counts(claims)
    text += f"; the papers' findings: {held(paper)}" if paper else ""
    text += f"; magexp's own statements: {held(own)}" if own else ""
    text += (f". Counted apart: re-tests of the headlines under their other readings (robustness): {held(retests)}"
             if retests else "")
    text += f"; exploratory settings (shown, never counted): {explored}" if explored else ""
    return text + (f"; sanity checks (true by construction): {sanity}" if sanity else "")


def _is_finding(c: dict) -> bool:
    """Whether claims row ``c`` is one of the papers' findings (the primary family, the paper's words)."""
    return c["role"] == "finding" and c["by"] == "paper" and c.get("family", "primary") == "primary"


def _is_statement(c: dict) -> bool:
    """Whether claims row ``c`` is one of magexp's own statements (counted, not a re-test)."""
    return c["role"] == "finding" and c["by"] == "magexp" and c.get("family", "magexp") in ("primary", "magexp")


def held(results: list[str]) -> str:
    """``k of n hold`` and how the others went (``contradicted 2, no difference detected 3``)."""
    others = pd.Series([r for r in results if r != HOLDS], dtype=object).value_counts()
    rest = ", ".join(f"{k} {int(others[k])}" for k in (FAILS, CONTRADICTED, NO_DIFFERENCE, UNDECIDED) if k in others)
    return f"{sum(r == HOLDS for r in results)} of {len(results)} hold" + (f" ({rest})" if rest else "")


def findings_table(p, *, appendix: bool = False) -> str:
    """The findings of a section: in the report the paper's own (the primary family; magexp's statements
    too where the section has no headline claim: it is magexp's own work), in the appendix magexp's
    statements of a paper section; a counts line of exactly the rows listed above each table.
    """
    own_here = appendix or not p.headlines
    found = [c for c in p.claims if (_is_statement(c) if appendix else _is_finding(c) or (own_here and _is_statement(c)))]
    if not found or (appendix and not p.headlines):
        return ""
    found.sort(key=lambda c: c["by"] != "paper")
    frame = pd.DataFrame(found)
    frame["claim"] = [f"{t} ({s})" if s else t for t, s in zip(frame.text, frame.section)]
    frame["result"] = frame.verdict.map(bold)
    where = ("" if own_here else " magexp's own statements on this paper's runs are listed in the "
             f"[appendix](APPENDIX.md#{p.paper}).")
    title = "### magexp's own statements\n\n" if appendix else "### Findings\n\n"
    legend = FINDINGS_LEGEND if appendix else f"({LEGENDS})"
    return (title + f"**{held(frame.verdict.tolist())}.** {legend}{where}"
            + "\n\n" + markdown_table(frame, ["by", "claim", "result", "reason"], names=["by", "claim", "result", "evidence"]))


def readings_section(p) -> str:
    """The appendix's account of each headline's readings, side by side: the primary first, with the
    paper's words that make it the most plausible, then every other reading with why it is less plausible;
    each with its source, settings and the verdict under it.
    """
    lines = []
    for h in (h for h in p.headlines if h["readings"]):
        lines.append(f"**{h['id']}** ({bold(h['verdict'])}; {h['robustness']}).\n")
        for r in sorted(h["readings"], key=lambda r: not r["primary"]):
            argued = (f"*Primary.* Why: {h['why']}" if r["primary"] else f"Less plausible: {r['less_plausible']}")
            lines.append(f"- {r['label']}: **{r['verdict']}**. Source: {r['source']}. Settings: "
                         f"{r['settings'] or 'as the source states'}. {argued}")
        lines.append("")
    if not lines:
        return ""
    return (f'<a id="{p.paper}-readings"></a>\n\n### Readings of what the paper leaves unstated\n\n'
            "Each headline is decided by its primary reading; the others test its robustness and never decide "
            f"(the verdict under each: {link(f'{p.paper}/readings', p.root)}).\n\n" + "\n".join(lines))

