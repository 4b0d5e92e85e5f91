"""Assemble ``results/summary.csv``, ``results/claims.csv``, ``results/versions.csv``,
``results/REPORT.md`` and ``results/APPENDIX.md`` from the papers' parts.

``REPORT.md`` is claims first (at most :data:`MAX_LINES` lines and :data:`MAX_CHARS` characters,
no table cell over :data:`MAX_CELL`): per paper, (1) its headline claims with their verdicts
(:func:`headline_verdict`), reasons and figures, (2) magexp's own findings, (3) the compared
numbers (rows with a paper value), (4) the deviations. ``APPENDIX.md`` holds the rest: per
artifact its figure, caption, full summary table (``n/a`` rows too), table and notes (measured
values interpolated from the runs, :func:`magexp.artifacts.claims.interpolate`), the sanity checks and the
speed of the core. ``claims.csv`` has every claim (headline, finding, sanity) with its full evidence."""

from __future__ import annotations

import functools
import platform
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from magexp.artifacts.claims import (CONTRADICTED, FAILS, HOLDS, NO_DIFFERENCE, SHORT, UNDECIDED, adjust, evaluate,
                                     interpolate, shorten)
from magexp.artifacts.plots import readings as readings_plot
from magexp.artifacts.kind_tables import winners
from magexp.artifacts.plots.style import save
from magexp.artifacts.spec import ROUNDOFF_FLOOR, artifact_paths, load, load_paper, papers
from magexp.artifacts.summary import COLUMNS, NOT_COMPARED, VERDICTS, relative
from magexp.core.atomic import atomic_path, write_text
from magexp.errors import MagexpError
from magexp.paths import RESULTS, ROOT
from magexp.run import provenance

#: significant digits of every float written to a results CSV (round-off must not churn files)
DIGITS = 6
SUMMARY_SHOWN = ["quantity", "estimator", "setting", "truth", "paper_value", "judged_value", "judged_lo", "judged_hi",
                 "judged_runs", "judged_n", "success_rate", "truth_in_interval", "verdict", "rel_difference"]
#: limits of REPORT.md (the appendix holds the rest; the section "magexp beside MAGYC" links its claims table)
MAX_LINES, MAX_CHARS, MAX_CELL = 400, 60_000, 300
#: verdicts of a headline claim
HEADLINE_VERDICTS = ("supported", "partly", "contradicted", "depends", "not testable here", "by construction")
#: the line of ``results/peers/peers.md`` (written by ``make peers-bench``) that ends what REPORT.md shows of it
PEERS_MARK = "<!-- REPORT.md shows the text above this line; the tables below are in peers/peers.md only -->"
#: a column of wall times measured on this machine has this in its name (an artifact's table keeps them in
#: ``results/timing/``, :func:`magexp.artifacts.reproduce.split_timing`)
MEASURED = "wall_time"
#: the headings of the report's sections on what ``make reproduce`` does not write (``magexp verify`` leaves
#: them out unless both sides have their source)
PEERS_HEADING, SPEED_HEADING = "## magexp beside MAGYC", "## Speed of the core"
CLAIM_COLUMNS = ["paper", "artifact", "id", "by", "role", "section", "figure", "text", "verdict", "reason", "evidence",
                 "p", "p_adjusted", "p_min", "detectable", "seeds", "readings_total", "readings_holding"]


def _floats(column: pd.Series) -> np.ndarray | None:
    """The column as floats if it holds floats: a float column, or an object column whose values are
    floats and missing values (e.g. a truth that some rows lack); else None (text, integers, flags)."""
    if pd.api.types.is_float_dtype(column):
        return column.to_numpy(float)
    if column.dtype == object:
        present = [v for v in column if v is not None and not (isinstance(v, float) and np.isnan(v))]
        if present and all(isinstance(v, (float, np.floating)) for v in present):
            return np.array([np.nan if v is None else float(v) for v in column])
    return None


#: columns of probabilities: never floored as round-off (a p of 1e-22 is written as it is)
EXACT = ("p", "p_adjusted", "p_min")


