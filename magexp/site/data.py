"""The structured data of the results website: the explorer's rows (every row of ``results/claims.csv``,
every compared number of ``results/summary.csv``) with the filters' options derived from them, and
each headline's verdict under each of its readings (``results/<paper>/readings.csv``)."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

from magexp.artifacts.paper_spec import load_paper

#: the explorer's claim filters and the columns it sorts by (issue 43 item 2)
CLAIM_FILTERS = ["paper", "role", "verdict", "reading"]
CLAIM_SORTS = ["p", "p_adjusted"]
#: the explorer's compared-number filters and sorts
NUMBER_FILTERS = ["paper", "artifact", "estimator", "verdict"]
NUMBER_SORTS = ["rel_difference"]
#: which reading a claim row was judged under when no headline's reading names it, by its ``family``
#: (claims.csv): the sensitivity family holds the headlines' re-tests under their other readings; every
#: other counted claim is judged under the primary reading
READING_OF_FAMILY = {"sensitivity": "other reading (re-test)", "exploratory": "exploratory setting",
                     "sanity": "none (sanity check)"}
PRIMARY = "primary reading"


def read_csv(path: Path) -> list[dict]:
    """The rows of a CSV as dicts of strings ([] when the file is absent): the site reads, never writes."""
    if not path.exists():
        return []
    with path.open(newline="") as fh:
        return list(csv.DictReader(fh))


def reading_names(names: list[str]) -> dict[tuple[str, str], str]:
    """``{(paper, "<artifact>.<claim id>"): its readings}``: the readings of the papers' headlines
    (``paper.yaml``) whose parts a claim is, by label, the primary marked (the explorer's reading filter)."""
    found: dict[tuple[str, str], list[str]] = {}
    for paper in names:
        for head in load_paper(paper).headline:
            for r in head.readings:
                label = f"{r.label} ({PRIMARY})" if r.label == head.primary else str(r.label)
                for part in r.parts or head.parts:
                    found.setdefault((paper, part), []).append(label)
    return {key: SEPARATOR.join(dict.fromkeys(labels)) for key, labels in found.items()}


def reading_of(row: dict, names: dict[tuple[str, str], str]) -> str:
    """The reading a claims row was judged under: a headline's primary reading, the readings whose parts
    it is (:func:`reading_names`), else what its family says (:data:`READING_OF_FAMILY`)."""
    if row.get("role") == "headline" and row.get("primary_reading"):
        return f"{row['primary_reading']} ({PRIMARY})"
    named = names.get((row.get("paper", ""), f"{row.get('artifact', '')}.{row.get('id', '')}"))
    return named or READING_OF_FAMILY.get(row.get("family", ""), PRIMARY)


def number(text: str) -> float | None:
    """A CSV cell as a float for sorting, ``None`` when it is empty or not a finite number."""
    try:
        value = float(text)
    except (TypeError, ValueError):
        return None
    return value if math.isfinite(value) else None


def artifact_files(paper: str, artifact: str, root: Path) -> list[str]:
    """The CSVs of an artifact's results that exist (its table, its runs, its cells), relative to ``root``."""
    if not artifact:
        return []
    names = [f"{paper}/{artifact}{suffix}.csv" for suffix in ("", "_runs", "_cells")]
    return [name for name in names if (root / name).exists()]


def figure_of(figure: str, root: Path) -> str:
    """A claim's figure (``paper/artifact``, claims.csv ``figure``) as its PNG relative to ``root``, or ''."""
    return f"{figure}.png" if figure and (root / f"{figure}.png").exists() else ""


def claim_rows(root: Path) -> list[dict]:
    """Every row of ``root/claims.csv``, in order, with the explorer's fields added: ``reading``
    (:func:`reading_of`), ``png`` (its figure), ``files`` (the CSVs of the runs it read) and ``p``,
    ``p_adjusted`` as numbers."""
    rows, claims = [], read_csv(root / "claims.csv")
    names = reading_names(list(dict.fromkeys(r["paper"] for r in claims)))
    for row in claims:
        figure = row.get("figure", "")
        artifact = row.get("artifact") or figure.split("/")[-1]
        rows.append({**row, "reading": reading_of(row, names), "png": figure_of(figure, root),
                     "files": artifact_files(row["paper"], artifact, root),
                     **{k: number(row.get(k, "")) for k in CLAIM_SORTS}})
    return rows


def number_rows(root: Path) -> list[dict]:
    """Every compared number of ``root/summary.csv`` (a row with a paper value), with its figure, its
    CSVs and ``rel_difference`` as a number."""
    rows = []
    for row in read_csv(root / "summary.csv"):
        if row.get("paper_value", "") == "":
            continue
        rows.append({**row, "png": figure_of(f"{row['paper']}/{row['artifact']}", root),
                     "files": artifact_files(row["paper"], row["artifact"], root),
                     **{k: number(row.get(k, "")) for k in NUMBER_SORTS}})
    return rows


#: a field holding several values (a claim tested under more than one reading), split for its filter
SEPARATOR = "; "
MULTI = ["reading"]


def options(rows: list[dict], keys: list[str]) -> dict[str, list[str]]:
    """Each filter's options: the distinct values of ``key`` among ``rows``, in their first order (a
    field of :data:`MULTI` split at :data:`SEPARATOR`, each value an option)."""
    return {key: list(dict.fromkeys(v for r in rows for v in values(r, key))) for key in keys}


def values(row: dict, key: str) -> list[str]:
    """The values a row offers a filter: its field, split when it is one of :data:`MULTI`."""
    text = str(row.get(key, ""))
    return text.split(SEPARATOR) if key in MULTI else [text]


def explorer_data(root: Path) -> dict:
    """The explorer's two tables (claims, compared numbers): rows, filters with their options, sort keys."""
    claims, numbers = claim_rows(root), number_rows(root)
    return {"claims": {"rows": claims, "filters": options(claims, CLAIM_FILTERS), "sorts": CLAIM_SORTS,
                       "multi": MULTI, "separator": SEPARATOR},
            "numbers": {"rows": numbers, "filters": options(numbers, NUMBER_FILTERS), "sorts": NUMBER_SORTS,
                        "multi": [], "separator": SEPARATOR}}


def embedded_json(data) -> str:
    """``data`` as JSON safe inside an HTML ``<script>`` element (no ``</`` can close it)."""
    return json.dumps(data, ensure_ascii=False, separators=(",", ":")).replace("</", "<\\/")


def readings(root: Path, paper: str) -> list[dict]:
    """Each headline of ``paper`` with its claims row and its verdict under each reading (primary first):
    ``{"claim": row, "readings": [{"reading", "verdict", "primary"}, ...]}``, in the headlines' order."""
    cells = read_csv(root / paper / "readings.csv")
    heads = [r for r in read_csv(root / "claims.csv") if r["paper"] == paper and r["role"] == "headline"]
    out = []
    for head in heads:
        mine = [c for c in cells if c["headline"] == head["id"]]
        mine.sort(key=lambda c: c["primary"] != "True")
        out.append({"claim": head, "readings": [{**c, "primary": c["primary"] == "True"} for c in mine]})
    return out
