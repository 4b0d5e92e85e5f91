"""The classical baselines, checked by hand or against their papers' formulation, and at the
Cramér-Rao bound on Ding's simulations; the swarm's boundary handling by hand."""

import numpy as np
import pytest
from hydra.utils import instantiate

from magexp.core.dataset import Dataset, Truth
from magexp.estimators import twostep as ts
from magexp.estimators.boundaries import clip, random_reentry, reflect
from magexp.core.ellipsoid import constraint_matrix, fit_ellipsoid, fit_ellipsoid_specific
from magexp.problems.symmetric import expand
from magexp.estimators.triangular import (MaximumLikelihoodScalar, TriangularCalibration, merayo_matrix,
                                          merayo_parameters)
from magexp.core.metrics import evaluate
from magexp.problems import make_problem
from magexp.scenarios.search import SearchBox

BOX = SearchBox(diag=(0.5, 1.5), offdiag=(-0.5, 0.5), offset=(-1000.0, 1000.0))


def sphere(n, rng):
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def scalar_problem(m, offset, *, n=300, field=50000.0, noise=0.0, seed=0, magnitudes=None):
    """Readings ``r = M h + offset + noise`` of field vectors ``h`` all over the sphere."""
    rng = np.random.default_rng(seed)
    mags = np.full(n, field) if magnitudes is None else magnitudes
    h = sphere(n, rng) * mags[:, None]
    r = h @ np.asarray(m).T + offset + noise * rng.normal(size=(n, 3))
    ds = Dataset(readings=r, reference_norm=mags, truth=Truth(np.linalg.inv(m), np.asarray(offset, float)),
                 noise_std=noise or None)
    return make_problem("scalar", ds, BOX)


M = np.array([[1.05, 0.03, -0.02], [0.01, 0.95, 0.04], [-0.03, 0.02, 1.10]])
O = np.array([212.0, -367.0, 398.0])


def gram_and_offset(problem, x):
    w, o = (a[0] for a in problem.unpack(x))
    return w.T @ w, o


# -- TWOSTEP --------------------------------------------------------------------------------
@pytest.mark.parametrize("varying", [False, True])
def test_twostep_centred_estimate_is_exact_without_noise(varying):
    """Alonso & Shuster's centred estimate solves z = L theta - c^T (I+E)^-1 c exactly for noise-free
    data: with a varying field magnitude as printed, with a constant one through the scale of
    the mean equation (``centred_estimate``)."""
    rng = np.random.default_rng(3)
    mags = rng.uniform(30000, 60000, 300) if varying else None
    p = scalar_problem(M, O, magnitudes=mags)
    scale = float(np.mean(p.dataset.reference_norm))
    z, lmat, w = ts.measurement(p.dataset.readings / scale, p.dataset.reference_norm / scale, 0.0)
    theta = ts.centred_estimate(z, lmat, w, p.dataset.readings / scale)
    wcal, o = ts.calibration(theta)
    g_true = np.linalg.inv(M).T @ np.linalg.inv(M)
    np.testing.assert_allclose(wcal.T @ wcal, g_true, atol=1e-9)
    np.testing.assert_allclose(o * scale, O, atol=1e-5)
    # the model of the docstring: z_k = L_k theta - c^T (I+E)^-1 c, by hand for the truth
    e = g_true - np.eye(3)
    c = g_true @ (O / scale)
    theta_true = np.concatenate([c, e[ts.UPPER]])
    np.testing.assert_allclose(z, lmat @ theta_true - c @ np.linalg.solve(np.eye(3) + e, c), atol=1e-9)


def test_twostep_gauss_newton_jacobian_matches_finite_differences():
    p = scalar_problem(M, O, noise=5.0)
    scale = 50000.0
    z, lmat, w = ts.measurement(p.dataset.readings / scale, p.dataset.reference_norm / scale, 5.0 / scale)
    theta = ts.centred_estimate(z, lmat, w, p.dataset.readings / scale) + 1e-3
    r, jac = ts.residual_and_jacobian(theta, z, lmat, w)
    num = np.empty_like(jac)
    for j in range(theta.size):
        d = np.zeros_like(theta)
        d[j] = 1e-7
        num[:, j] = (ts.residual_and_jacobian(theta + d, z, lmat, w)[0] - ts.residual_and_jacobian(theta - d, z, lmat, w)[0]) / 2e-7
    np.testing.assert_allclose(jac, num, rtol=1e-5, atol=1e-6 * np.abs(jac).max())