def tidy(frame: pd.DataFrame, floor: float = ROUNDOFF_FLOOR) -> pd.DataFrame:
    """Float columns with magnitudes below ``floor`` (round-off, e.g. a noise-free RMS of 1e-11)
    written as ``±floor`` (not the :data:`EXACT` ones); every float then rounded to :data:`DIGITS`
    significant digits."""
    out = frame.copy()
    for col in out.columns:
        v = _floats(out[col])
        if v is not None:
            small = np.isfinite(v) & (v != 0) & (np.abs(v) < (0 if col in EXACT else floor))
            v = np.where(small, np.sign(v) * floor, v)
            with np.errstate(divide="ignore", invalid="ignore"):
                mag = np.where(np.isfinite(v) & (v != 0), np.floor(np.log10(np.abs(np.where(v == 0, 1, v)))), 0)
            scale = 10.0 ** (DIGITS - 1 - mag)
            out[col] = np.where(np.isfinite(v), np.round(v * scale) / scale, v)
    return out


def write_csv(frame: pd.DataFrame, path: Path) -> None:
    """A results CSV: :func:`tidy` values, ``%.6g`` floats (identical bytes on every fresh clone
    when only round-off differs)."""
    with atomic_path(path) as tmp:  # an interrupt leaves the old file or the new one
        tidy(frame).to_csv(tmp, index=False, float_format=f"%.{DIGITS}g")


def versions() -> dict:
    """The versions behind the results: python and the libraries (:mod:`magexp.run.provenance`) and
    ``magexp_commit``, the last commit that changed anything outside ``results/`` (so committing the
    regenerated results does not change the record, and a fresh clone writes the same bytes)."""
    try:
        commit = subprocess.run(["git", "log", "-1", "--format=%h", "--abbrev=12", "--", ".", ":(exclude)results"],
                                capture_output=True, text=True, check=True,
                                cwd=ROOT).stdout.strip() or provenance.commit()
    except (OSError, subprocess.CalledProcessError):
        commit = provenance.commit()
    libs = provenance.provenance()
    return {**{k: v for k, v in libs.items() if k not in ("magexp_commit", "config_hash", "commit")},
            "magexp_commit": commit}


def _fmt(v) -> str:
    if v is None or (isinstance(v, float) and not np.isfinite(v)):
        return ""
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, (float, np.floating)):
        return f"{v:.4g}"
    return str(v)


_LATEX = {"\\": r"\textbackslash{}", "&": r"\&", "%": r"\%", "$": r"\$", "#": r"\#", "_": r"\_", "{": r"\{",
          "}": r"\}", "~": r"\textasciitilde{}", "^": r"\textasciicircum{}"}


def _tex(text: str) -> str:
    return "".join(_LATEX.get(ch, ch) for ch in str(text))


def latex_table(frame: pd.DataFrame, columns: list[str]) -> str:
    """The same table as :func:`markdown_table`, as a LaTeX ``tabular`` with ``booktabs`` rules
    (``\\usepackage{booktabs}``), ready to ``\\input`` into a paper."""
    lines = [r"\begin{tabular}{" + "l" * len(columns) + "}", r"\toprule",
             " & ".join(_tex(c) for c in columns) + r" \\", r"\midrule"]
    lines += [" & ".join(_tex(_fmt(r[c])) for c in columns) + r" \\" for _, r in frame.iterrows()]
    return "\n".join(lines + [r"\bottomrule", r"\end{tabular}", ""])


def _cell(v) -> str:
    """A Markdown table cell: :func:`_fmt`, with ``|`` escaped and line breaks flattened."""
    return " ".join(_fmt(v).split()).replace("|", "\\|")


def markdown_table(frame: pd.DataFrame, columns: list[str], tex: Path | None = None, names: list[str] | None = None) -> str:
    """A Markdown table of ``columns`` (headed ``names``, default the columns); with ``tex``, its
    LaTeX twin (:func:`latex_table`) is written there. A table without rows is an error: the
    caller says in words that there is nothing to show."""
    if not len(frame):
        raise MagexpError(f"an empty table ({', '.join(columns)}) would be printed: say so in words instead")
    if tex is not None:
        write_text(tex, latex_table(frame, columns))
    head = "| " + " | ".join(names or columns) + " |\n|" + "---|" * len(columns) + "\n"
    return head + "".join("| " + " | ".join(_cell(r[c]) for c in columns) + " |\n" for _, r in frame.iterrows())


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


