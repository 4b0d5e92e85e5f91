"""Assemble ``results/summary.csv``, ``results/claims.csv``, ``results/versions.csv``,
``results/REPORT.md`` and ``results/APPENDIX.md`` from the papers' parts.

``REPORT.md`` is claims first (each paper's section at most :data:`MAX_CHARS` characters, so a paper added makes
room for itself; the legends the sections share written once, in its section "How to read" (:func:`how_to_read`);
no text cut; no line over :data:`~magexp.artifacts.formats.LINE_LIMIT`): per paper, (1) its headline claims with
their verdicts under their primary readings, the deciding
numbers and their robustness (:mod:`magexp.artifacts.headlines`), (2) the paper's findings, (3) the compared
numbers (rows with a paper value), (4) the deviations. ``APPENDIX.md`` holds the rest: per
artifact its figure, caption, full summary table (``n/a`` rows too), table and notes (measured
values interpolated from the runs, :func:`magexp.artifacts.claims.interpolate`), the sanity checks and the
speed of the core. ``claims.csv`` has every claim (headline, finding, sanity) with its full evidence. Every CSV
and table is written in the formats of :mod:`magexp.artifacts.formats`."""

from __future__ import annotations

import functools
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from magexp.artifacts.claims import interpolate
from magexp.artifacts.formats import (HOW_TO_READ, PEERS_HEADING, SPEED_HEADING, fmt, latex_table, markdown_table,
                                     wrap_markdown, write_csv)
from magexp.artifacts.headlines import claim_rows, headlines, paper_outcomes, runs_reader
from magexp.artifacts.kinds.heatmap import winners
from magexp.artifacts.report_claims import (FINDINGS_LEGEND, HEADLINES_LEGEND, LEGENDS, bold, counts, draw_readings,
                                            findings_table, headline_list, link, readings_section)
from magexp.artifacts.spec import load
from magexp.artifacts.paper_spec import artifact_paths, load_paper, papers
from magexp.artifacts.summary import COLUMNS, NOT_COMPARED, VERDICTS, relative
from magexp.core.atomic import atomic_path, write_text
from magexp.core.outcomes import succeeded_majority
from magexp.errors import MagexpError
from magexp.paths import RESULTS, ROOT
from magexp.run import provenance

SUMMARY_SHOWN = ["quantity", "estimator", "setting", "truth", "paper_value", "judged_value", "judged_lo", "judged_hi",
                 "judged_runs", "judged_n", "success_rate", "truth_in_interval", "verdict", "rel_difference"]
#: the budget of each section of REPORT.md (a paper's; the appendix holds the rest; the section "magexp beside
#: MAGYC" links its claims table; the legends every paper shares are written once, in "How to read"): a
#: reviewer reads one in a few minutes, and a paper added brings its own budget (:func:`over_budget` names a
#: section over it and by how much). Characters measure reading, not source lines, which depend on where
#: :func:`~magexp.artifacts.formats.wrap_markdown` wraps
MAX_CHARS = 30_000
#: the whole of REPORT.md's lines: claims first, the rest in the CSVs and the appendix
MAX_REPORT_LINES = 400
#: the line of ``results/peers/peers.md`` (written by ``make peers-bench``) that ends what REPORT.md shows of it
PEERS_MARK = "<!-- REPORT.md shows the text above this line; the tables below are in peers/peers.md only -->"
CLAIM_COLUMNS = ["paper", "artifact", "id", "by", "role", "section", "figure", "text", "verdict", "reason", "evidence",
                 "family", "level", "p", "p_adjusted", "p_min", "detectable", "observed", "seeds", "effect",
                 "seeds_planned", "primary_reading", "why", "robustness", "readings_total", "readings_holding"]


