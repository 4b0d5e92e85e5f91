"""The pages of the results website, as Markdown text keyed by their path under ``docs/``'s ``results/``.

The report's prose is written once, by :mod:`magexp.artifacts.report`, into ``REPORT.md`` and
``APPENDIX.md``; the site places those sections (split at their headings, never re-rendered) on one
page per paper and its sub-pages, with every link rewritten to the page it now lives on. The views
the report has no home for are built from the structured data (:mod:`magexp.site.data`): the landing
page's headline tables, each headline's readings side by side, and the claims explorer."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from magexp.artifacts.formats import HOW_TO_READ, PEERS_HEADING, SPEED_HEADING
from magexp.artifacts.paper_spec import load_paper, papers
from magexp.site.data import embedded_json, explorer_data, read_csv, readings

#: where the site's pages and the results' files live in the build (``site/results/...``)
PREFIX = "results"
#: a Markdown link or image: ``[text](target)`` (group 1 the target)
LINK = re.compile(r"(?<=\]\()([^)\s]+)(?=\))")
#: an artifact's subsection of the appendix: ``### name: title``
ARTIFACT = re.compile(r"^### (\w+): (.*)$")
#: the anchor the appendix puts before a paper's section and its readings
ANCHOR = re.compile(r'<a id="([\w-]+)"></a>')
#: the results' files the site carries (the figures and every CSV a page or the explorer links)
CARRIED = ("*.png", "*.csv")
#: every table of the MAGYC comparison (written by ``make peers-bench``), a page of its own
PEERS_TABLES = "peers/peers.md"


@dataclass
class Figure:
    """One figure of a paper, as the appendix gives it: its artifact, title, PNG and caption."""

    name: str
    title: str
    png: str
    caption: str


@dataclass
class Section:
    """One paper's parts of the report and the appendix, split at their headings."""

    paper: str
    title: str
    report: str = ""
    appendix: str = ""
    figures: list[Figure] = field(default_factory=list)


def split(text: str, marker: str = "## ") -> list[tuple[str, str]]:
    """``text`` cut before every line starting with ``marker``: ``[(heading, body), ...]`` (the text
    before the first heading under the heading '')."""
    parts, heading, body = [], "", []
    for line in text.splitlines():
        if line.startswith(marker):
            parts.append((heading, "\n".join(body)))
            heading, body = line[len(marker):].strip(), []
        else:
            body.append(line)
    parts.append((heading, "\n".join(body)))
    return parts


def demote(text: str) -> str:
    """A report section's headings one level up (``###`` to ``##``): the section becomes a page whose
    title is the ``#`` heading."""
    return re.sub(r"^#(#+) ", r"\1 ", text, flags=re.M)


def figures(appendix: str, paper: str) -> list[Figure]:
    """The figures of a paper's appendix section: each artifact subsection's image and the paragraph
    under it (its caption, with the measured values the report filled in)."""
    out = []
    for heading, body in split(appendix, "### "):
        match = ARTIFACT.match(f"### {heading}")
        if not match:
            continue
        paragraphs = [p.strip() for p in body.split("\n\n") if p.strip()]
        image = next((k for k, p in enumerate(paragraphs) if p.startswith(f"![{match.group(1)}]")), None)
        if image is None:
            continue
        after = paragraphs[image + 1] if image + 1 < len(paragraphs) else ""
        caption = "" if after.startswith("Data:") else after
        out.append(Figure(match.group(1), match.group(2), f"{paper}/{match.group(1)}.png", caption))
    return out


def sections(root: Path) -> list[Section]:
    """Each paper's section of ``REPORT.md`` and ``APPENDIX.md`` (found by its title), with its figures,
    in the papers' order; a paper with no section in the report is left out."""
    titles = {load_paper(p).title: p for p in papers()}
    report = dict(split((root / "REPORT.md").read_text()))
    appendix = dict(split((root / "APPENDIX.md").read_text()))
    out = []
    for title, paper in titles.items():
        if title not in report:
            continue
        text = appendix.get(title, "")
        out.append(Section(paper, title, report[title], text, figures(text, paper)))
    return out


#: a bold line that titles the table or list under it: ``**name** (note)``, then a blank line and a table or list
TABLE_TITLE = re.compile(r"^\*\*(.+?)\*\*(.*)\n\n(?=\||- )", re.M)
#: a paragraph the appendix opens with a claim's id in bold (``**ipso_more_accurate** (supported; ...``)
CLAIM_TITLE = re.compile(r"^\*\*(\w+)\*\* ", re.M)
#: the page of the report's legends, and the anchor every paper section links them by (``#how-to-read``)
LEGENDS, LEGENDS_ANCHOR = "how-to-read.md", "#" + HOW_TO_READ.removeprefix("## ").lower().replace(" ", "-")


def headed(text: str) -> str:
    """``text`` with each bold line that titles a table or list, and each paragraph opened by a claim's id in
    bold, made a heading: a long page of tables and readings has headings to jump by."""
    text = TABLE_TITLE.sub(lambda m: f"### {m.group(1).replace('`', '')}{m.group(2)}\n\n", text)
    return CLAIM_TITLE.sub(lambda m: f"### {m.group(1)}\n\n", text)


