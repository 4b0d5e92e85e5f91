"""The family each claim of a paper is tested in: Holm's correction runs within a family, never across.

* ``primary``: the paper's findings (``by: paper``) and every claim that decides a headline under its
  primary reading (:meth:`magexp.artifacts.paper_spec.Headline.primary_parts`);
* ``sensitivity``: the claims that re-test a headline under another reading (robustness; never deciding);
* ``magexp``: magexp's own statements (``by: magexp``) that decide no headline;
* ``sanity``: true by construction (``role: sanity``), each judged alone, never counted;
* ``exploratory``: a setting chosen because its runs resemble the paper's numbers (``role:
  exploratory``), each judged alone, never counted.

A re-test under another reading thus never enlarges the primary family: checking robustness costs the
paper's findings no power.
"""

from __future__ import annotations


def claim_families(headlines: list, specs: list) -> dict[str, str]:
    """``{"<artifact>.<claim id>": family}`` of every claim of a paper (module docstring)."""
    primary = {p for h in headlines for p in h.primary_parts()}
    sensitivity = {p for h in headlines for p in h.sensitivity_parts()} - primary
    out = {}
    for spec in specs:
        for c in spec.claims:
            key = f"{spec.name}.{c.id}"
            if c.role in ("sanity", "exploratory"):
                out[key] = c.role
            elif key in primary:
                out[key] = "primary"
            elif key in sensitivity:
                out[key] = "sensitivity"
            else:
                out[key] = "primary" if c.by == "paper" else "magexp"
    return out