def read_runs(path: Path) -> pd.DataFrame:
    """A runs CSV, consolidated: ``read_csv`` leaves one block per column (95 in ``benchmark_heatmap``),
    a copy one per dtype, and the claims and the summary take rows from it hundreds of times (a
    selection of ``benchmark_heatmap``'s cells: 1.7 ms as read, 1.0 ms consolidated)."""
    return pd.read_csv(path).copy()


def _runs(root: Path, paper: str, name: str) -> pd.DataFrame | None:
    path = root / paper / f"{name}_runs.csv"
    return read_runs(path) if path.exists() else None


def _runs_reader(root: Path, paper: str):
    """``name -> runs table`` of ``paper``: each runs CSV read once, however many sections use it."""
    return functools.cache(lambda name: _runs(root, paper, name))


def _outcomes(specs: list, runs) -> list[tuple[str, object]]:
    """``(artifact, Outcome)`` of every claim of ``specs`` (one paper: one family of comparisons,
    Holm-adjusted by :func:`magexp.artifacts.claims.adjust`) whose runs table (``runs(name)``) has rows."""
    out = []
    for spec in specs:
        table = runs(spec.name) if spec.claims else None
        if table is not None and len(table):
            out += [(spec.name, evaluate(c, table)) for c in spec.claims]
    adjust([o for _, o in out])
    return out


def claim_outcomes(root: Path = RESULTS, paper: str | None = None) -> list[tuple[str, object]]:
    """``(artifact, Outcome)`` of every claim whose artifact has runs under ``root``."""
    return [o for p in ([paper] if paper else papers())
            for o in _outcomes([load(path) for path in artifact_paths(p)], _runs_reader(root, p))]


def headline_verdict(results: list[str | None]) -> str:
    """The verdict of a headline claim from its parts' outcomes (None: the part's artifact has no
    runs here): ``supported`` (every part holds), ``contradicted`` (none holds), ``partly``
    (some hold), ``not testable here`` (no part could be evaluated)."""
    known = [r for r in results if r is not None]
    if not known:
        return "not testable here"
    held = sum(r == HOLDS for r in known)
    if held == len(results):
        return "supported"
    return "contradicted" if held == 0 else "partly"


def readings_verdict(verdicts: list[tuple[str, str]]) -> tuple[str, str]:
    """The verdict of a headline judged under several readings of what its paper left unstated, from
    ``(label, verdict)`` per reading: the common verdict where every reading gives the same, else
    ``depends`` with the split, which names the readings on each side, each label quoted (``depends:
    supported under "w = 0.4", "c1 = c2 = 2"; contradicted under "constriction PSO"``; '' when they agree)."""
    order = {v: i for i, v in enumerate(HEADLINE_VERDICTS)}
    sides: dict[str, list[str]] = {}
    for label, verdict in verdicts:
        sides.setdefault(verdict, []).append(label)
    if len(sides) == 1:
        return verdicts[0][1], ""
    split = "; ".join(f"{v} under " + ", ".join(f'"{label}"' for label in labels)
                      for v, labels in sorted(sides.items(), key=lambda kv: order[kv[0]]))
    return "depends", f"depends: {split}"


def _reading_rows(h, outcomes: dict) -> list[dict]:
    """Each reading of headline ``h``: its label, source, parts and verdict (its parts' outcomes,
    :func:`headline_verdict`); none when ``h`` declares no readings."""
    rows = []
    for r in h.readings:
        parts = list(r.parts or h.parts)
        results = [outcomes[p].result if p in outcomes else None for p in parts]
        rows.append({"label": r.label, "source": " ".join(str(r.source).split()), "parts": parts,
                     "verdict": headline_verdict(results),
                     "outcomes": "; ".join(f"{p}: {res or 'no runs here'}" for p, res in zip(parts, results))})
    return rows