def overall(root: Path) -> str:
    """The report's ``**Overall.**`` paragraph, all its lines (the counts of every claim and compared number)."""
    return next((p.strip() for p in (root / "REPORT.md").read_text().split("\n\n") if p.startswith("**Overall.**")), "")


class Links:
    """Rewrites a link of the report or the appendix (relative to ``results/``) for the page it now lives on."""

    def __init__(self, secs: list[Section]):
        self.anchors = {}
        for s in secs:
            for anchor in ANCHOR.findall(s.appendix):
                self.anchors[anchor] = f"{s.paper}/appendix.md#{anchor}"
            self.anchors[s.paper] = f"{s.paper}/appendix.md"

    def target(self, target: str, depth: int) -> str:
        """Where ``target`` points from a page ``depth`` folders below ``results/``."""
        if re.match(r"[a-z]+:", target) or target.startswith("#") and target != LEGENDS_ANCHOR:
            return target
        path, _, anchor = target.partition("#")
        up = "../" * depth
        if path in ("", "REPORT.md") and f"#{anchor}" == LEGENDS_ANCHOR:
            return up + LEGENDS
        if path == "APPENDIX.md":
            return up + (self.anchors.get(anchor, "index.md") if anchor else "index.md")
        if path == "REPORT.md":
            return up + "index.md"
        return up + target

    def rewrite(self, text: str, depth: int) -> str:
        """``text`` with every link target rewritten (:meth:`target`)."""
        return LINK.sub(lambda m: self.target(m.group(1), depth), text)


def headline_table(paper: str, root: Path) -> str:
    """A paper's headline claims as one table for the landing page: claim, verdict under the primary
    reading, how many of its readings hold, its section of the paper."""
    rows = [r for r in read_csv(root / "claims.csv") if r["paper"] == paper and r["role"] == "headline"]
    if not rows:
        return "No headline claim.\n"
    lines = ["| claim | verdict | readings holding | where in the paper |", "|---|---|---|---|"]
    for r in rows:
        held = f"{r['readings_holding']} of {r['readings_total']}" if r["readings_total"] else ""
        lines.append(f"| {cell(r['text'])} | **{r['verdict']}** | {held} | {cell(r['section'])} |")
    return "\n".join(lines) + "\n"


def cell(text: str) -> str:
    """``text`` safe in one cell of a Markdown table (no pipe, no line break)."""
    return " ".join(str(text).split()).replace("|", "\\|")


def landing(secs: list[Section], root: Path) -> str:
    """The landing page: the Overall counts, then each paper's headline table and its pages."""
    lines = ["# Results\n", "The results of `make reproduce`, as committed under `results/`: each paper's "
             "headline claims with their verdicts under their primary readings, the paper's findings, its numbers "
             "beside ours, the deviations and every figure. Every claim and compared number is also in the "
             "[claims explorer](explorer.md), to filter and sort; the legends of every page: [how to read](how-to-read.md).\n",
             overall(root) + "\n"]
    for s in secs:
        lines += [f"## {s.title}\n", headline_table(s.paper, root),
                  f"[Claims and figures]({s.paper}/index.md) · [readings side by side]({s.paper}/readings.md) · "
                  f"[appendix]({s.paper}/appendix.md)\n"]
    lines += ["## Other pages\n", "[magexp beside MAGYC](peers.md) · [speed of the core](speed.md)\n"]
    return "\n".join(lines)


def paper_page(s: Section, links: Links) -> str:
    """A paper's page: its report section (headline claims first, then findings, compared numbers,
    deviations), then every figure with its caption."""
    body = demote(f"## {s.title}\n{s.report}")
    parts = [links.rewrite(body, 1), "\nEach headline under each of its readings: [readings side by side](readings.md).\n"]
    if s.figures:
        parts.append("## Figures\n")
    for f in s.figures:
        caption = links.rewrite(f.caption, 1) if f.caption else ""
        parts.append(f"### {f.name}: {f.title} {{#{f.name}}}\n\n![{f.name}](../{f.png}){{ loading=lazy }}\n\n{caption}\n\n"
                     f"Its tables and notes: [appendix](appendix.md#{f.name}).\n")
    return "\n".join(parts)


def appendix_page(s: Section, links: Links) -> str:
    """A paper's appendix sub-page: its readings, deviations, findings and sanity checks in full, and per
    artifact its tables and notes (the figure itself is on the paper page)."""
    text = links.rewrite(headed(demote(f"## {s.title}: appendix\n{s.appendix}")), 1)
    for f in s.figures:
        text = text.replace(f"## {f.name}: {f.title}\n", f"## {f.name}: {f.title} {{#{f.name}}}\n")
        text = text.replace(f"![{f.name}](../{f.png})", f"Figure and caption: [on the paper's page](index.md#{f.name}).")
    return text


