"""A paper's claims judged on its runs, and its headline claims judged from them under their primary reading,
with their robustness under the other readings of what the paper left unstated.

:func:`paper_outcomes` evaluates every claim of a paper's artifacts on their runs tables, Holm-adjusted within
its family (:mod:`magexp.artifacts.families`); :func:`headlines` gives each headline claim of its
``paper.yaml`` the verdict of its primary reading's parts (:func:`headline_verdict`) and says how it fares
under the others (:func:`robustness`); :func:`claim_rows` are the rows of ``claims.csv``. The report
(:mod:`magexp.artifacts.report`) prints them.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pandas as pd

from magexp.artifacts.claims import FAILS, evaluate, interpolate
from magexp.artifacts.comparisons import CONTRADICTED, HOLDS, adjust
from magexp.artifacts.families import claim_families
from magexp.artifacts.formats import read_runs
from magexp.artifacts.spec import load
from magexp.artifacts.spec_check import check_claims
from magexp.artifacts.paper_spec import NOT_SHOWN, artifact_paths, check_headlines, load_paper, papers
from magexp.artifacts.power import claim_plans
from magexp.errors import MagexpError
from magexp.paths import RESULTS



def _runs(root: Path, paper: str, name: str) -> pd.DataFrame | None:
    """An artifact's ``_runs.csv`` under ``root``, None when it has none there."""
    path = root / paper / f"{name}_runs.csv"
    return read_runs(path) if path.exists() else None


def runs_reader(root: Path, paper: str):
    """``name -> runs table`` of ``paper``: each runs CSV read once, however many sections use it."""
    return functools.cache(lambda name: _runs(root, paper, name))


def paper_outcomes(specs: list, runs) -> list[tuple[str, object]]:
    """``(artifact, Outcome)`` of every claim of ``specs`` (one paper) whose runs table (``runs(name)``)
    has rows, Holm-adjusted within its family (:func:`magexp.artifacts.families.claim_families`,
    :func:`magexp.artifacts.comparisons.adjust`).
    """
    out = []
    for spec in specs:
        table = runs(spec.name) if spec.claims else None
        if table is not None and len(table):
            check_claims(spec, table)  # a spec edited since its runs (a redraw): one line, never a verdict
            out += [(spec.name, evaluate(c, table)) for c in spec.claims]
    family = claim_families(load_paper(specs[0].paper).headline, specs) if specs else {}
    adjust([o for _, o in out], [family[f"{name}.{o.claim.id}"] for name, o in out])
    return out


def claim_outcomes(root: Path = RESULTS, paper: str | None = None) -> list[tuple[str, object]]:
    """``(artifact, Outcome)`` of every claim whose artifact has runs under ``root``."""
    return [o for p in ([paper] if paper else papers())
            for o in paper_outcomes([load(path) for path in artifact_paths(p)], runs_reader(root, p))]


def headline_verdict(results: list[str | None]) -> str:
    """The verdict of a headline claim from its parts' outcomes (None: the part's artifact has no
    runs here): ``supported`` (every part holds), ``partly`` (some hold), ``contradicted`` (none holds and
    one does not hold or is contradicted), ``not shown`` (none holds and none goes against it: each part
    cannot be decided or detects no difference), ``not testable here`` (no part could be evaluated).
    """
    known = [r for r in results if r is not None]
    if not known:
        return "not testable here"
    held = sum(r == HOLDS for r in known)
    if held == len(results):
        return "supported"
    if held:
        return "partly"
    return "contradicted" if any(r in (FAILS, CONTRADICTED) for r in known) else NOT_SHOWN


def _reading_rows(h, outcomes: dict) -> list[dict]:
    """Each reading of headline ``h``: its label, source, settings, parts, verdict (its parts' outcomes,
    :func:`headline_verdict`) and whether it is the primary; none when ``h`` declares no readings."""
    rows = []
    for r in h.readings:
        parts = list(r.parts or h.parts)
        results = [outcomes[p].result if p in outcomes else None for p in parts]
        rows.append({"label": r.label, "source": " ".join(str(r.source).split()),
                     "settings": " ".join(str(r.settings).split()), "parts": parts,
                     "less_plausible": " ".join(str(r.less_plausible).split()), "primary": r.label == h.primary,
                     "verdict": headline_verdict(results),
                     "outcomes": "; ".join(f"{p}: {res or 'no runs here'}" for p, res in zip(parts, results)),
                     "could_see": could_see([outcomes[p] for p in parts if p in outcomes])})
    return rows


