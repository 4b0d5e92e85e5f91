"""One voice: no statement of the report (a headline's part, a finding, magexp's statement, a sanity check)
says the opposite of another about the same metric of the same runs.

Two threshold claims of an artifact that read the same metric speak of the same values where the selection
of one contains the other's. A claim that holds or fails bounds those values: "max <= 300 holds" says
every value is at most 300, "min >= 415 holds" that every value is at least 415, "median >= 415 holds"
that some value is at least 415. Every value of a selection is a value of any selection containing it, so
"every value of S is at most U" and "some value of a part of S is at least x > U" cannot both be true: a
pair of such statements is a contradiction, whatever their roles (issue 39: a sanity check said every seed
settles by step 300 while the headline said none does before step 415).
"""

import itertools

import pandas as pd
import pytest

from magexp.artifacts.comparisons import HOLDS
from magexp.artifacts.paper_spec import artifact_paths, papers
from magexp.artifacts.spec import load
from magexp.paths import RESULTS

#: statistics that lie between the smallest and the largest value of their selection
WITHIN = ("min", "max", "median", "mean", "q25", "q75", "lo", "hi")


def bounds(op: str, value: float, stat: str, holds: bool) -> dict:
    """What a threshold claim's outcome says of its selection's values: ``all_le``/``all_ge`` (every value
    at most / at least) and ``some_ge``/``some_le`` (some value at least / at most)."""
    upper = op in ("<=", "<")  # the claim bounds its statistic from above
    if not holds:  # the converse holds: the statistic lies on the other side
        upper = not upper
    if upper:
        return {"all_le": value} if stat == "max" else {"some_le": value}
    return {"all_ge": value} if stat == "min" else {"some_ge": value}


def contradiction(broad: dict, narrow: dict) -> bool:
    """Whether bounds on a selection (``broad``) and on a selection it contains (``narrow``) cannot both
    hold (every value of ``narrow`` is a value of ``broad``)."""
    if "all_le" in broad and any(k in narrow for k in ("some_ge", "all_ge")):
        return narrow.get("some_ge", narrow.get("all_ge")) > broad["all_le"]
    if "all_ge" in broad and any(k in narrow for k in ("some_le", "all_le")):
        return narrow.get("some_le", narrow.get("all_le")) < broad["all_ge"]
    return False


def contains(broad: dict, narrow: dict) -> bool:
    """Whether selection ``narrow`` (``where:``) picks a part of what ``broad`` picks."""
    return all(k in narrow and str(narrow[k]) == str(v) for k, v in broad.items())


def test_bounds_and_contradictions_by_hand():
    every_by_300 = bounds("<=", 300, "max", True)
    none_before_415 = bounds(">=", 415, "min", True)
    assert every_by_300 == {"all_le": 300} and none_before_415 == {"all_ge": 415}
    assert contradiction(every_by_300, none_before_415) and contradiction(none_before_415, every_by_300)
    assert not contradiction(every_by_300, bounds(">=", 200, "median", True))
    assert bounds("<=", 300, "max", False) == {"some_ge": 300}  # a failed "max <= 300": some value above 300
    assert contains({"estimator": "kf"}, {"estimator": "kf", "seeds": 10}) and not contains({"a": 1}, {"b": 1})


def _threshold_claims() -> list[tuple[str, str, object]]:
    """``(paper, artifact, claim)`` of every threshold claim whose statistic lies within its values."""
    return [(p, spec.name, c) for p in papers() for spec in (load(x) for x in artifact_paths(p))
            for c in spec.claims if c.kind == "threshold" and c.stat in WITHIN]


def test_no_two_statements_on_the_same_metric_contradict():
    path = RESULTS / "claims.csv"
    if not path.exists():
        pytest.skip("results/claims.csv is absent: run make reproduce")
    claims = pd.read_csv(path, keep_default_na=False)
    result = {(r.artifact, r.id): r.verdict for r in claims.itertuples()}
    found = {}
    for paper, art, c in _threshold_claims():
        if (art, c.id) in result:
            found.setdefault((paper, art, c.metric), []).append(
                (c, bounds(c.op, float(c.value), c.stat, result[(art, c.id)] == HOLDS)))
    assert found, "no threshold claim was read"
    clashes = [f"{art}: {a.id} ({a.stat} {a.op} {a.value:g}) vs {b.id} ({b.stat} {b.op} {b.value:g}) on {metric}"
               for (paper, art, metric), group in found.items() for (a, ba), (b, bb) in itertools.permutations(group, 2)
               if contains(a.where, b.where) and contradiction(ba, bb)]
    assert not clashes, "statements that say the opposite of each other: " + "; ".join(clashes)