def headlines(paper: str, specs: list, outcomes: dict, runs) -> list[dict]:
    """Each headline claim of ``paper`` (``paper.yaml``) with its verdict, reason and figure
    (:func:`_headline_row`). ``outcomes``: ``{"artifact.id": Outcome}``; a part (of the headline or of
    a reading) naming no claim of the paper is an error."""
    declared = {f"{s.name}.{c.id}" for s in specs for c in s.claims}
    rows = []
    for h in load_paper(paper).headline:
        named = list(h.parts) + [p for r in h.readings for p in r.parts]
        unknown = [p for p in named if p not in declared]
        if unknown:
            raise MagexpError(f"{paper}/paper.yaml headline {h.id!r}: part {unknown[0]!r} names no claim of {paper} "
                              "(write <artifact>.<claim id>)")
        rows.append(_headline_row(paper, h, outcomes, runs))
    return rows


def _over_readings(h, verdict: str, readings: list[dict]) -> tuple[str, str]:
    """The verdict of headline ``h`` over its ``readings`` (:func:`readings_verdict`; ``verdict``, its
    own, when it has none) and the split ('' when they agree); a common ``supported`` of a headline
    that holds by construction reads ``by construction``."""
    if not readings:
        return verdict, ""
    verdict, split = readings_verdict([(r["label"], r["verdict"]) for r in readings])
    if not split and verdict == "supported" and str(h.construction).strip():
        verdict = "by construction"
    return verdict, split


def _headline_row(paper: str, h, outcomes: dict, runs) -> dict:
    """One headline's row. The reason is written whole (:func:`_headline_verdict`;
    ``tests/test_report.py`` holds it to :data:`magexp.artifacts.claims.SHORT` characters); the
    evidence is the reason followed by each reading's verdict and every part's outcome and full
    evidence. With ``readings:`` it is judged under each (:func:`readings_verdict`): a split verdict
    reads ``depends`` and its reason opens with the split; ``readings_total`` counts its readings (1:
    the headline's own parts only), ``readings_holding`` those under which it is supported;
    ``readings`` keeps each reading's verdict (for the figure)."""
    parts = [outcomes.get(p) for p in h.parts]
    verdict, reason = _headline_verdict(h, parts, runs)
    readings = _reading_rows(h, outcomes)
    verdict, split = _over_readings(h, verdict, readings)
    full = f"{split}. {reason}" if split else reason
    figure = h.figure or (f"{paper}/{h.parts[0].split('.')[0]}" if h.parts else "")
    evidence = " | ".join([full] + [f"reading {r['label']} ({r['source']}): {r['verdict']} ({r['outcomes']})"
                                    for r in readings]
                          + [f"{p}: {o.result} ({o.evidence})" for p, o in zip(h.parts, parts) if o])
    holding = sum(r["verdict"] == "supported" for r in readings) if readings else int(verdict == "supported")
    return {"paper": paper, "artifact": "", "id": h.id, "by": "paper", "role": "headline", "section": h.section,
            "figure": figure, "text": str(h.text).strip(), "verdict": verdict,
            "reason": full if len(full) <= SHORT else split or reason, "evidence": evidence,
            "readings_total": len(readings) or int(bool(h.parts)), "readings_holding": holding, "readings": readings}


def _headline_verdict(h, parts: list, runs) -> tuple[str, str]:
    """The verdict of headline ``h`` and its reason, from the outcomes ``parts`` of its parts (None:
    no runs here): its ``reason:`` template read on the runs of the first part's artifact, else each
    part's result and numbers; an untestable headline says why; one that is ``supported`` only by
    construction (``construction:`` says why) reads ``by construction``, never counted as supported."""
    if h.untestable:
        return "not testable here", str(h.untestable).strip()
    verdict = headline_verdict([o.result if o is not None else None for o in parts])
    if verdict == "supported" and str(h.construction).strip():
        verdict = "by construction"
    if h.reason and parts[0] is not None:
        return verdict, interpolate(" ".join(str(h.reason).split()), runs(h.parts[0].split(".")[0]))
    return verdict, "; ".join(f"{p.split('.')[1]}: {o.result if o else 'no runs here'}"
                              + (f" ({o.short})" if o else "") for p, o in zip(h.parts, parts))