def versions() -> dict:
    """The versions behind the results: python and the libraries (:mod:`magexp.run.provenance`) and
    ``magexp_commit``, the last commit that changed anything outside ``results/`` (so committing the
    regenerated results does not change the record, and a fresh clone writes the same bytes).
    """
    try:
        commit = subprocess.run(["git", "log", "-1", "--format=%h", "--abbrev=12", "--", ".", ":(exclude)results"],
                                capture_output=True, text=True, check=True,
                                cwd=ROOT).stdout.strip() or provenance.commit()
    except (OSError, subprocess.CalledProcessError):
        commit = provenance.commit()
    libs = provenance.provenance()
    return {**{k: v for k, v in libs.items() if k not in ("magexp_commit", "config_hash", "commit")},
            "magexp_commit": commit}


def collect(root: Path = RESULTS) -> pd.DataFrame:
    """Every paper's summary part, in the papers' order."""
    parts = []
    for paper in papers():
        path = root / paper / "summary.csv"
        if path.exists() and path.stat().st_size > 0:
            part = pd.read_csv(path, keep_default_na=False, na_values=[""])
            parts.append(part.reindex(columns=COLUMNS))
    if not parts:
        return pd.DataFrame(columns=COLUMNS)
    return pd.concat(parts, ignore_index=True)[COLUMNS]


class Paper:
    """One paper's parts, each read once: meta, specs, runs, summary rows, claim outcomes."""

    def __init__(self, paper: str, summary: pd.DataFrame, root: Path):
        self.paper, self.root = paper, root
        self.meta = load_paper(paper)
        self.specs = [load(path) for path in artifact_paths(paper)]
        self.runs = runs_reader(root, paper)
        self.rows = summary[summary.paper == paper]
        self.outcomes = paper_outcomes(self.specs, self.runs)
        by_id = {f"{name}.{o.claim.id}": o for name, o in self.outcomes}
        self.headlines = headlines(paper, self.specs, by_id, self.runs)
        self.claims = claim_rows(paper, self.specs, self.outcomes)

    @functools.cached_property
    def winners(self) -> str:
        """Its "which method to pick" section (:func:`_winners_section`), its CSVs read once for the report's
        pointer and the appendix."""
        return _winners_section(self)


#: a cell with more compared numbers than this (a parameter table) is one line of the report
COLLAPSE = 4


def _judged_text(r) -> str:
    """What a row's verdict used: ``median [lo, hi], <which runs> (n)``."""
    interval = f" [{fmt(r.judged_lo)}, {fmt(r.judged_hi)}]" if np.isfinite(r.judged_lo) else ""
    return f"{fmt(r.judged_value)}{interval}, {r.judged_runs} ({int(r.judged_n)})"


def compared_rows(rows: pd.DataFrame) -> pd.DataFrame:
    """The report's rows of compared numbers (``label``, ``paper``, ``ours``, ``verdict``, ``reason``):
    one per summary row with a compared paper value, ``ours`` what its verdict used
    (:func:`_judged_text`), except that a cell with more than :data:`COLLAPSE` of them (a parameter
    table) becomes one line: its verdict counts, and the rows not reproduced (every row stays in the
    appendix and ``summary.csv``).
    """
    out = []
    rows = rows[~rows.verdict.isin(NOT_COMPARED)]
    for _, cell in rows.groupby(["artifact", "estimator", "setting"], sort=False):
        if len(cell) <= COLLAPSE:
            out += [{"label": r.label, "paper": fmt(r.paper_value), "ours": _judged_text(r),
                     "verdict": bold(r.verdict), "reason": r.reason} for r in cell.itertuples()]
            continue
        first = cell.iloc[0]
        head = str(first.label).split(",", 1)
        name = head[0].rsplit(" ", 1)[0] if " " in head[0] else head[0]  # "RDPSO S11" -> "RDPSO"
        label = ", ".join([f"{name} ({len(cell)} values: {', '.join(cell.quantity.astype(str))})", *head[1:]])
        counts = cell.verdict.value_counts()
        verdict = ", ".join(bold(f"{k} {int(counts[k])}") if k != "reproduced" else f"{k} {int(counts[k])}"
                            for k in VERDICTS if k in counts)
        others = cell[cell.verdict != "reproduced"]
        reason = "; ".join(f"{r.quantity} {r.verdict}: paper {fmt(r.paper_value)}, ours {fmt(r.judged_value)}"
                           + (f" ({relative(r.rel_difference)})" if r.verdict == "differs" else "")
                           for r in others.itertuples())
        runs = ", ".join(sorted(set(cell.judged_runs.astype(str))))
        out.append({"label": label, "paper": f"{len(cell)} values", "ours": f"{runs}: see appendix", "verdict": verdict,
                    "reason": reason or "every value reproduced"})
    return pd.DataFrame(out, columns=["label", "paper", "ours", "verdict", "reason"])