def could_see(parts: list) -> str:
    """What the tests of a reading's parts could have seen, in words, where none holds and none goes against it
    (its verdict :data:`~magexp.artifacts.paper_spec.NOT_SHOWN`; '' otherwise): its first part's, with how many
    parts are alike."""
    if headline_verdict([o.result for o in parts]) != NOT_SHOWN:
        return ""
    o, alike = parts[0], sum(q.result == parts[0].result for q in parts)
    head = (o.result if len(parts) == 1 else f"all {alike} parts: {o.result}" if alike == len(parts)
            else f"{alike} of its {len(parts)} parts: {o.result}")
    if o.undetected and o.detectable_words:
        return (f"{head}; {o.claim.id} would have seen {o.detectable_words} with 80 % power at its level "
                f"{o.level:.3g} (observed: {o.observed:.3g})")
    if o.p_min >= o.level:
        return f"{head}; {o.claim.id} cannot reach its level at n = {o.n}: its smallest p is {o.p_min:.3g}"
    return f"{head}: {o.short}"


def robustness(verdict: str, readings: list[dict]) -> str:
    """One sentence on how the verdict of a headline fares under its other readings: ``robust under all
    N readings`` where each gives the primary's verdict, else the primary's verdict and, per other
    verdict, the readings that give it, what a "not shown" one's tests could have seen (:func:`could_see`) and
    why each is less plausible.
    """
    if not readings:
        return "no unstated setting it turns on is read otherwise"
    others = [r for r in readings if not r["primary"]]
    if all(r["verdict"] == verdict for r in others):
        return f"robust under all {len(readings)} readings"
    same = [r for r in others if r["verdict"] == verdict]
    text = f"{verdict} under the primary reading" + ("".join(f' and under "{r["label"]}"' for r in same))
    sides: dict[str, list[dict]] = {}
    for r in others:
        if r["verdict"] != verdict:
            sides.setdefault(r["verdict"], []).append(r)
    for v, rs in sides.items():
        text += f"; {v} under " + " and ".join(f'"{r["label"]}" ({_seen(r)}less plausible: {r["less_plausible"]})'
                                               for r in rs)
    return text


def _seen(reading: dict) -> str:
    """What a reading's tests could have seen, ending in '; ' ('' when it is not "not shown")."""
    return f"{reading['could_see']}; " if reading.get("could_see") else ""


def headlines(paper: str, specs: list, outcomes: dict, runs) -> list[dict]:
    """Each headline claim of ``paper`` (``paper.yaml``) with its verdict, reason and figure
    (:func:`_headline_row`). ``outcomes``: ``{"artifact.id": Outcome}``; a part (of the headline or of
    a reading) naming no claim of the paper is an error.
    """
    listed = load_paper(paper).headline
    check_headlines(paper, listed, specs)
    return [_headline_row(paper, h, outcomes, runs) for h in listed]


def _headline_row(paper: str, h, outcomes: dict, runs) -> dict:
    """One headline's row, decided by its primary reading
    (:meth:`magexp.artifacts.paper_spec.Headline.primary_parts`); its other readings give ``robustness``
    (:func:`robustness`) and never the verdict. The reason is the deciding
    numbers (:func:`_headline_verdict`); the evidence adds each reading's verdict, source and settings and
    every deciding part's outcome; ``readings_total`` counts its readings (1: none declared),
    ``readings_holding`` those under which it is supported; ``readings`` keeps each reading's row (for
    the figure)."""
    deciding = h.primary_parts()
    parts = [outcomes.get(p) for p in deciding]
    verdict, reason = _headline_verdict(h, deciding, parts, runs)
    readings = _reading_rows(h, outcomes)
    figure = h.figure or (f"{paper}/{h.parts[0].split('.')[0]}" if h.parts else "")
    robust = robustness(verdict, readings)
    primary = next((r for r in readings if r["primary"]), None)
    primary_text = (f"{primary['label']} ({primary['source']}: {primary['settings']})".replace(": )", ")")
                    if primary else "")
    argued = [f"primary reading: {primary_text}; why: {' '.join(str(h.why).split())}"] if primary else []
    evidence = " | ".join([reason, *argued, f"robustness: {robust}"]
                          + [f"reading {r['label']} ({r['source']}; {r['settings']}): {r['verdict']} ({r['outcomes']})"
                             for r in readings]
                          + [f"{p}: {o.result} ({o.evidence})" for p, o in zip(deciding, parts) if o])
    holding = sum(r["verdict"] == "supported" for r in readings) if readings else int(verdict == "supported")
    return {"paper": paper, "artifact": "", "id": h.id, "by": "paper", "role": "headline", "section": h.section,
            "figure": figure, "text": str(h.text).strip(), "verdict": verdict, "reason": reason,
            "evidence": evidence, "primary_reading": primary["label"] if primary else _no_reading(verdict),
            "why": " ".join(str(h.why).split()), "robustness": robust,
            "readings_total": len(readings) or int(bool(h.parts)), "readings_holding": holding, "readings": readings}