def claim_rows(paper: str, specs: list, outcomes: list) -> list[dict]:
    """One ``claims.csv`` row per evaluated claim of ``paper`` (``p``, ``p_adjusted``, ``p_min`` and
    ``detectable`` for comparisons; ``detectable`` only where no difference is detected)."""
    own = {s.name: s for s in specs}
    return [{"paper": paper, "artifact": name, "id": o.claim.id, "by": o.claim.by, "role": o.claim.role,
             "section": o.claim.section, "figure": f"{paper}/{o.claim.figure or own[name].name}",
             "text": o.claim.text, "verdict": o.result, "reason": shorten(o.short), "evidence": o.evidence,
             "p": o.p, "p_adjusted": o.p_adjusted, "p_min": o.p_min,
             "detectable": o.detectable if o.result == NO_DIFFERENCE else np.nan, "seeds": o.n or np.nan}
            for name, o in outcomes]


def _link(figure: str, root: Path) -> str:
    """A Markdown link to a figure ``<paper>/<artifact>`` (its PNG), or '' if it was not drawn."""
    if not figure:
        return ""
    name = figure.split("/")[-1]
    return f"[{name}]({figure}.png)" if (root / f"{figure}.png").exists() else name


def _bold(verdict: str) -> str:
    return f"**{verdict}**" if verdict in ("contradicted", "partly", FAILS, CONTRADICTED, "differs") else verdict


class Paper:
    """One paper's parts, each read once: meta, specs, runs, summary rows, claim outcomes."""

    def __init__(self, paper: str, summary: pd.DataFrame, root: Path):
        self.paper, self.root = paper, root
        self.meta = load_paper(paper)
        self.specs = [load(path) for path in artifact_paths(paper)]
        self.runs = _runs_reader(root, paper)
        self.rows = summary[summary.paper == paper]
        self.outcomes = _outcomes(self.specs, self.runs)
        by_id = {f"{name}.{o.claim.id}": o for name, o in self.outcomes}
        self.headlines = headlines(paper, self.specs, by_id, self.runs)
        self.claims = claim_rows(paper, self.specs, self.outcomes)
        #: the claims that test a headline only under another reading than magexp's (the readings figure
        #: and claims.csv show them; the report's findings table leaves them out)
        self.reading_parts = {part for h in self.meta.headline for r in h.readings for part in r.parts} - {
            part for h in self.meta.headline for part in h.parts}


def _headline_table(p: Paper) -> str:
    if not p.headlines:
        return "No headline claim of this section is declared (`headline:` in its `paper.yaml`).\n"
    frame = pd.DataFrame(p.headlines)
    frame["claim"] = frame.text
    frame["verdict"] = frame.verdict.map(_bold)
    frame["figure"] = frame.figure.map(lambda f: _link(f, p.root))
    frame["readings"] = [f"{h} of {t} supported" if t else "" for h, t in zip(frame.readings_holding, frame.readings_total)]
    grid = (f"Each headline is judged under every plausible reading of a setting the paper leaves unstated "
            f"(`readings:` of its `paper.yaml`; `depends`: the readings split, the reason names each side); the "
            f"verdict under each reading: {_link(f'{p.paper}/readings', p.root)}.\n\n")
    return grid + markdown_table(frame, ["claim", "section", "verdict", "readings", "reason", "figure"])


def draw_readings(p: Paper) -> None:
    """``<paper>/readings.png``: the verdict of each headline under each reading
    (:mod:`magexp.artifacts.plots.readings`), and the cells it draws in ``readings.csv``; none for a
    paper without headlines."""
    if p.headlines:
        (p.root / p.paper).mkdir(parents=True, exist_ok=True)
        write_csv(pd.DataFrame(readings_plot.cells(p.headlines), columns=["headline", "reading", "verdict"]),
                  p.root / p.paper / "readings.csv")
        save(readings_plot.draw(p.headlines, f"{p.meta.title}: each headline under each reading"),
             p.root / p.paper / "readings.png")