#: a ``differs`` row whose difference is below this fraction of its block's scale is counted apart
SMALL_DIFFERENCE = 0.01


def compared_counts(rows: pd.DataFrame) -> str:
    """The verdict counts of compared rows, ``differs`` split by its size on the block's scale and
    by a failed majority: ``reproduced 8, differs 4 (1 by less than 1 % of its scale; 2 on a failed
    majority), uninformative 4``; then the rows not compared.
    """
    counts = rows.verdict.value_counts()
    differs = rows[rows.verdict == "differs"]
    small = int((differs.rel_difference < SMALL_DIFFERENCE).sum())
    failed = int(differs.reason.astype(str).str.contains("failed majority").sum())
    split = [f"{small} of them by less than {100 * SMALL_DIFFERENCE:g} % of their scale"] if small else []
    split += [f"{failed} on a failed majority of our runs"] if failed else []
    parts = [f"{k} {int(counts.get(k, 0))}" + (f" ({'; '.join(split)})" if k == "differs" and split else "")
             for k in VERDICTS if k not in NOT_COMPARED]
    skipped = int(counts.get("not compared", 0))
    return ", ".join(parts) + (f"; not compared {skipped}" if skipped else "")


def _compared_table(p: Paper) -> str:
    """The report's table of compared numbers of paper ``p`` ('' when it has none)."""
    rows = p.rows[p.rows.verdict != "n/a"]
    if not len(rows):
        return ""
    return ("### Compared numbers\n\n" + compared_counts(rows)
            + f" ({LEGENDS}). The {int((p.rows.verdict == 'n/a').sum())} rows without a paper value, and every row of "
            f"a parameter table: [appendix](APPENDIX.md#{p.paper}), [`summary.csv`](summary.csv).\n\n"
            + markdown_table(compared_rows(rows[rows.verdict != "not compared"]), ["label", "paper", "ours", "verdict", "reason"],
                             names=["quantity", "paper", "ours", "verdict", "reason"]))


def _deviations_section(meta, paper: str, root: Path, *, full: bool = False) -> str:
    """The deviations from the paper's text, whole (``full``: with the LaTeX twin, for the appendix)."""
    if not meta.deviations:
        return ""
    frame = pd.DataFrame([{"what": " ".join(d.text.split()), "why": " ".join(d.reason.split())} for d in meta.deviations])
    return "### Deviations from the paper's text\n\n" + markdown_table(
        frame, ["what", "why"], tex=root / paper / "deviations.tex" if full else None)


def _winners_section(p: Paper) -> str:
    """magexp's "which method to pick": the winner per case of each artifact with a winners table (in the
    appendix: the report, read first, holds the claims and links these tables)."""
    parts = []
    for spec in p.specs:
        path = p.root / p.paper / f"{spec.name}.csv"
        if not spec.report_table or not path.exists():
            continue
        frame = pd.read_csv(path)
        if "case" not in frame or "bound_ratio_hi" not in frame:
            continue
        best = winners(frame)
        if not len(best):
            continue
        legends = LEGENDS.replace("](#", "](REPORT.md#")  # the legend lives in the report
        parts.append(f"**{spec.title}** ({link(f'{p.paper}/{spec.name}', p.root)}; {legends})\n\n"
                     + markdown_table(best, ["case", "winner", "bound_ratio", "success_rate", "tied"]))
    return "### Which method to pick\n\n" + "\n".join(parts) if parts else ""


