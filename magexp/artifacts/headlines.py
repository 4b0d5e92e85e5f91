"""A paper's claims judged on its runs, and its headline claims judged from them, under each reading of what
the paper left unstated.

:func:`paper_outcomes` evaluates every claim of a paper's artifacts on their runs tables (one family of
comparisons, Holm-adjusted); :func:`headlines` gives each headline claim of its ``paper.yaml`` a verdict from
its parts' outcomes (:func:`headline_verdict`), judged under each reading (:func:`readings_verdict`);
:func:`claim_rows` are the rows of ``claims.csv``. The report (:mod:`magexp.artifacts.report`) prints them.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pandas as pd

from magexp.artifacts.claims import HOLDS, NO_DIFFERENCE, SHORT, adjust, evaluate, interpolate, shorten
from magexp.artifacts.families import claim_families
from magexp.artifacts.formats import read_runs
from magexp.artifacts.spec import load
from magexp.artifacts.paper_spec import artifact_paths, load_paper, papers
from magexp.artifacts.power import claim_plans
from magexp.errors import MagexpError
from magexp.paths import RESULTS

#: verdicts of a headline claim
HEADLINE_VERDICTS = ("supported", "partly", "contradicted", "depends", "not testable here", "by construction")


def _runs(root: Path, paper: str, name: str) -> pd.DataFrame | None:
    path = root / paper / f"{name}_runs.csv"
    return read_runs(path) if path.exists() else None


def runs_reader(root: Path, paper: str):
    """``name -> runs table`` of ``paper``: each runs CSV read once, however many sections use it.

    Parameters
    ----------
    root : Path
        The results folder.
    paper : str
        The paper.

    Returns
    -------
    callable
        ``name -> runs table`` (cached).
    """
    return functools.cache(lambda name: _runs(root, paper, name))


def paper_outcomes(specs: list, runs) -> list[tuple[str, object]]:
    """``(artifact, Outcome)`` of every claim of ``specs`` (one paper) whose runs table (``runs(name)``)
    has rows, Holm-adjusted within its family (:func:`magexp.artifacts.families.claim_families`,
    :func:`magexp.artifacts.claims.adjust`).

    Parameters
    ----------
    specs : list of Artifact
        The paper's artifacts.
    runs : callable
        ``name -> runs table`` (:func:`runs_reader`).

    Returns
    -------
    list of tuple
        ``(artifact, Outcome)`` per claim.
    """
    out = []
    for spec in specs:
        table = runs(spec.name) if spec.claims else None
        if table is not None and len(table):
            out += [(spec.name, evaluate(c, table)) for c in spec.claims]
    family = claim_families(specs[0].paper, specs) if specs else {}
    adjust([o for _, o in out], [family[f"{name}.{o.claim.id}"] for name, o in out])
    return out


def claim_outcomes(root: Path = RESULTS, paper: str | None = None) -> list[tuple[str, object]]:
    """``(artifact, Outcome)`` of every claim whose artifact has runs under ``root``.

    Parameters
    ----------
    root : Path
        The results folder.
    paper : str, optional
        One paper (default: every paper).

    Returns
    -------
    list of tuple
        ``(artifact, Outcome)`` per claim.
    """
    return [o for p in ([paper] if paper else papers())
            for o in paper_outcomes([load(path) for path in artifact_paths(p)], runs_reader(root, p))]


def headline_verdict(results: list[str | None]) -> str:
    """The verdict of a headline claim from its parts' outcomes (None: the part's artifact has no
    runs here): ``supported`` (every part holds), ``contradicted`` (none holds), ``partly``
    (some hold), ``not testable here`` (no part could be evaluated).

    Parameters
    ----------
    results : list of str or None
        Each part's result (None: no runs).

    Returns
    -------
    str
        The verdict.
    """
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
    supported under "w = 0.4", "c1 = c2 = 2"; contradicted under "constriction PSO"``; '' when they agree).

    Parameters
    ----------
    verdicts : list of tuple of str
        ``(label, verdict)`` per reading.

    Returns
    -------
    tuple of str
        ``(verdict, split)`` (split empty where every reading agrees).
    """
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
    a reading) naming no claim of the paper is an error.

    Parameters
    ----------
    paper : str
        The paper.
    specs : list of Artifact
        Its artifacts.
    outcomes : dict
        ``{"artifact.id": Outcome}``.
    runs : callable
        ``name -> runs table`` (:func:`runs_reader`).

    Returns
    -------
    list of dict
        A row per headline claim.
    """
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
    """One ``claims.csv`` row per evaluated claim of ``paper`` (``p``, ``p_adjusted``, ``p_min`` for
    comparisons; ``detectable`` at the row's level beside the ``observed`` effect where no difference is
    detected; a comparison's declared ``effect`` in words and the ``seeds_planned`` for it,
    :func:`magexp.artifacts.power.claim_plans`, whose evidence says the power reached where the cap bound).

    Parameters
    ----------
    paper : str
        The paper whose claims are listed.
    specs : list of Artifact
        Its artifacts, in order.
    outcomes : list of tuple
        ``(artifact, Outcome)`` per claim (:func:`paper_outcomes`).

    Returns
    -------
    list of dict
        A ``claims.csv`` row per claim.
    """
    own = {s.name: s for s in specs}
    plans = claim_plans(specs, claim_families(paper, specs))
    rows = []
    for name, o in outcomes:
        plan = plans.get(f"{name}.{o.claim.id}")
        capped = (f"; planned seeds capped at {plan.seeds}: power {plan.power:.2f} against {plan.words} "
                  f"at level {plan.level:.3g}") if plan is not None and plan.capped else ""
        undetected = o.result == NO_DIFFERENCE
        rows.append({"paper": paper, "artifact": name, "id": o.claim.id, "by": o.claim.by, "role": o.claim.role,
                     "section": o.claim.section, "figure": f"{paper}/{o.claim.figure or own[name].name}",
                     "text": o.claim.text, "verdict": o.result, "reason": shorten(o.short),
                     "evidence": o.evidence + capped, "p": o.p, "p_adjusted": o.p_adjusted, "p_min": o.p_min,
                     "detectable": o.detectable if undetected else np.nan,
                     "observed": o.observed if undetected else np.nan, "seeds": o.n or np.nan,
                     "effect": plan.words if plan else "", "seeds_planned": plan.seeds if plan else np.nan})
    return rows