def counts(claims: list[dict], peers: list[str] = ()) -> str:
    """The counts of a section (or of all, ``claims`` of every paper): the papers' headline claims by
    verdict, the papers' findings apart from magexp's own statements (with ``peers``: the outcomes of
    the MAGYC section's claims, magexp's too), and the sanity checks, which are not counted."""
    heads = pd.Series([c["verdict"] for c in claims if c["role"] == "headline"], dtype=object).value_counts()
    paper = [c["verdict"] for c in claims if c["role"] == "finding" and c["by"] == "paper"]
    own = [c["verdict"] for c in claims if c["role"] == "finding" and c["by"] == "magexp"] + list(peers)
    sanity = sum(c["role"] == "sanity" for c in claims)
    text = ("The papers' headline claims: " + ", ".join(f"{k} {int(heads.get(k, 0))}" for k in HEADLINE_VERDICTS)
            if len(heads) else "No headline claim")
    text += f"; the papers' findings: {_held(paper)}" if paper else ""
    text += f"; magexp's own statements: {_held(own)}" if own else ""
    return text + (f"; sanity checks (true by construction, not counted): {sanity}" if sanity else "")


def _held(results: list[str]) -> str:
    """``k of n hold`` and how the others went (``contradicted 2, no difference detected 3``)."""
    others = pd.Series([r for r in results if r != HOLDS], dtype=object).value_counts()
    rest = ", ".join(f"{k} {int(others[k])}" for k in (FAILS, CONTRADICTED, NO_DIFFERENCE, UNDECIDED) if k in others)
    return f"{sum(r == HOLDS for r in results)} of {len(results)} hold" + (f" ({rest})" if rest else "")


def _elsewhere(p: Paper) -> str:
    """What the findings table of the report leaves out: the claims that test a headline only under
    another reading than magexp's (:attr:`Paper.reading_parts`)."""
    n = sum(f"{c['artifact']}.{c['id']}" in p.reading_parts for c in p.claims)
    return (f" The {n} claims that test a headline under another reading of an unstated setting are in the "
            "readings figure and `claims.csv`.") if n else ""


def _listed(p: Paper, c: dict, own_here: bool, appendix: bool) -> bool:
    """Whether the findings table lists claim row ``c`` (:func:`_findings_table`)."""
    by_paper = c["by"] == "paper"
    return (c["role"] == "finding" and (by_paper or own_here) and not (appendix and by_paper)
            and f"{c['artifact']}.{c['id']}" not in p.reading_parts)


def _findings_table(p: Paper, *, appendix: bool = False) -> str:
    """The findings of a section: in the report the paper's own (and magexp's where the section has no
    headline claim: it is magexp's own work), in the appendix magexp's statements of a paper section."""
    own_here = appendix or not p.headlines
    found = [c for c in p.claims if _listed(p, c, own_here, appendix)]
    if not found or (appendix and not p.headlines):
        return ""
    found.sort(key=lambda c: c["by"] != "paper")
    frame = pd.DataFrame(found)
    frame["claim"] = [f"{t} ({s})" if s else t for t, s in zip(frame.text, frame.section)]
    frame["result"] = frame.verdict.map(_bold)
    frame["evidence"] = frame.reason.map(lambda r: shorten(r, 200))
    where = ("" if own_here else " magexp's own statements on this paper's runs are listed in the "
             f"[appendix](APPENDIX.md#{p.paper}).")
    title = "### magexp's own statements\n\n" if appendix else "### Findings\n\n"
    return (title + "*paper*: the paper's statement, checked; *magexp*: stated by this report, a test fails if one "
            "does not hold. A comparison holds only where its test separates the two sides at alpha 0.05 after "
            "Holm's correction over the section's comparisons; full evidence and p-values: "
            f"[`claims.csv`](claims.csv).{where}"
            + ("" if appendix else _elsewhere(p))
            + "\n\n" + markdown_table(frame, ["by", "claim", "result", "evidence"]))


#: a cell with more compared numbers than this (a parameter table) is one line of the report
COLLAPSE = 4