def readings_page(s: Section, root: Path) -> str:
    """Each headline's verdict under each of its readings in one view, the primary marked, with why the
    primary is the most plausible and how the verdict fares under the others (claims.csv)."""
    lines = [f"# {s.title}: readings side by side\n", "A headline is decided under its primary reading (★) of what "
             "the paper leaves unstated; the other readings re-test it and never decide. Every reading's source and "
             "settings: [appendix](appendix.md).\n"]
    if (root / s.paper / "readings.png").exists():
        lines.append(f"![readings](../{s.paper}/readings.png){{ loading=lazy }}\n")
    for k, h in enumerate(readings(root, s.paper), 1):
        claim = h["claim"]
        lines.append(f"## {k}. {claim['id']}: {claim['verdict']}\n\n{cell(claim['text'])}\n")
        if h["readings"]:
            lines += ["| reading | verdict |", "|---|---|"]
            lines += [f"| {'★ ' if r['primary'] else ''}{cell(r['reading'])}{' (primary)' if r['primary'] else ''} "
                      f"| **{r['verdict']}** |" for r in h["readings"]]
            lines.append("")
        why = f"*Why the primary reading:* {cell(claim['why'])}\n\n" if claim["why"] else ""
        lines.append(f"{why}*Robustness:* {cell(claim['robustness']) or 'no other reading'}.\n")
    return "\n".join(lines)


def explorer_page(root: Path) -> str:
    """The claims explorer: every claim and compared number as JSON in the page (it works from
    ``file://``), drawn and filtered by ``explorer.js``."""
    return ("---\nhide:\n  - navigation\n  - toc\n---\n\n# Claims explorer\n\nEvery row of `results/claims.csv` and every compared number of "
            "`results/summary.csv` (a row with a paper value). Filter by the menus, sort by a column marked ↕, "
            "click a row for its full evidence, its figure and the CSVs of the runs it read.\n\n"
            "## Claims\n\n<div class=\"mx-explorer\" data-table=\"claims\"></div>\n\n"
            "## Compared numbers\n\n<div class=\"mx-explorer\" data-table=\"numbers\"></div>\n\n"
            f"<script type=\"application/json\" id=\"mx-data\">{embedded_json(explorer_data(root))}</script>\n")


def other_pages(root: Path, links: Links) -> dict[str, str]:
    """The pages of the report's sections that belong to no paper: magexp beside MAGYC, the speed of the core."""
    report = dict(split((root / "REPORT.md").read_text()))
    appendix = dict(split((root / "APPENDIX.md").read_text()))
    peers = PEERS_HEADING.removeprefix("## ")
    speed = next((h for h in appendix if h.startswith(SPEED_HEADING.removeprefix("## "))), None)
    out = {"peers.md": links.rewrite(demote(f"## {peers}\n{report.get(peers, '')}"), 0),
           "speed.md": links.rewrite(demote(f"## {speed}\n{appendix[speed]}"), 0) if speed else "# Speed of the core\n"}
    if (root / PEERS_TABLES).exists():  # the section links its every table
        out[PEERS_TABLES] = headed(demote((root / PEERS_TABLES).read_text()))
    return out


def pages(root: Path) -> dict[str, str]:
    """Every page of the site's results part: ``{path under results/: Markdown}``."""
    secs = sections(root)
    links = Links(secs)
    legends = dict(split((root / "REPORT.md").read_text())).get(HOW_TO_READ.removeprefix("## "), "")
    out = {"index.md": links.rewrite(landing(secs, root), 0), "explorer.md": explorer_page(root),
           LEGENDS: links.rewrite(demote(f"{HOW_TO_READ}\n{legends}"), 0)}
    for s in secs:
        out[f"{s.paper}/index.md"] = paper_page(s, links)
        out[f"{s.paper}/readings.md"] = readings_page(s, root)
        out[f"{s.paper}/appendix.md"] = appendix_page(s, links)
    out.update(other_pages(root, links))
    return out


def nav(root: Path) -> list:
    """The site's navigation entries for the results pages (mkdocs ``nav`` form)."""
    entries = [{"Overview": f"{PREFIX}/index.md"}, {"How to read": f"{PREFIX}/{LEGENDS}"},
               {"Claims explorer": f"{PREFIX}/explorer.md"}]
    for s in sections(root):
        entries.append({s.title: [{"Claims and figures": f"{PREFIX}/{s.paper}/index.md"},
                                  {"Readings side by side": f"{PREFIX}/{s.paper}/readings.md"},
                                  {"Appendix": f"{PREFIX}/{s.paper}/appendix.md"}]})
    peers = [{"Summary": f"{PREFIX}/peers.md"}] + ([{"Every table": f"{PREFIX}/{PEERS_TABLES}"}]
                                                   if (root / PEERS_TABLES).exists() else [])
    entries += [{"magexp beside MAGYC": peers}, {"Speed of the core": f"{PREFIX}/speed.md"}]
    return entries


def carried(root: Path) -> list[Path]:
    """The results' files the site copies (:data:`CARRIED`), relative to ``root``, sorted."""
    return sorted({p.relative_to(root) for pattern in CARRIED for p in root.rglob(pattern)})