# -- triangular (Merayo) and noise-weighted ML (Vasconcelos) ---------------------------------
def test_triangular_recovers_merayos_gains_and_angles():
    """Data made by Merayo's model E = S T B + O: the fitted lower-triangular W is (S T)^-1, and its
    gains and non-orthogonality angles come back."""
    gains, angles = np.array([1.02, 0.97, 1.05]), np.radians([0.8, -1.1, 0.5])
    m = merayo_matrix(gains, angles)
    p = scalar_problem(m, O)
    res = TriangularCalibration().fit(p)
    w, o = (a[0] for a in p.unpack(res.x))
    np.testing.assert_allclose(w, np.linalg.inv(m), atol=1e-10)
    assert np.allclose(np.triu(w, 1), 0)
    g, a = merayo_parameters(w)
    np.testing.assert_allclose(g, gains, atol=1e-10)
    np.testing.assert_allclose(a, angles, atol=1e-10)
    np.testing.assert_allclose(o, O, atol=1e-6)


def test_triangular_parameters_remove_the_rotation_valley():
    """12 scalar parameters: the residual Jacobian has rank 9 (3 rotations cost nothing); the 9
    triangular ones: full rank."""
    p = scalar_problem(M, O, noise=1.0)
    tri = TriangularCalibration()
    q = tri.start(p)
    f9 = tri.residuals_of(p)

    def jac(f, x):
        return np.column_stack([(f(x + d) - f(x - d)) / (2 * 1e-6) for d in np.eye(x.size) * 1e-6])

    assert np.linalg.matrix_rank(jac(f9, q), tol=1e-6) == 9
    x12 = p.pack(*tri.unpack(q))
    j12 = jac(p.residuals, x12)
    sv = np.linalg.svd(j12, compute_uv=False)
    assert sv[8] / sv[0] > 1e-6 and sv[9] / sv[0] < 1e-6


def test_ml_scalar_weights_are_the_residual_noise():
    """sigma_k = sigma ||W^T u|| / ||u|| is the std of |W(r - o)| - B under reading noise (Monte Carlo)."""
    rng = np.random.default_rng(0)
    w = np.diag([1.5, 1.0, 0.6])
    u = np.array([0.3, -0.5, 0.8]) * 50000.0
    r = np.linalg.solve(w, u)
    sigma = 5.0
    draws = np.linalg.norm((r + sigma * rng.normal(size=(200000, 3))) @ w.T, axis=1)
    predicted = sigma * np.linalg.norm(w.T @ u) / np.linalg.norm(u)
    assert draws.std() == pytest.approx(predicted, rel=0.01)
    # with W a multiple of a rotation every weight is equal: ML is the triangular least squares
    q, _ = np.linalg.qr(np.random.default_rng(1).normal(size=(3, 3)))
    p = scalar_problem(np.linalg.inv(1.1 * q), O, noise=3.0)
    a, b = TriangularCalibration().fit(p).x, MaximumLikelihoodScalar().fit(p).x
    np.testing.assert_allclose(gram_and_offset(p, a)[0], gram_and_offset(p, b)[0], atol=1e-7)  # entries ~1.2
    np.testing.assert_allclose(a[9:], b[9:], atol=1e-3)


# -- ellipsoid-specific (Li & Griffiths) -------------------------------------------------------
def test_ellipsoid_specific_constraint_and_exactness():
    v = np.array([1.0, 2.0, 3.0, 0.1, 0.2, 0.3])  # a, b, c, h, g, f
    i_, j_ = v[:3].sum(), v[0] * v[1] + v[1] * v[2] + v[0] * v[2] - (v[3:] ** 2).sum()
    assert v @ constraint_matrix(4.0) @ v == pytest.approx(4 * j_ - i_**2)
    p = scalar_problem(M, O)
    w, o = fit_ellipsoid_specific(p.dataset.readings, 50000.0)
    np.testing.assert_allclose(w.T @ w, np.linalg.inv(M).T @ np.linalg.inv(M), atol=1e-10)
    np.testing.assert_allclose(o, O, atol=1e-6)


def test_ellipsoid_specific_is_an_ellipsoid_where_the_plain_fit_is_not():
    """Readings on a small cap with noise: the unconstrained algebraic fit often returns a
    hyperboloid (no calibration); Li & Griffiths' constraint always gives an ellipsoid."""
    plain_failed = 0
    for seed in range(20):
        rng = np.random.default_rng(seed)
        h = sphere(400, rng)
        h = h[h[:, 2] > 0.85][:25] * 50000.0  # a cap of ~30 degrees
        r = h @ M.T + O + 300.0 * rng.normal(size=h.shape)
        plain_failed += fit_ellipsoid(r, 50000.0) is None
        assert fit_ellipsoid_specific(r, 50000.0) is not None
    assert plain_failed >= 1


# -- pso9 and the baselines at the bound on Ding's simulations ---------------------------------
def test_pso9_expands_a_symmetric_matrix():
    x = expand(np.arange(9.0))[0]
    np.testing.assert_array_equal(x, [0, 1, 2, 1, 3, 4, 2, 4, 5, 6, 7, 8])