def _judged_text(r) -> str:
    """What a row's verdict used: ``median [lo, hi], <which runs> (n)``."""
    interval = f" [{_fmt(r.judged_lo)}, {_fmt(r.judged_hi)}]" if np.isfinite(r.judged_lo) else ""
    return f"{_fmt(r.judged_value)}{interval}, {r.judged_runs} ({int(r.judged_n)})"


def compared_rows(rows: pd.DataFrame) -> pd.DataFrame:
    """The report's rows of compared numbers (``label``, ``paper``, ``ours``, ``verdict``, ``reason``):
    one per summary row with a compared paper value, ``ours`` what its verdict used
    (:func:`_judged_text`), except that a cell with more than :data:`COLLAPSE` of them (a parameter
    table) becomes one line: its verdict counts, and the rows not reproduced (every row stays in the
    appendix and ``summary.csv``)."""
    out = []
    rows = rows[~rows.verdict.isin(NOT_COMPARED)]
    for _, cell in rows.groupby(["artifact", "estimator", "setting"], sort=False):
        if len(cell) <= COLLAPSE:
            out += [{"label": r.label, "paper": _fmt(r.paper_value), "ours": _judged_text(r),
                     "verdict": _bold(r.verdict), "reason": r.reason} for r in cell.itertuples()]
            continue
        first = cell.iloc[0]
        head = str(first.label).split(",", 1)
        name = head[0].rsplit(" ", 1)[0] if " " in head[0] else head[0]  # "RDPSO S11" -> "RDPSO"
        label = ", ".join([f"{name} ({len(cell)} values: {', '.join(cell.quantity.astype(str))})", *head[1:]])
        counts = cell.verdict.value_counts()
        verdict = ", ".join(_bold(f"{k} {int(counts[k])}") if k != "reproduced" else f"{k} {int(counts[k])}"
                            for k in VERDICTS if k in counts)
        others = cell[cell.verdict != "reproduced"]
        reason = "; ".join(f"{r.quantity} {r.verdict}: paper {_fmt(r.paper_value)}, ours {_fmt(r.judged_value)}"
                           + (f" ({relative(r.rel_difference)})" if r.verdict == "differs" else "")
                           for r in others.itertuples())
        runs = ", ".join(sorted(set(cell.judged_runs.astype(str))))
        out.append({"label": label, "paper": f"{len(cell)} values", "ours": f"{runs}: see appendix", "verdict": verdict,
                    "reason": shorten(reason or "every value reproduced", MAX_CELL, "the appendix")})
    return pd.DataFrame(out, columns=["label", "paper", "ours", "verdict", "reason"])


#: a ``differs`` row whose difference is below this fraction of its block's scale is counted apart
SMALL_DIFFERENCE = 0.01


def compared_counts(rows: pd.DataFrame) -> str:
    """The verdict counts of compared rows, ``differs`` split by its size on the block's scale and
    by a failed majority: ``reproduced 8, differs 4 (1 by less than 1 % of its scale; 2 on a failed
    majority), uninformative 4``; then the rows not compared."""
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
    rows = p.rows[p.rows.verdict != "n/a"]
    if not len(rows):
        return ""
    return ("### Compared numbers\n\n" + compared_counts(rows)
            + " (`uninformative` is not counted as reproduced; `not compared`: the row's reason says why). *ours*: "
            "the median and 2.5-97.5 % interval the verdict used, over the runs named (all seeds, or those of the "
            "paper run's outcome) and their number; a `differs` row gives its distance from the paper's value as a "
            "share of its block's scale (summary.csv `scale`); a parameter table is one line (all its rows: "
            f"[appendix](APPENDIX.md#{p.paper})). The {int((p.rows.verdict == 'n/a').sum())} rows without a paper "
            "value are in the appendix and [`summary.csv`](summary.csv).\n\n"
            + markdown_table(compared_rows(rows[rows.verdict != "not compared"]), ["label", "paper", "ours", "verdict", "reason"],
                             names=["quantity", "paper", "ours", "verdict", "reason"]))


