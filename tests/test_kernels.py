"""The fused costs: compiled and numpy kernels agree to 1e-9, neither chunking nor the other particles
evaluated alongside change a particle's bits, and the compiled kernels give the same bits in every
call and every process."""

import subprocess
import sys

import numpy as np
import pytest

from magexp.errors import MagexpError
from magexp.problems import kernels

needs_numba = pytest.mark.skipif(kernels.compiled() is None, reason="numba not installed or MAGEXP_NUMBA=0")


def swarm(n_readings, n_particles, seed=0):
    """Readings around a 500-unit field, particles around a sensible calibration, plus the exact one."""
    rng = np.random.default_rng(seed)
    readings = rng.standard_normal((n_readings, 3)) * 500 + [30.0, -20.0, 10.0]
    w = np.eye(3) + 0.05 * rng.standard_normal((n_particles, 3, 3))
    o = 40 * rng.standard_normal((n_particles, 3))
    w[0], o[0] = np.eye(3), [30.0, -20.0, 10.0]
    return readings, w, o


@needs_numba
@pytest.mark.parametrize("n_readings, n_particles", [(1, 1), (7, 3), (300, 50), (2000, 600)])
def test_scalar_kernels_agree_with_the_direct_formula(n_readings, n_particles):
    readings, w, o = swarm(n_readings, n_particles)
    reference = np.linalg.norm(readings - [30.0, -20.0, 10.0], axis=1)
    from magexp.core.ellipsoid import normalise

    c, s, u = normalise(readings)
    direct = np.array([np.sqrt(np.mean((np.linalg.norm((readings - oi) @ wi.T, axis=1) - reference) ** 2))
                       for wi, oi in zip(w, o)])
    fused = kernels.compiled().scalar_cost(w, o, c, s, u, reference)
    np.testing.assert_allclose(fused, kernels.scalar_cost_numpy(w, o, c, s, u, reference), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(fused, direct, rtol=1e-9, atol=1e-9)
    residuals = kernels.compiled().scalar_residuals(w[-1], o[-1], readings, reference)
    np.testing.assert_allclose(residuals, np.linalg.norm((readings - o[-1]) @ w[-1].T, axis=1) - reference,
                               rtol=1e-12, atol=1e-9)


@needs_numba
@pytest.mark.parametrize("n_readings, n_particles", [(1, 1), (7, 3), (300, 50), (2000, 600)])
def test_vector_kernels_agree_with_the_direct_formula(n_readings, n_particles):
    readings, w, o = swarm(n_readings, n_particles)
    reference = (readings - [30.0, -20.0, 10.0]) + np.random.default_rng(1).standard_normal((n_readings, 3))
    direct = np.array([np.linalg.norm(reference - (readings - oi) @ wi.T, axis=1).sum() for wi, oi in zip(w, o)])
    fused = kernels.compiled().vector_cost(w, o, readings, reference)
    np.testing.assert_allclose(fused, kernels.vector_cost_numpy(w, o, readings, reference), rtol=1e-9)
    np.testing.assert_allclose(fused, direct, rtol=1e-9)


def fallback_costs(w, o, readings):
    """The numpy fallback's scalar, vector and squared-vector costs of ``(w, o)`` on ``readings``."""
    from magexp.core.ellipsoid import normalise

    c, s, u = normalise(readings)
    return np.concatenate([kernels.scalar_cost_numpy(w, o, c, s, u, np.linalg.norm(readings, axis=1)),
                           kernels.vector_cost_numpy(w, o, readings, readings),
                           kernels.vector_cost_numpy(w, o, readings, readings, squared=True)])


def test_chunking_does_not_change_the_fallback(monkeypatch):
    """A chunk of 7 particle-readings (many chunks, a ragged last one) gives the unchunked bits: the
    sums run reading after reading across the chunks."""
    readings, w, o = swarm(101, 5)
    whole = fallback_costs(w, o, readings)
    monkeypatch.setattr(kernels, "CHUNK", 7)
    np.testing.assert_array_equal(fallback_costs(w, o, readings), whole)


@pytest.mark.parametrize("n_readings, n_particles", [(7, 3), (300, 50), (2000, 2)])
def test_a_particles_cost_does_not_depend_on_the_particles_beside_it(n_readings, n_particles):
    """Each particle alone, and the swarm in another order, give each particle the bits it has in
    the whole swarm: in the numpy fallback and in the path in use (compiled unless MAGEXP_NUMBA=0).
    So a fit's ``fun``, recorded from a whole population, is ``cost(x)`` of its ``x`` (the
    black-box estimators' callbacks check that)."""
    from magexp.core.ellipsoid import normalise

    readings, w, o = swarm(n_readings, n_particles)
    c, s, u = normalise(readings)
    reference = np.linalg.norm(readings, axis=1)
    order = np.random.default_rng(1).permutation(n_particles)
    for cost in (lambda w, o: fallback_costs(w, o, readings).reshape(3, -1),
                 lambda w, o: np.stack([kernels.scalar_cost(w, o, c, s, u, reference),
                                        kernels.vector_cost(w, o, readings, readings)])):
        whole = cost(w, o)
        alone = np.column_stack([cost(w[k:k + 1], o[k:k + 1]) for k in range(n_particles)])
        np.testing.assert_array_equal(alone, whole)
        np.testing.assert_array_equal(cost(w[order], o[order]), whole[:, order])


@pytest.mark.parametrize("n_particles", [50, 5000])
def test_the_fallbacks_working_memory_is_one_chunk(n_particles):
    """What the run guard counts for the numpy fallback (:func:`kernels.working_floats`) bounds the peak
    of one call beyond its inputs (tracemalloc, which numpy reports to) and is under twice it:
    ``O(max(CHUNK, P))`` on 2 000 readings, never readings x particles."""
    import tracemalloc

    readings, w, o = swarm(2000, n_particles)
    reference = np.linalg.norm(readings, axis=1)
    from magexp.core.ellipsoid import normalise

    c, s, u = normalise(readings)
    for rows, call in ((1, lambda: kernels.scalar_cost_numpy(w, o, c, s, u, reference)),
                       (3, lambda: kernels.vector_cost_numpy(w, o, readings, readings))):
        tracemalloc.start()
        call()
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        bound = 8 * kernels.working_floats(n_particles, rows, fused=False)
        assert bound / 2 <= peak <= bound, (rows, peak, bound)


def test_fallback_is_used_without_numba(monkeypatch):
    readings, w, o = swarm(50, 4)
    monkeypatch.setenv("MAGEXP_NUMBA", "0")
    kernels.compiled.cache_clear()
    try:
        assert kernels.compiled() is None
        f = kernels.vector_cost(w, o, readings, readings)
    finally:
        kernels.compiled.cache_clear()
    np.testing.assert_array_equal(f, kernels.vector_cost_numpy(w, o, readings, readings))


def test_non_finite_vector_cost_is_inf():
    readings, w, o = swarm(10, 3)
    w[1, 0, 0] = np.nan
    w[2, 0, 0] = 1e300
    f = kernels.vector_cost(w, o, readings, readings)
    assert np.isfinite(f[0]) and f[1] == np.inf and f[2] == np.inf


SNIPPET = """
import hashlib, numpy as np
from magexp.problems import kernels
rng = np.random.default_rng(5)
r = rng.standard_normal((997, 3)) * 500; w = np.eye(3) + 0.1 * rng.standard_normal((83, 3, 3))
o = 50 * rng.standard_normal((83, 3)); ref = np.linalg.norm(r, axis=1)
c, s, u = r.mean(axis=0), 500.0, (r - r.mean(axis=0)) / 500.0
nb = kernels.compiled()
print(hashlib.sha256(nb.scalar_cost(w, o, c, s, u, ref).tobytes() + nb.vector_cost(w, o, r, r).tobytes()).hexdigest())
"""


@needs_numba
@pytest.mark.full  # two fresh processes (make test-full); the in-process bit tests: test_determinism.py
def test_compiled_kernels_are_bitwise_reproducible_across_processes():
    """No fastmath, no threads: two fresh processes give the same bits (and so does this one)."""
    runs = [subprocess.run([sys.executable, "-c", SNIPPET], capture_output=True, text=True, check=True).stdout
            for _ in range(2)]
    assert runs[0] == runs[1] and len(runs[0].strip()) == 64
    namespace = {}
    exec(SNIPPET.replace("print(", "namespace_out = ("), namespace)
    assert namespace["namespace_out"] == runs[0].strip()


@needs_numba
@pytest.mark.parametrize("objective", ["scalar", "vector"])
def test_the_lean_swarm_cost_gives_the_kernels_bits(objective):
    """``problem.cost`` through the prepared compiled entry (:func:`kernels.swarm_cost`) equals the
    kernels called on ``W``, ``o`` bit for bit, a non-finite particle included; a forward
    parameterisation and a subclass that changes the cost get no compiled entry."""
    from magexp.core.dataset import Dataset
    from magexp.problems import make_problem
    from magexp.problems.base import swarm_kernel
    from magexp.scenarios.search import SearchBox

    readings, w, o = swarm(257, 31)
    w[3, 0, 0] = np.nan
    n = len(readings)
    body = readings - [30.0, -20.0, 10.0]
    dataset = Dataset(readings=readings, reference_norm=np.linalg.norm(body, axis=1),
                      attitude=np.broadcast_to(np.eye(3), (n, 3, 3)), field_nav=body)
    box = SearchBox(diag=(0.5, 1.5), offdiag=(-0.5, 0.5), offset=(-100.0, 100.0))
    problem = make_problem(objective, dataset, box, parameterisation="inverse")
    assert swarm_kernel(problem) is not None
    if objective == "scalar":
        expected = kernels.scalar_cost(w, o, *problem._normalised, problem._reference)
    else:
        expected = kernels.vector_cost(w, o, problem._readings, problem.reference)
        assert expected[3] == np.inf
    thetas = np.concatenate([w.reshape(-1, 9), o], axis=1)
    np.testing.assert_array_equal(problem.cost(thetas), expected)
    np.testing.assert_array_equal(problem.cost(thetas[5]), expected[5:6])  # one vector: shape (1,)
    with pytest.raises(MagexpError, match=r"shape \(31, 9\)"):
        problem.cost(thetas[:, :9])
    assert swarm_kernel(make_problem(objective, dataset, box, parameterisation="forward")) is None
    if objective == "vector":
        assert swarm_kernel(make_problem("vector_ls", dataset, box, parameterisation="inverse")) is None