def _report_section(p: Paper) -> str:
    """The report's section of paper ``p``: headlines, findings, winners, compared numbers, deviations."""
    intro = " ".join(str(p.meta.intro).split())
    lines = [f"## {p.meta.title}\n", f"{intro}\n" if intro else "", "### Headline claims\n", headline_list(p)]
    winners = ("### Which method to pick\n\nThe winner per case of each benchmark table: "
               f"[appendix](APPENDIX.md#{p.paper}-which-method-to-pick).\n") if p.winners else ""
    lines += [findings_table(p), winners, _compared_table(p), _deviations_section(p.meta, p.paper, p.root),
              f"Figures, notes, full tables and sanity checks: [appendix](APPENDIX.md#{p.paper}).\n"]
    return "\n".join(x for x in lines if x)


def _appendix_section(p: Paper) -> str:
    """A paper's appendix: sanity checks, then every artifact with its figure, caption, tables, notes."""
    lines = [f'<a id="{p.paper}"></a>\n', f"## {p.meta.title}\n", f"{str(p.meta.intro).strip()}\n",
             readings_section(p), _deviations_section(p.meta, p.paper, p.root, full=True)]
    lines.append(findings_table(p, appendix=True))
    if p.winners:
        lines.append(f'<a id="{p.paper}-which-method-to-pick"></a>\n\n{p.winners}\n')
    frame = pd.DataFrame(p.claims) if p.claims else pd.DataFrame(columns=CLAIM_COLUMNS)
    sanity = frame[frame.role == "sanity"]
    if len(sanity):
        lines.append("### Sanity checks\n\nStatements that hold by construction or check magexp's implementation; "
                     "never counted as findings.\n\n" + markdown_table(sanity, ["artifact", "text", "verdict", "reason"],
                                                                        names=["artifact", "check", "result", "evidence"]))
    if len(frame):
        write_text(p.root / p.paper / "claims.tex", latex_table(frame, ["artifact", "by", "role", "text", "verdict"]))
    for spec in p.specs:
        if not (p.root / p.paper / f"{spec.name}.png").exists():
            continue
        table = p.runs(spec.name)
        lines.append(f"### {spec.name}: {spec.title}\n")
        lines.append(f"![{spec.name}]({p.paper}/{spec.name}.png)\n")
        if spec.caption:
            lines.append(f"{_prose(spec, spec.caption, table, p.runs, p.specs)}\n")
        timing = (f", wall times on this machine: [`timing/{spec.name}.csv`](timing/{spec.name}.csv)"
                  if (p.root / "timing" / f"{spec.name}.csv").exists() else "")
        lines.append(f"Data: [`{p.paper}/{spec.name}.csv`]({p.paper}/{spec.name}.csv), "
                     f"runs: [`{p.paper}/{spec.name}_runs.csv`]({p.paper}/{spec.name}_runs.csv){timing}.\n")
        art = p.rows[p.rows.artifact == spec.name]
        if len(art):
            lines.append(markdown_table(art, SUMMARY_SHOWN, tex=p.root / p.paper / f"{spec.name}_summary.tex"))
        if spec.report_table:
            lines.append(_artifact_table(spec, p.root / p.paper / f"{spec.name}.csv"))
        if spec.notes:
            lines.append(f"\n{_prose(spec, spec.notes, table, p.runs, p.specs)}\n")
    return "\n".join(lines)


#: ``{seeds:<artifact>}`` in a caption: the seeds of another artifact's runs (of the same paper)
_SEEDS_OF = re.compile(r"\{seeds:(\w+)\}")


def seed_count(table: pd.DataFrame) -> str:
    """The seeds per cell of a runs table: ``"30"``, or ``"30 to 150"`` where a comparison's ``effect:``
    gave some cells more (:mod:`magexp.artifacts.power`).
    """
    per = table.groupby("cell").seed.nunique() if "cell" in table else pd.Series([table.seed.nunique()])
    lo, hi = int(per.min()), int(per.max())
    return str(hi) if lo == hi else f"{lo} to {hi}"


