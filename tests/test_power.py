"""Sample sizes fixed before the data (magexp.artifacts.power) and `detectable` at the verdict's own level."""

import itertools
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from scipy.stats import binom, fisher_exact, norm

from magexp.artifacts import power
from magexp.artifacts.claims import Claim
from magexp.artifacts.comparisons import NO_DIFFERENCE
from magexp.artifacts.paper_spec import load_paper, papers
from magexp.artifacts.families import claim_families
from magexp.artifacts.plan import ArtifactPlan, paper_specs
from magexp.artifacts.sample_sizes import planned_seeds
from magexp.artifacts.significance import (POWER, detect_paired, detect_rise, effect_error, fisher_greater,
                                          fisher_power, fisher_reject)
from magexp.errors import MagexpError
from magexp.paths import RESULTS


def _brute_fisher_power(n1, n2, p1, p0, level):
    """Power by scipy's own test on every table, one by one."""
    total = 0.0
    for k1, k2 in itertools.product(range(n1 + 1), range(n2 + 1)):
        p = fisher_exact([[k1, n1 - k1], [k2, n2 - k2]], alternative="greater").pvalue
        total += binom.pmf(k1, n1, p1) * binom.pmf(k2, n2, p0) * (p < level)
    return total


@pytest.mark.parametrize("n1, n2, p1, p0, level", [(6, 5, 0.9, 0.3, 0.05), (8, 8, 0.7, 0.4, 0.01), (4, 7, 1.0, 0.2, 0.1)])
def test_exact_fisher_power_agrees_with_scipy_table_by_table(n1, n2, p1, p0, level):
    assert fisher_power(n1, n2, p1, p0, level)[0] == pytest.approx(_brute_fisher_power(n1, n2, p1, p0, level), abs=1e-12)


def test_the_rejection_region_is_the_decision_rule_of_the_verdict():
    for n1, n2, level in [(12, 9, 0.01), (30, 30, 0.002)]:
        expected = np.array([[fisher_greater(a, n1, b, n2) < level for b in range(n2 + 1)] for a in range(n1 + 1)])
        assert (fisher_reject(n1, n2, level) == expected).all()


def test_required_fisher_seeds_are_the_smallest_that_reach_the_power():
    effect = (("baseline", 0.35), ("rise", 0.3))
    n, reached = power.required_seeds("fisher", effect, 0.05, 10, 120)
    scan = [m for m in range(10, 121) if power.power_at(m, "fisher", effect, 0.05) >= POWER]
    assert n == scan[0] and reached >= POWER
    assert power.power_at(n - 1, "fisher", effect, 0.05) < POWER


def test_a_cap_that_binds_is_reported_with_the_power_it_reaches():
    n, reached = power.required_seeds("fisher", (("baseline", 0.4), ("rise", 0.05)), 0.001, 30, 60)
    assert n == 60 and reached < POWER