@pytest.mark.parametrize("name", ["twostep", "ellipsoid_specific"] + [pytest.param(name, marks=pytest.mark.full) for name in (
    "triangular", "ml_scalar", "pso9")])  # make test: the two cheapest
def test_baseline_reaches_the_bound_on_ding(make_cfg, name):
    """Median over seeds of the error / Cramér-Rao bound of W^T W and of the offset within
    [0.5, 1.3] on both of Ding's simulations (A = 5 nT)."""
    for scenario in ("ding2024_exp1", "ding2024_exp2"):
        cfg = make_cfg(f"scenario={scenario}", f"estimator={name}", "scenario.noise=5")
        sc, est = instantiate(cfg.scenario, _convert_="all"), instantiate(cfg.estimator, _convert_="all")
        if name == "pso9":
            est.n_iterations = 400
        ratios = []
        for seed in range(6 if name == "pso9" else 12):
            p = make_problem("scalar", sc.generate(rng=np.random.default_rng(seed)), sc.search)
            m = evaluate(p, est.fit(p, rng=np.random.default_rng(seed)))
            ratios.append((m["gram_error_ratio"], m["offset_error_ratio"]))
        med = np.median(ratios, axis=0)
        assert np.all(med < 1.3) and np.all(med > 0.3), (scenario, med)


def test_local_minimises_exactly_and_least_squares_is_what_lm_minimises(make_cfg):
    """On eq 8's residuals in least squares (``vector_ls``) BFGS (``local``) lands on lm's solution;
    on eq 8 itself it finds a lower F than lm's."""
    cfg = make_cfg("scenario=yuan2018_mode1", "estimator=local")
    sc, local = instantiate(cfg.scenario, _convert_="all"), instantiate(cfg.estimator, _convert_="all")
    lm = instantiate(make_cfg("estimator=lm").estimator, _convert_="all")
    ds = sc.generate(rng=np.random.default_rng(0))
    ls_problem = make_problem("vector_ls", ds, sc.search, **sc.problem_options)
    a, b = local.fit(ls_problem).x, lm.fit(ls_problem).x
    np.testing.assert_allclose(a[9:], b[9:], atol=1e-4)
    eq8 = make_problem("vector", ds, sc.search, **sc.problem_options)
    assert eq8.cost_direct(local.fit(eq8).x) < eq8.cost_direct(b) - 1e-3


# -- boundary handling -------------------------------------------------------------------------
def test_boundary_strategies_by_hand():
    lo, hi = np.array([0.0, 0.0]), np.array([1.0, 1.0])
    x = np.array([[1.3, 0.5], [-0.2, 2.7]])
    v = np.array([[0.5, 0.1], [-0.4, 2.0]])
    rng = np.random.default_rng(0)
    cx, cv = clip(x, v, lo, hi, rng=rng)
    np.testing.assert_allclose(cx, [[1.0, 0.5], [0.0, 1.0]])
    np.testing.assert_array_equal(cv, v)
    rx, rv = reflect(x, v, lo, hi, rng=rng)
    # 1.3 -> 0.7; -0.2 -> 0.2; 2.7 -> 2.7 mod 2 = 0.7 (two widths: back inside going up)
    np.testing.assert_allclose(rx, [[0.7, 0.5], [0.2, 0.7]])
    np.testing.assert_allclose(rv, [[-0.5, 0.1], [0.4, -2.0]])
    qx, qv = random_reentry(x, v, lo, hi, rng=rng)
    assert np.all((qx >= lo) & (qx <= hi)) and qx[0, 1] == 0.5
    np.testing.assert_allclose(qv, [[0.0, 0.1], [0.0, 0.0]])


def test_boundary_is_a_checked_setting_and_reflect_keeps_the_swarm_inside(make_cfg):
    from magexp.errors import MagexpError
    from magexp.run.runner import build

    with pytest.raises(MagexpError, match="estimator.boundary='wall' is not allowed: choose one of clip, reflect"):
        build(make_cfg("estimator=pso", "estimator.boundary=wall").estimator, "pso")
    for name in ("reflect", "random"):
        est = build(make_cfg("estimator=pso", f"estimator.boundary={name}", "estimator.n_iterations=30",
                             "estimator.n_particles=10").estimator, "pso")
        sc = instantiate(make_cfg("scenario=ding2024_exp1").scenario, _convert_="all")
        p = make_problem("scalar", sc.generate(rng=np.random.default_rng(0)), sc.search)
        res = est.fit(p, rng=np.random.default_rng(0))
        assert np.all(res.x >= p.lower) and np.all(res.x <= p.upper)