def _prose(spec, text: str, table: pd.DataFrame | None, runs=None, specs=()) -> str:
    """A caption or note with its measured values filled in: ``{seeds}`` (the seeds per cell of its runs,
    :func:`seed_count`),
    ``{seeds:<artifact>}`` (the seeds of that artifact's runs, ``runs(name)``: a caption pointing to
    another artifact's table; the seeds that artifact's spec declares, among ``specs``, where its runs
    are not in this output folder, as after ``reproduce --only``) and every ``{stat:metric@selection:format}`` field
    (:func:`magexp.artifacts.claims.interpolate`; a field whose selection has no value fails the build,
    naming the artifact and the field)."""
    seeds = seed_count(table) if table is not None and "seed" in table else str(spec.seeds)
    text = str(text).strip().replace("{seeds}", seeds)

    def seeds_of(m: re.Match) -> str:
        other = runs(m.group(1)) if runs is not None else None
        if other is not None and "seed" in other:
            return seed_count(other)
        declared = [s.seeds for s in specs if s.name == m.group(1)]
        if not declared:
            raise MagexpError(f"{spec.name}: caption field {m.group(0)!r}: {m.group(1)!r} is no artifact of this paper")
        return str(declared[0])

    text = _SEEDS_OF.sub(seeds_of, text)
    if table is None:
        return text
    try:
        return interpolate(text, table)
    except MagexpError as exc:
        raise MagexpError(f"{spec.name}: {exc}") from None


def _artifact_table(spec, path: Path) -> str:
    """The artifact's own CSV as a table (columns ``report_table``), and the winner per case."""
    frame = pd.read_csv(path)
    cols = [c for c in spec.report_table if c in frame]
    if not len(frame) or not cols:
        return ""
    text = markdown_table(frame, cols, tex=path.with_name(f"{spec.name}_table.tex"))
    by = "bound_ratio" if "bound_ratio_hi" in frame and frame.bound_ratio_hi.notna().any() else spec.plot.get("metric")
    if "case" in frame and by and f"{by}_hi" in frame:  # recordings: no bound, the held-out spread
        simulated = by == "bound_ratio"
        what = "RMS offset error / sqrt(tr CRB)" if simulated else str(by).replace("_", " ")
        among = "" if simulated else "; among the estimators that succeed on at least half the runs"
        ranked = frame if simulated else frame[succeeded_majority(frame.success_rate)]
        best = winners(ranked, by)
        if not len(best):
            return text + f"\nNo case has a winner: no estimator has an interval of its {what}{among}.\n"
        text += (f"\n**Winner per case** (lowest {what}; declared only where its 95 % interval lies below every "
                 f"other estimator's; else no winner, and the estimators whose intervals overlap the best{among}):\n\n"
                 + markdown_table(best, ["case", "winner", by, f"{by}_lo", f"{by}_hi", "success_rate",
                                         "tied"], tex=path.with_name(f"{spec.name}_winners.tex")))
    return text


def peer_results(root: Path) -> list[str]:
    """The results of the claims of the section "magexp beside MAGYC": the second column of the claims
    table of ``root/peers/peers.md`` (the table under its ``**Claims**`` line; none without the file).
    """
    path = root / "peers" / "peers.md"
    if not path.exists():
        return []
    lines = path.read_text().split(PEERS_MARK)[0].splitlines()
    start = next((i for i, line in enumerate(lines) if line.startswith("**Claims** (")), len(lines))
    table = []
    for line in lines[start + 1:]:
        if line.startswith("|"):
            table.append(line)
        elif table:
            break
    return [row.split("|")[2].strip() for row in table[2:]]


