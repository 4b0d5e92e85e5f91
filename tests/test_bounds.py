"""The Cramér-Rao bound against closed forms and a small Monte Carlo."""

import inspect

import numpy as np
import pytest
import yaml
from hydra.utils import instantiate

from magexp.core import bounds
from magexp.core.bounds import cramer_rao
from magexp.estimators.lm import LevenbergMarquardt
from magexp.paths import CONF
from magexp.problems import make_problem, problem_class


def test_scalar_bound_identifies_nine_and_matches_the_floor_formula(make_cfg):
    sc = instantiate(make_cfg("scenario.noise=2", "scenario.noise_kind=gaussian").scenario, _convert_="all")
    prob = make_problem("scalar", sc.generate(rng=np.random.default_rng(0)), sc.search)
    crb = cramer_rao(prob)
    assert crb["identifiable"] == 9  # a scalar objective cannot see a rotation of W
    assert crb["rms_floor"] == pytest.approx(2 * np.sqrt(291 / 300), rel=0.02)


def test_least_squares_is_near_efficient_in_monte_carlo(make_cfg):
    sc = instantiate(make_cfg("scenario.noise=5", "scenario.noise_kind=gaussian", "scenario.n_readings=100").scenario,
                     _convert_="all")
    errors, bound = [], None
    for seed in range(40):
        prob = make_problem("scalar", sc.generate(rng=np.random.default_rng(seed)), sc.search)
        bound = bound or cramer_rao(prob)["offset_bound"]
        errors.append(LevenbergMarquardt().fit(prob).x[9:] - prob.dataset.truth.offset)
    mc = np.sqrt(np.mean(np.sum(np.square(errors), axis=1)))
    assert 0.75 * bound < mc < 1.35 * bound


def test_no_bound_without_noise(make_cfg):
    sc = instantiate(make_cfg("scenario.noise=0").scenario, _convert_="all")
    assert cramer_rao(make_problem("scalar", sc.generate(rng=np.random.default_rng(0)), sc.search)) is None


def test_two_rings_leave_the_scalar_offset_unidentified(make_cfg):
    """Turns about only two axes put the readings on two planar rings, which do not fix a
    quadric: the scalar bound of the offset is infinite, the vector one finite."""
    sc = instantiate(make_cfg("scenario=yuan2018_mode2").scenario, _convert_="all")
    ds = sc.generate(rng=np.random.default_rng(0))
    scalar = cramer_rao(make_problem("scalar", ds, sc.search, **sc.problem_options))
    vector = cramer_rao(make_problem("vector", ds, sc.search, **sc.problem_options))
    assert scalar["offset_bound"] == np.inf and scalar["unidentified_invariants"] > 0
    assert 0 < vector["offset_bound"] < 1.0 and vector["unidentified_invariants"] == 0


def test_ship_offset_bound_matches_monte_carlo(make_cfg):
    """Gains (~1) and offsets (~1000 nT) differ in scale by orders of magnitude: the bound must
    still match the least-squares spread (a relative cut-off on the unscaled Fisher matrix
    once dropped the offset directions and gave a bound of 1e-8 nT)."""
    from magexp.estimators.linear import LeastSquares

    sc = instantiate(make_cfg("scenario=yan2022_sim", "scenario.angle_noise_deg=0").scenario, _convert_="all")
    errors, bounds = [], []
    for seed in range(60):
        prob = make_problem("ship", sc.generate(rng=np.random.default_rng(seed)), sc.search)
        if seed < 5:
            bounds.append(cramer_rao(prob)["offset_bound"])
        errors.append(LeastSquares().fit(prob).x[9:] - prob.dataset.truth.offset)
    mc = np.sqrt(np.mean(np.sum(np.square(errors), axis=1)))
    assert 0.7 * np.mean(bounds) < mc < 1.3 * np.mean(bounds)


# ---- the O(N) bound against the dense computation it replaced --------------------------------

SCENARIOS = sorted(p.stem for p in (CONF / "scenario").glob("*.yaml"))


