"""The seeds of each cell, fixed before any run: a cell of a comparison or a trend that declares an
``effect:`` gets the seeds that detect it with 80 % power at its family's strictest Holm level
(:mod:`magexp.artifacts.power`, which states the calculation), every other cell the artifact's ``seeds``.

``python -m magexp.artifacts.sample_sizes [paper ...]`` prints, per paper, each planned claim's effect,
family, level, test, seeds and the power they reach.
"""

from __future__ import annotations

import sys
from pathlib import Path

from magexp.artifacts.families import claim_families
from magexp.artifacts.paper_spec import artifact_paths, load_paper, papers
from magexp.artifacts import plan as planning  # plan_artifact read at call time (a test counts the plans)
from magexp.artifacts.plan import ArtifactPlan, claim_cells
from magexp.artifacts.power import ClaimPlan, claim_plans
from magexp.artifacts.spec import load
from magexp.artifacts.spec_check import check_plan


def paper_plans(paper: str, specs: list) -> dict[str, ClaimPlan]:
    """:func:`magexp.artifacts.power.claim_plans` of ``paper``'s artifacts in their families."""
    return claim_plans(specs, claim_families(load_paper(paper).headline, specs))


def sibling_specs(spec) -> list:
    """``spec`` with the other artifacts of its folder (its paper: a family counts them all); alone when
    it was read from no file.
    """
    if getattr(spec, "path", None) is None:
        return [spec]
    paths = sorted(p for p in Path(spec.path).parent.glob("*.yaml") if p.name != "paper.yaml")
    return [spec if p.stem == spec.name else load(p) for p in paths]


def planned_seeds(plan: ArtifactPlan) -> dict[int, int]:
    """``{cell: seeds}`` of the cells of the comparisons and trends of ``plan`` that declare an ``effect:`` (the most,
    where a cell serves several), from the artifact and its paper's family sizes alone.
    """
    spec = plan.spec
    plans = paper_plans(spec.paper, sibling_specs(spec))
    out: dict[int, int] = {}
    for c in spec.claims:
        chosen = plans.get(f"{spec.name}.{c.id}")
        for ci in (claim_cells(plan, c) if chosen else []):
            out[ci] = max(out.get(ci, 0), chosen.seeds)
    return out


def plan_with_effects(spec, *, seeds: int | None = None, tiny: bool = False) -> ArtifactPlan:
    """:func:`magexp.artifacts.plan.plan_artifact` with the planned seeds of :func:`planned_seeds` (the
    canonical reproduction's plan; ``seeds`` or ``tiny``: an exploration, every cell alike), its claims and
    reported values checked against its planned cells before anything runs (:func:`magexp.artifacts.spec_check.check_plan`).
    """
    plan = planning.plan_artifact(spec, seeds=seeds, tiny=tiny, seeds_for=planned_seeds)
    check_plan(plan)
    return plan


def main(argv: list[str] | None = None) -> int:
    """Print, per paper (every paper by default), each planned comparison's or trend's effect, family,
    level, test, seeds and power.
    """
    for paper in (argv or papers()):
        specs = [load(p) for p in artifact_paths(paper)]
        for key, p in paper_plans(paper, specs).items():
            note = " (capped: below the target power)" if p.capped else ""
            print(f"{key}: {p.words}; {p.test} at {p.level:.3g} ({p.family}, m = {p.m}): "
                  f"{p.seeds} seeds, power {p.power:.2f}{note}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