def _peers_section(root: Path) -> str:
    """The section "magexp beside MAGYC": its counts (:func:`peer_results`, magexp's own statements),
    the headline and the count of claims that hold from ``root/peers/peers.md`` (the text above
    :data:`PEERS_MARK` up to its first table), the figure, and a link to the claims table and the rest
    (its claims are computed by :mod:`magexp.perf.peers`, which ``make peers-bench`` runs; ``make
    reproduce`` never writes ``results/peers``), or one line when the bench has not been run."""
    path = root / "peers" / "peers.md"
    if not path.exists():
        return (f"{PEERS_HEADING}\n\nSkipped: `results/peers/peers.md` is absent (`make peers` builds the "
                "peer's environment, `make peers-bench` runs the bench).\n")
    lines = path.read_text().split(PEERS_MARK)[0].rstrip().splitlines()
    first_table = next((i for i, line in enumerate(lines) if line.startswith("|")), len(lines))
    lines = [line.split(";")[0] + "; their table and rule: [`peers/peers.md`](peers/peers.md))."
             if line.startswith("**Claims** (") else line for line in lines[:first_table]]
    lines.insert(1, f"\n**Counts.** {counts([], peer_results(root))}.")
    text = "\n".join(lines).rstrip()
    figure = "![peers](peers/peers.png)\n\n" if (root / "peers" / "peers.png").exists() else ""
    return f"{text}\n\n{figure}Every table and note: [`peers/peers.md`](peers/peers.md); every run: [`peers/peers.csv`](peers/peers.csv).\n"


def _speed_section(root: Path) -> str:
    """The appendix's speed section from ``bench.csv`` ('' without one: only ``make bench`` writes it)."""
    path = root / "bench.csv"
    if not path.exists():
        return ""
    frame = pd.read_csv(path)
    cols = [c for c in ("measure", "estimator", "value", "unit", "lo", "hi") if c in frame]
    return (f"{SPEED_HEADING} (`make bench`)\n\nMeasured by `make bench` on this machine, side by side in one "
            "run (variants alternating, one BLAS thread): medians with the interquartile range (`lo`-`hi`), or a "
            "95 % interval for success rates ([`bench.csv`](bench.csv); the sections are described in the README)."
            "\n\n" + markdown_table(frame, cols, tex=root / "bench.tex"))


RULE = ("The verdict of a compared number is one rule, applied in order: `differs` when the paper's value lies "
        "outside the interval of our runs (2.5-97.5 % over seeds, widened only by its printing precision; a paper "
        "run that succeeded or failed is judged against our runs of the same outcome, a parameter against our "
        "successful runs), or inside but with most of our runs failed; `uninformative` when inside, but the "
        "interval cannot exclude values far from the paper's (a ratio matched only by ratios with a failed run on "
        "one side, a parameter whose interval spans half its search range or more than 15 % of its block's scale, "
        "any other value whose interval is wider than the value itself, or an entry marked `informative: false`); "
        "else `reproduced`. `not compared`: a number the artifact says is not comparable (its reason says why).")


#: what :data:`RULE` adds where a paper's value is a statistic over its own trials (:mod:`magexp.artifacts.monte_carlo`)
MONTE_CARLO_RULE = (" A paper's value that is a median or a mean over its own trials (`statistic`, `trials`) is judged "
                    "against the interval in which that statistic over as many runs like ours falls (a two-stage "
                    "bootstrap), not against the spread of single runs.")


def rule(summary: pd.DataFrame) -> str:
    """:data:`RULE`, with :data:`MONTE_CARLO_RULE` where a row of ``summary`` judges such a value."""
    mc = "judged_runs" in summary and summary.judged_runs.astype(str).str.contains("trials (bootstrap)", regex=False).any()
    return RULE + (MONTE_CARLO_RULE if mc else "")


#: the legend of the compared numbers after :func:`rule` (once in REPORT.md, under "How to read")
COMPARED_LEGEND = ("`uninformative` is not counted as reproduced. *ours*: the "
                   "median and 2.5-97.5 % interval the verdict used, over the runs named (all seeds, or those of the "
                   "paper run's outcome) and their number; a `differs` row gives its distance from the paper's value "
                   "as a share of its block's scale (summary.csv `scale`); a cell with more than "
                   f"{COLLAPSE} compared numbers (a parameter table) is one line.")
#: the legend of the winners tables (once in REPORT.md, under "How to read")
WINNERS_LEGEND = ("magexp's own pick per case: the estimator with the lowest RMS offset error / sqrt(tr CRB), a winner "
                  "only where its 95 % CI lies below every other's, else the tied set.")