def _dense_cramer_rao(problem, theta: np.ndarray | None = None, *, analytic: bool = True) -> dict | None:
    """The bound as computed before it became O(N) (dense N m x N m noise covariance), kept
    verbatim as the reference of ``test_block_bound_equals_the_dense_one``; ``analytic=False``
    takes its derivatives by central differences, as it did then (the problems' analytic
    Jacobians, which the O(N) bound uses, differ from those by ~1e-8 relative).

    Returns ``rms_floor`` (expected best RMS of the problem's residual components), ``invariant_cov``
    (the CRB covariance of ``problem.invariants``), and the expected error sizes
    ``offset_bound`` (``sqrt(tr Cov(o))``) and ``gram_bound`` (relative, for ``W^T W``).
    """
    theta = problem.truth_theta() if theta is None else theta
    if theta is None or not problem.dataset.noise_std:
        return None
    sigma2, problem = float(problem.dataset.noise_std) ** 2, bounds.noise_free(problem)
    ds = problem.dataset
    steps = 1e-6 * np.maximum(np.abs(theta), 1e-3 * np.maximum(np.abs(problem.upper - problem.lower), 1e-12))
    if analytic:
        jac, g = problem.jacobians(theta)  # (N*m, p), (N, m, 3)
    else:
        jac = bounds.central_differences(problem.residuals, theta, steps)
        g = bounds.finite_difference_noise_blocks(problem, theta)
    m = g.shape[1]
    cov_blocks = sigma2 * g @ g.transpose(0, 2, 1)  # (N, m, m)
    # Σ^{-1/2} J: whiten block by block
    evals, evecs = np.linalg.eigh(cov_blocks)
    inv_sqrt = evecs @ (np.where(evals > 0, 1 / np.sqrt(np.maximum(evals, 1e-300)), 0)[..., None]
                        * evecs.transpose(0, 2, 1))
    jw = np.einsum("nij,njp->nip", inv_sqrt, jac.reshape(ds.n, m, -1)).reshape(ds.n * m, -1)
    # invert with the parameters scaled to unit columns: their scales differ by orders of magnitude
    # (a gain vs an offset in nT), and a relative cut-off on the raw matrix would drop whole directions
    d = np.maximum(np.linalg.norm(jw, axis=0), 1e-300)
    fisher_scaled = (jw / d).T @ (jw / d)
    cov = np.linalg.pinv(fisher_scaled, rcond=1e-10, hermitian=True) / np.outer(d, d)
    h = bounds.central_differences(problem.invariants, theta, steps)
    inv_cov = h @ cov @ h.T
    # an invariant is identifiable only if its gradient lies in the row space of J; otherwise
    # the data cannot pin it down and its bound is infinite (the pseudo-inverse would hide that)
    colnorm = np.maximum(np.linalg.norm(jac, axis=0), 1e-300)
    _, sv_j, vt = np.linalg.svd(jac / colnorm, full_matrices=False)
    row_space = vt[sv_j > 1e-6 * sv_j[0]]
    h_scaled = h / colnorm
    outside = np.linalg.norm(h_scaled - (h_scaled @ row_space.T) @ row_space, axis=1)
    blind = outside > 1e-5 * np.maximum(np.linalg.norm(h_scaled, axis=1), 1e-300)
    inv_cov[blind, :] = np.inf
    inv_cov[:, blind] = np.inf
    # expected in-sample RMS of the (unweighted) least-squares fit
    scaled = jac / np.maximum(np.linalg.norm(jac, axis=0), 1e-300)  # column scale must not decide the rank
    u, sv, _ = np.linalg.svd(scaled, full_matrices=False)
    rank = int(np.sum(sv > 1e-6 * sv[0]))
    q = u[:, :rank]
    sigma = np.zeros((ds.n * m, ds.n * m))
    idx = np.arange(ds.n)[:, None] * m + np.arange(m)
    sigma[idx[:, :, None], idx[:, None, :]] = cov_blocks
    proj = np.eye(ds.n * m) - q @ q.T
    rms_floor = float(np.sqrt(np.trace(proj @ sigma @ proj.T) / (ds.n * m)))  # per residual component
    out = {"rms_floor": rms_floor, "invariant_cov": inv_cov, "identifiable": int(rank),
           "unidentified_invariants": int(blind.sum())}
    out.update(problem.invariant_bounds(theta, inv_cov))
    return out


def _bound_cases() -> list:
    """``(scenario, analytic, rtol)``: the first scenario of each paper and objective (its config's ``objective``), with
    the analytic derivatives and with the central differences, in make test; the other scenarios in make test-full."""
    cases, seen = [], set()
    for name in SCENARIOS:
        config = yaml.safe_load((CONF / "scenario" / f"{name}.yaml").read_text()) or {}
        family = name.partition("_")[0], config.get("objective")
        marks = [pytest.mark.full] if family in seen else []
        cases += [pytest.param(name, True, 1e-9, id=f"{name}-analytic", marks=marks),
                  pytest.param(name, False, 1e-6, id=f"{name}-differences", marks=marks)]
        seen.add(family)
    return cases