def test_the_wilcoxon_simulation_is_near_noethers_sample_size():
    """Noether (1987): the signed-rank test needs n = (z(1-a) + z(power))^2 / (3 (p' - 1/2)^2), p' = P(d1 + d2 < 0)."""
    ratio, spread, level = 1.5, 0.5, 0.05
    z = np.random.default_rng(1).standard_normal((4, 400_000))
    d = np.exp(spread * z[:2]) - ratio * np.exp(spread * z[2:])
    p_prime = np.mean(d[0] + d[1] < 0)
    n = int(np.ceil((norm.ppf(1 - level) + norm.ppf(POWER)) ** 2 / (3 * (p_prime - 0.5) ** 2)))
    assert 0.7 <= power.wilcoxon_power(n, ratio, spread, level) <= 0.9
    assert power.wilcoxon_power(n // 3, ratio, spread, level) < 0.6  # and the power rises with n


def test_the_permutation_simulation_gains_power_with_seeds_and_holds_its_level():
    assert power.permutation_power(20, 1.0 + 1e-9, 0.5, 0.05) <= 0.1  # no effect: rejects about level
    low, high = (power.permutation_power(n, 1.5, 0.5, 0.01) for n in (15, 60))
    assert low < 0.6 < high


def test_an_effect_is_validated_with_one_line():
    with pytest.raises(MagexpError, match=r"effect=\{'ratio': 1.5\} is not allowed: give exactly \{ratio: number, spread"):
        Claim(id="c", text="", kind="ordering", cells=[{"a": 1}, {"a": 2}], effect={"ratio": 1.5})
    with pytest.raises(MagexpError, match="baseline \\+ rise <= 1"):
        Claim(id="c", text="", kind="ordering", stat="success_rate", cells=[{"a": 1}, {"a": 2}],
              effect={"rise": 0.5, "baseline": 0.7})
    with pytest.raises(MagexpError, match="only a comparison or a trend has one"):
        Claim(id="c", text="", kind="success", value=0.9, effect={"rise": 0.1, "baseline": 0.5})
    assert effect_error({"ratio": 1.2, "spread": 0.3}, "median") == ""


def test_every_comparison_claim_declares_the_effect_its_seeds_are_planned_for():
    missing = [f"{s.name}.{c.id}" for paper in papers() for s in paper_specs(paper) for c in s.claims
               if c.kind in ("ordering", "winner") and not c.effect]
    assert not missing, f"comparison claims without an effect: (the seeds cannot be planned) {missing}"


def test_the_claims_cells_get_the_planned_seeds_and_the_others_the_artifacts():
    claim = Claim(id="more", text="", kind="ordering", stat="success_rate", better="higher", test="fisher",
                  cells=[{"estimator": "a"}, {"estimator": "b"}], effect={"rise": 0.3, "baseline": 0.35})
    spec = SimpleNamespace(name="art", paper="nopaper", claims=[claim], seeds=20, max_seeds=400, path=None)
    plan = ArtifactPlan(spec=spec, cells=[{"estimator": e} for e in "abc"],
                        overrides=[[f"estimator={e}"] for e in "abc"], configs=[], index=[])
    n, _ = power.required_seeds("fisher", (("baseline", 0.35), ("rise", 0.3)), 0.05, 20, 400)
    assert n > 20 and planned_seeds(plan) == {0: n, 1: n}


def test_the_level_is_the_strictest_holm_step_of_the_claims_family():
    specs = paper_specs("yuan2018")
    levels = power.claim_levels(specs, claim_families(load_paper("yuan2018").headline, specs))
    family, m, level = levels["yuan2018_ext_clamps.rdpso_more_reliable_table4_absolute"]
    assert family == "primary" and level == pytest.approx(0.05 / m)
    assert levels["yuan2018_table4.rdpso_more_reliable_than_pso"][0] == "sensitivity"  # a re-test under another reading
    assert sum(f == "primary" for f, _, _ in levels.values()) == m
    assert levels["yuan2018_table7.rdpso_beats_ekf"][2] == 0.05  # a sanity check is judged alone


def test_detect_rise_is_exact_at_the_level_and_says_when_no_rise_reaches_the_power():
    rise, words = detect_rise(0.5, 30, 30, 0.0042)
    assert fisher_power(30, 30, 0.5 + rise, 0.5, 0.0042)[0] >= POWER > fisher_power(30, 30, 0.5 + rise - 0.002, 0.5, 0.0042)[0]
    assert words == f"a success-rate rise of {rise:.3g}"
    rise, words = detect_rise(49 / 60, 60, 60, 0.001)
    assert np.isnan(rise) and words == "no rise up to a success rate of 1 reaches 80 % power at this level"


def test_a_paired_detectable_is_not_computable_on_tied_differences():
    d = np.r_[np.zeros(16), np.linspace(-1, 1, 14)]
    value, words = detect_paired(d, 0.01)
    assert np.isnan(value) and words == "not computable (16 of 30 ties)"
    value, words = detect_paired(np.linspace(-1, 1, 30), 0.01)
    assert value > detect_paired(np.linspace(-1, 1, 30), 0.05)[0] > 0  # a stricter level: a larger detectable


def test_no_undetected_difference_is_at_least_what_its_test_could_detect():
    rows = pd.read_csv(RESULTS / "claims.csv")
    assert {"observed", "effect", "seeds_planned"} <= set(rows.columns), "claims.csv predates the power columns"
    undetected = rows[(rows.verdict == NO_DIFFERENCE) & rows.detectable.notna()]
    bad = undetected[undetected.observed >= undetected.detectable]
    assert bad.empty, f"no difference detected, yet observed >= detectable: {bad[['artifact', 'id']].values.tolist()}"


def test_a_binding_cap_is_recorded_with_the_power_it_reaches():
    from magexp.artifacts.sample_sizes import paper_plans

    plan = paper_plans("real", paper_specs("real"))["real_table7.table7_order"]
    assert plan.capped and plan.seeds == 5 and plan.power < POWER  # max_seeds: 5 (a run costs ~24 CPU-s)
    assert plan.power == pytest.approx(power.wilcoxon_power(5, 2.0, 1.0, 0.05))