def _deviations_section(meta, paper: str, root: Path, *, full: bool = False) -> str:
    """The deviations from the paper's text; in the report each cell is cut at :data:`MAX_CELL`
    characters (``full``: the appendix's whole text, with the LaTeX twin)."""
    if not meta.deviations:
        return ""
    cut = (lambda t: " ".join(t.split())) if full else (lambda t: shorten(" ".join(t.split()), MAX_CELL, "the appendix"))
    frame = pd.DataFrame([{"what": cut(d.text), "why": cut(d.reason)} for d in meta.deviations])
    return "### Deviations from the paper's text\n\n" + markdown_table(
        frame, ["what", "why"], tex=root / paper / "deviations.tex" if full else None)


def _winners_section(p: Paper) -> str:
    """magexp's "which method to pick": the winner per case of each artifact with a winners table."""
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
        parts.append(f"**{spec.title}** ({_link(f'{p.paper}/{spec.name}', p.root)}): lowest RMS offset error / "
                     "sqrt(tr CRB), a winner only where its 95 % CI lies below every other's, else the tied set.\n\n"
                     + markdown_table(best, ["case", "winner", "bound_ratio", "success_rate", "tied"]))
    return "### Which method to pick\n\n" + "\n".join(parts) if parts else ""


def _report_section(p: Paper) -> str:
    intro = " ".join(str(p.meta.intro).split())
    lines = [f"## {p.meta.title}\n", f"{intro}\n" if intro else "", "### Headline claims\n",
             f"**Counts.** {counts(p.headlines + p.claims)}.\n", _headline_table(p)]
    lines += [_findings_table(p), _winners_section(p), _compared_table(p), _deviations_section(p.meta, p.paper, p.root),
              f"Figures, notes, full tables and sanity checks: [appendix](APPENDIX.md#{p.paper}).\n"]
    return "\n".join(x for x in lines if x)


def _appendix_section(p: Paper) -> str:
    """A paper's appendix: sanity checks, then every artifact with its figure, caption, tables, notes."""
    lines = [f'<a id="{p.paper}"></a>\n', f"## {p.meta.title}\n", f"{str(p.meta.intro).strip()}\n",
             _deviations_section(p.meta, p.paper, p.root, full=True)]
    lines.append(_findings_table(p, appendix=True))
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
    """The seeds per cell of a runs table: ``"30"``, or ``"30 to 150"`` where a ``grow:`` rule gave
    some cells more."""
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
        ranked = frame if simulated else frame[frame.success_rate >= 0.5]
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
    table of ``root/peers/peers.md`` (the table under its ``**Claims**`` line; none without the file)."""
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


def build(root: Path = RESULTS) -> None:
    """Write ``root/summary.csv``, ``root/claims.csv``, ``root/versions.csv``, ``root/REPORT.md``
    and ``root/APPENDIX.md``."""
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
        "and where we depart from its text. " + RULE + " Figures, notes, full tables and sanity checks: "
        "[APPENDIX.md](APPENDIX.md); every row: [`summary.csv`](summary.csv); every claim with its full evidence: "
        "[`claims.csv`](claims.csv); versions: [`versions.csv`](versions.csv).\n",
        f"**Overall.** {counts(claims.to_dict('records'), peer_results(root))}. Compared numbers ("
        f"{len(compared)} of {len(summary)} summary rows have a paper value): {compared_counts(compared)}.\n",
    ]
    text += [_report_section(p) for p in parts]
    text.append(_peers_section(root))
    write_text(root / "REPORT.md", "\n".join(text))
    appendix = ["# magexp report: appendix\n", "Everything [REPORT.md](REPORT.md) leaves out: per artifact its figure, "
                "caption, every summary row (`n/a` rows too), its table and notes; per paper its sanity checks. "
                "Columns of the tables: see the README (`results/summary.csv`); `judged_*` are the median, interval, "
                "runs and their number that the verdict used.\n"]
    appendix += [_appendix_section(p) for p in parts]
    appendix.append(_speed_section(root))
    write_text(root / "APPENDIX.md", "\n".join(appendix))


if __name__ == "__main__":
    build(Path(sys.argv[1]) if len(sys.argv) > 1 else RESULTS)