def how_to_read(summary: pd.DataFrame) -> str:
    """The section "How to read" of REPORT.md: the legends every paper's section shares, written once (issue 44:
    1,700 characters a paper before) and linked from each part (:data:`~magexp.artifacts.report_claims.LEGENDS`)."""
    return (f"{HOW_TO_READ}\n\nThe legends of the parts of every paper's section below (each part links here).\n\n"
            f"### Headline claims\n\n{HEADLINES_LEGEND}\n\n### Findings\n\n{FINDINGS_LEGEND}\n\n"
            f"### Compared numbers\n\n{rule(summary)} {COMPARED_LEGEND}\n\n### Which method to pick\n\n{WINNERS_LEGEND}\n")


def section_sizes(text: str) -> dict[str, int]:
    """``{heading: characters}`` of each section of a report's Markdown (split at its ``## `` headings; the
    opening under its ``# `` title)."""
    return {section.splitlines()[0].lstrip("# "): len(section) for section in text.split("\n## ")}


def over_budget(text: str, limit: int = MAX_CHARS) -> list[str]:
    """One line per section of ``text`` longer than ``limit`` characters (:data:`MAX_CHARS`), naming it and by
    how much: what a failing size test prints."""
    return [f"section {name!r} has {n:,} characters: {n - limit:,} over its budget of {limit:,} (MAX_CHARS, "
            "magexp/artifacts/report.py)" for name, n in section_sizes(text).items() if n > limit]


def build(root: Path = RESULTS) -> None:
    """Write ``root/summary.csv``, ``root/claims.csv``, ``root/versions.csv``, ``root/REPORT.md``
    and ``root/APPENDIX.md``.
    """
    summary = collect(root)
    write_csv(summary, root / "summary.csv")
    record = versions()
    with atomic_path(root / "versions.csv") as tmp:
        pd.DataFrame([{"package": k, "version": v} for k, v in record.items()]).to_csv(tmp, index=False)
    parts = [Paper(p, summary, root) for p in papers() if (summary.paper == p).any() or (root / p).is_dir()]
    for p in parts:
        draw_readings(p)
    claims = pd.DataFrame([r for p in parts for r in p.headlines + p.claims], columns=CLAIM_COLUMNS)
    write_csv(claims, root / "claims.csv")
    compared = summary[summary.verdict != "n/a"]
    text = [
        "# magexp report\n",
        "Every number below is regenerated by `make reproduce` (one paper: `make reproduce-<paper>`). Per paper: "
        "its headline claims and whether our runs support them, the paper's findings and magexp's own statements, "
        "the paper's numbers beside ours, "
        "and where we depart from its text; their legends, written once: [How to read](#how-to-read). Figures, "
        "notes, full tables and sanity checks: "
        "[APPENDIX.md](APPENDIX.md); every row: [`summary.csv`](summary.csv); every claim with its full evidence: "
        "[`claims.csv`](claims.csv); versions: [`versions.csv`](versions.csv).\n",
        f"**Overall.** {counts(claims.to_dict('records'), peer_results(root))}. Compared numbers ("
        f"{len(compared)} of {len(summary)} summary rows have a paper value): {compared_counts(compared)}.\n",
    ]
    text.append(how_to_read(summary))
    text += [_report_section(p) for p in parts]
    text.append(_peers_section(root))
    write_text(root / "REPORT.md", wrap_markdown("\n".join(text)))
    appendix = ["# magexp report: appendix\n", "Everything [REPORT.md](REPORT.md) leaves out: per artifact its figure, "
                "caption, every summary row (`n/a` rows too), its table and notes; per paper its sanity checks. "
                "Columns of the tables: see the README (`results/summary.csv`); `judged_*` are the median, interval, "
                "runs and their number that the verdict used.\n"]
    appendix += [_appendix_section(p) for p in parts]
    appendix.append(_speed_section(root))
    write_text(root / "APPENDIX.md", wrap_markdown("\n".join(appendix)))


if __name__ == "__main__":
    build(Path(sys.argv[1]) if len(sys.argv) > 1 else RESULTS)