@pytest.mark.parametrize("scenario_name, analytic, rtol", _bound_cases())
def test_block_bound_equals_the_dense_one(make_cfg, scenario_name, analytic, rtol):
    """Every scenario's own objective (and the scalar one where it applies): the same numbers as
    the dense ``N m x N m`` computation, to 1e-9 relative with the same (analytic) derivatives;
    to 1e-6 with the central differences of the dense computation as it was (their truncation
    and rounding error, ~1e-8, is the whole difference)."""
    sc = instantiate(make_cfg(f"scenario={scenario_name}").scenario, _convert_="all")
    ds = sc.generate(rng=np.random.default_rng(1))
    objectives = {sc.objective} | ({"scalar"} if ds.reference_norm is not None and sc.objective != "ship" else set())
    compared = 0
    for objective in sorted(objectives):
        options = getattr(sc, "problem_options", {}) if objective != "ship" else {}
        if objective != sc.objective:  # the scenario's options are its own objective's: keep the shared ones
            accepted = inspect.signature(problem_class(objective).__init__).parameters
            options = {k: v for k, v in options.items() if k in accepted}
        prob = make_problem(objective, ds, sc.search, **options)
        with np.errstate(all="ignore"):
            dense = _dense_cramer_rao(prob, analytic=analytic)
        block = cramer_rao(prob)
        if dense is None:
            assert block is None
            continue
        compared += 1
        assert block["identifiable"] == dense["identifiable"]
        assert block["unidentified_invariants"] == dense["unidentified_invariants"]
        np.testing.assert_allclose(block["rms_floor"], dense["rms_floor"], rtol=rtol)
        # covariances relative to their scale sqrt(c_ii c_jj): an entry near zero compares as a correlation
        finite = np.isfinite(np.diag(dense["invariant_cov"]))
        scale = np.sqrt(np.outer(np.diag(dense["invariant_cov"])[finite], np.diag(dense["invariant_cov"])[finite]))
        np.testing.assert_array_equal(np.isinf(block["invariant_cov"]), np.isinf(dense["invariant_cov"]))
        np.testing.assert_allclose(block["invariant_cov"][np.ix_(finite, finite)] / scale,
                                   dense["invariant_cov"][np.ix_(finite, finite)] / scale, rtol=rtol, atol=rtol)
        for key in ("offset_bound", "gram_bound", "matrix_bound"):
            if key in dense:
                np.testing.assert_allclose(block[key], dense[key], rtol=rtol)
    assert compared or not ds.noise_std


@pytest.mark.parametrize("objective, options", [
    ("scalar", {"parameterisation": "inverse"}), ("scalar", {"parameterisation": "forward"}),
    ("vector", {"parameterisation": "forward"}), ("vector", {"parameterisation": "inverse"}),
    ("vector_ls", {"parameterisation": "forward"}), ("ship", {}),
])
def test_analytic_jacobians_equal_central_differences(make_cfg, objective, options):
    """``problem.jacobians`` (``∂r/∂θ`` and ``∂r_i/∂x_i``) against central differences, at a
    point away from the truth (so no residual is zero and every term of the chain rule counts)."""
    scenario = "yan2022_sim" if objective == "ship" else "yuan2018_mode1"
    sc = instantiate(make_cfg(f"scenario={scenario}").scenario, _convert_="all")
    ds = sc.generate(rng=np.random.default_rng(3))
    prob = make_problem(objective, ds, sc.search, **options)
    theta = prob.truth_theta()
    theta = theta + 0.02 * np.abs(theta).max() * np.random.default_rng(4).standard_normal(theta.size) \
        * np.r_[np.full(9, 1 / np.abs(theta).max()), np.ones(3)]
    steps = 1e-6 * np.maximum(np.abs(theta), 1e-3)
    numeric = bounds.central_differences(prob.residuals, theta, steps), bounds.finite_difference_noise_blocks(prob, theta)
    for analytic, central in zip(prob.jacobians(theta), numeric):
        assert analytic.shape == central.shape
        np.testing.assert_allclose(analytic, central, rtol=1e-6, atol=1e-7 * np.abs(central).max())


def test_a_subclass_that_changes_the_residuals_falls_back_to_differences(make_cfg):
    """Analytic Jacobians belong to the residuals they were derived from: a subclass with other
    residuals gets None (the bound then differentiates numerically)."""
    from magexp.problems.scalar import ScalarCalibration

    class Squared(ScalarCalibration):
        def residuals(self, theta):
            return super().residuals(theta) ** 2

    sc = instantiate(make_cfg("scenario=ding2024_exp1", "scenario.n_readings=50").scenario, _convert_="all")
    ds = sc.generate(rng=np.random.default_rng(0))
    assert ScalarCalibration(ds, sc.search).jacobians(ScalarCalibration(ds, sc.search).truth_theta()) is not None
    prob = Squared(ds, sc.search)
    assert prob.jacobians(prob.truth_theta()) is None
    assert cramer_rao(prob) is not None  # by central differences