def _no_reading(verdict: str) -> str:
    """The ``primary_reading`` of a headline that declares no readings: it is judged on the paper's
    stated settings, or on none when it cannot be tested here."""
    return "none: not testable here" if verdict == "not testable here" else "the paper's stated settings"


def _headline_verdict(h, deciding: list[str], parts: list, runs) -> tuple[str, str]:
    """The verdict of headline ``h`` and its reason, from the outcomes ``parts`` of its deciding parts
    (None: no runs here): its ``reason:`` template read on the runs of the first part's artifact, else
    each part's result and numbers, preceded by the parts that do not hold (a claim about every instance
    fails on the instances named); an untestable headline says why; one that is ``supported`` only by
    construction (``construction:`` says why) reads ``by construction``, never counted as supported."""
    if h.untestable:
        return "not testable here", str(h.untestable).strip()
    verdict = headline_verdict([o.result if o is not None else None for o in parts])
    if verdict == "supported" and str(h.construction).strip():
        verdict = "by construction"
    lead, failing = _failing(verdict, deciding, parts)
    if h.reason and parts[0] is not None:
        return verdict, lead + interpolate(" ".join(str(h.reason).split()), runs(deciding[0].split(".")[0]))
    shown = [(p, o) for p, o in zip(deciding, parts) if p not in failing]
    return verdict, lead + "; ".join(f"{p.split('.')[1]}: {o.result if o else 'no runs here'}"
                                     + (f" ({o.short})" if o else "") for p, o in shown)


def _failing(verdict: str, deciding: list[str], parts: list) -> tuple[str, set]:
    """The lead of a ``partly`` headline's reason, naming each deciding part that does not hold (the
    instance a claim about every instance fails on) with its evidence, and those parts ('' and none
    for any other verdict)."""
    failing = [(p, o) for p, o in zip(deciding, parts) if o is not None and o.result != HOLDS]
    if verdict != "partly" or not failing:
        return "", set()
    return ("Not on: " + "; ".join(f"{o.claim.text} ({o.result}: {o.short})" for _, o in failing) + ". ",
            {p for p, _ in failing})


def claim_rows(paper: str, specs: list, outcomes: list) -> list[dict]:
    """One ``claims.csv`` row per evaluated claim of ``paper`` (its ``family``; ``level``, ``p``,
    ``p_adjusted``, ``p_min`` for comparisons and trends; ``detectable`` at the row's level beside the
    ``observed`` effect where no difference is detected (a trend that cannot be decided at its level), a trend's slope; a comparison's declared ``effect`` in words and the
    ``seeds_planned`` for it, :func:`magexp.artifacts.power.claim_plans`, whose evidence says the power
    reached where the cap bound).
    """
    own = {s.name: s for s in specs}
    plans = claim_plans(specs, claim_families(load_paper(paper).headline, specs))
    rows = []
    for name, o in outcomes:
        plan = plans.get(f"{name}.{o.claim.id}")
        capped = (f"; planned seeds capped at {plan.seeds}: power {plan.power:.2f} against {plan.words} "
                  f"at level {plan.level:.3g}") if plan is not None and plan.capped else ""
        undetected = o.undetected
        rows.append({"paper": paper, "artifact": name, "id": o.claim.id, "by": o.claim.by, "role": o.claim.role,
                     "section": o.claim.section, "figure": f"{paper}/{o.claim.figure or own[name].name}",
                     "text": o.claim.text, "verdict": o.result, "reason": o.short, "evidence": o.evidence + capped,
                     "family": o.family, "level": o.level if o.is_comparison else np.nan,
                     "p": o.p, "p_adjusted": o.p_adjusted, "p_min": o.p_min,
                     "detectable": o.detectable if undetected else np.nan,
                     "observed": o.observed if undetected or o.claim.kind == "trend" else np.nan, "seeds": o.n or np.nan,
                     "effect": plan.words if plan else "", "seeds_planned": plan.seeds if plan else np.nan})
    return rows
