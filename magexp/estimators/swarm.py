"""The one swarm engine behind every PSO variant in magexp (:class:`SwarmOptimizer`, whose docstring has
the iteration's equation).

Variants differ only by small strategy pieces passed in: the velocity rule
(:mod:`magexp.estimators.velocity`: one kernel per rule), its coefficient schedules
(:mod:`magexp.estimators.schedules`), the initialiser (:mod:`magexp.estimators.initialisers`) and the
boundary handling (:mod:`magexp.estimators.boundaries`, ``clip`` unless configured). The whole swarm is
evaluated with one call of ``problem.cost``.

Each step runs the kernel in numpy (:func:`numpy_step`) or, with numba (:func:`compiled`), in one
compiled call per iteration (:mod:`magexp.estimators._compiled`), on random numbers drawn several
iterations per call (:func:`_draw_blocks`): the same numbers either way, bit for bit. When the problem
also offers a compiled cost (:func:`magexp.problems.base.swarm_kernel`), the boundary is ``clip`` and no
callback watches, one compiled call runs a whole block of iterations (:meth:`SwarmOptimizer._run`).
"""

from __future__ import annotations

from functools import cache, partial
from itertools import chain

import numpy as np

from magexp.core.outcomes import on_face
from magexp.errors import check, check_nonnegative, check_positive_int
from magexp.estimators import boundaries
from magexp.estimators.initialisers import Uniform
from magexp.estimators.result import FitResult
from magexp.estimators.velocity import ALL, InertiaVelocity
from magexp.problems import kernels
from magexp.problems.base import swarm_kernel


DRAW_BLOCK = 1 << 14  # random numbers drawn per call (128 kB: they stay in cache)
_NO_MOVE = (False, np.empty((0, 0, 0)), np.zeros(3))  # the step after the last iteration: no move


def _draw_blocks(rng: np.random.Generator, rule, shape: tuple, t_max: int, block: int):
    """The random factors of iterations ``1..t_max``, drawn ``block`` iterations per call."""
    buffer = np.empty((min(block, t_max), rule.n_draws, *shape))
    for start in range(1, t_max + 1, block):
        yield rule.factors(rng.random(out=buffer[: min(block, t_max + 1 - start)]))


def numpy_step(kernel, needs_mean, x, v, pbest, pcost, cost, moves, r, c, limits, clip_box) -> int:
    """One step in numpy (the best updates with ``cost``, then, if ``moves``, the next move): the twin of the
    compiled step, the same kernel called once on whole arrays (``i = j =`` :data:`~magexp.estimators.velocity.ALL`)."""
    better = cost < pcost
    np.copyto(pbest, x, where=better[:, None])
    np.copyto(pcost, cost, where=better)
    g = int(pcost.argmin())
    if moves:
        velocity = kernel(ALL, ALL, x, v, pbest, g, pbest.mean(axis=0) if needs_mean else None, r, c)
        np.minimum(np.maximum(velocity, -limits[0]), limits[0], out=v)
        np.add(x, v, out=x)
    return g


@cache
def compiled():
    """The compiled swarm steps, if numba is in use."""
    if kernels.compiled() is None:
        return None
    # lazy: _compiled imports numba at its top (measured 205 ms CPU to import, min of 5, after numpy); building a
    # swarm estimator (pso, ipso, rdpso, pso9) imports this module, and a numpy-only run (MAGEXP_NUMBA=0, no numba)
    # must neither pay for numba nor fail without it. Reached only when kernels.compiled() has loaded numba already.
    from magexp.estimators import _compiled

    return _compiled


def check_speed(value, name: str, per: str) -> float:
    """A velocity limit, refused unless finite and > 0."""
    v = check_nonnegative(value, name)
    check(v > 0, f"{name}={value!r} is not allowed: it must be a number > 0 (v_max = {name.rpartition('.')[2]}"
                 f"{' x ' + per if per else ''}; 0 leaves the velocity unbounded)")
    return v


class SwarmOptimizer:
    """Global-best particle swarm over a box-bounded problem (Kennedy & Eberhart 1995; the engine
    of Ding 2024's PSO and IPSO and of Yuan 2018's RDPSO).

    Every iteration moves each particle by its new velocity (Ding 2024 eqs 10-11, eq 11's ``v^t``
    read as the new velocity; Yuan 2018 eqs 16-17 for RDPSO), then updates the bests:

    .. math:: v_{ij} \\leftarrow \\mathrm{clip}(\\mathrm{rule}_{ij}, -v_{max}, v_{max}),\\quad
              x_{ij} \\leftarrow x_{ij} + v_{ij}

    with the velocity rule of ``velocity`` (Ding 2024 eq 10: :class:`~magexp.estimators.velocity.InertiaVelocity`;
    Yuan 2018 eqs 10-17: :class:`~magexp.estimators.rdpso.RandomDriftVelocity`).

    Parameters
    ----------
    name : str
        As in :class:`~magexp.estimators.base.Estimator`.
    n_particles, n_iterations : int
        Swarm size and number of iterations.
    velocity : VelocityRule, optional
        The velocity rule (:mod:`magexp.estimators.velocity`; default: traditional inertia-weight
        PSO).
    init : callable, optional
        The initialiser ``init(n, lower, upper, rng=rng)`` (default: uniform).
    velocity_clamp : float
        ``v_max = velocity_clamp * (upper - lower)``, > 0 (0 would leave the velocity unbounded:
        the first uniform initial velocity ``U(-inf, inf)`` is not a number).
    initial_velocity : str
        ``"uniform"`` (``U(-v_max, v_max)``) or ``"zero"``.
    velocity_limit : float, optional
        Absolute ``v_max``, the same for every dimension (Yuan 2018 Table 1: 1.5), > 0; when
        given it replaces ``velocity_clamp``.
    boundary : str
        What a particle leaving the box does: ``clip``, ``reflect`` or ``random``
        (:mod:`magexp.estimators.boundaries`).
    references, label : str
        As in :class:`~magexp.estimators.base.Estimator`: each config of the engine sets its own
        (pso, ipso, rdpso: PSO, IPSO, RDPSO; an empty label: the class's).
    """

    needs = ("cost",)
    iterative = True
    label = ""
    smoke = {"n_particles": 6, "n_iterations": 6}
    METRICS = ("on_boundary",)  # the columns its fit writes (:meth:`fit`'s ``metrics``)

    def __init__(self, *, name: str = "pso", n_particles: int = 50, n_iterations: int = 800,
                 velocity=None, init=None, velocity_clamp: float = 0.2,
                 initial_velocity: str = "uniform", references: str = "", velocity_limit: float | None = None,
                 boundary: str = "clip", label: str = ""):
        self.name = name
        self.label = label or type(self).label
        self.n_particles = check_positive_int(n_particles, "estimator.n_particles")
        self.n_iterations = check_positive_int(n_iterations, "estimator.n_iterations")
        self.velocity = velocity if velocity is not None else InertiaVelocity()
        self.init = init if init is not None else Uniform()
        self.velocity_clamp = check_speed(velocity_clamp, "estimator.velocity_clamp", "(upper - lower)")
        self.velocity_limit = None if velocity_limit is None else check_speed(velocity_limit,
                                                                              "estimator.velocity_limit", "")
        check(initial_velocity in ("uniform", "zero"),
              f"estimator.initial_velocity={initial_velocity!r} is not allowed: choose uniform or zero")
        self.initial_velocity = initial_velocity
        self.boundary = boundary
        self._handle = boundaries.boundary(boundary)
        self.references = references

    def velocity_max(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """The per-dimension velocity limit.

        Parameters
        ----------
        lo, hi : ndarray, shape (d,)
            The box.

        Returns
        -------
        ndarray, shape (d,)
            ``v_max``: the absolute limit, or ``velocity_clamp`` times the box's width.
        """
        if self.velocity_limit is not None:
            return np.full(lo.shape, self.velocity_limit)
        return self.velocity_clamp * (hi - lo)

    def _run(self, run, problem, x, v, pbest, pcost, history, blocks, coef, limits) -> int:
        """Every iteration with the cost compiled in, one call per block of draws: the same numbers as one step
        and one ``problem.cost`` per iteration."""
        t, t_max = 0, len(history) - 1
        for r in blocks:
            k = len(r)
            run(x, v, pbest, pcost, history, t, k, r, coef[t: t + k], limits, True, problem)
            t += k
        return run(x, v, pbest, pcost, history, t_max, 1, r[:0], coef[:0], limits, True, problem)

    def fit(self, problem, *, rng: np.random.Generator, callback=None) -> FitResult:
        """Minimise ``problem.cost`` within ``[problem.lower, problem.upper]``.

        Parameters
        ----------
        problem, rng, callback
            As in :meth:`magexp.estimators.base.Estimator.fit`. ``problem``: ``cost(thetas: (n, p)) ->
            (n,)``, ``lower``, ``upper``. ``rng``: every random number of the run (initial swarm, rule,
            boundary). ``callback``: ``callback(t, gbest, gbest_cost)`` after every iteration.

        Returns
        -------
        FitResult
            The best position and cost, the best cost of every iteration, and in ``metrics``
            ``on_boundary``: the coordinates of the best on the box's faces.
        """
        lo, hi = problem.lower, problem.upper
        n, t_max, rule = self.n_particles, self.n_iterations, self.velocity
        vmax = self.velocity_max(lo, hi)
        x = np.array(self.init(n, lo, hi, rng=rng), float, order="C")
        v = rng.uniform(-1.0, 1.0, x.shape) * np.where(np.isfinite(vmax), vmax, 0.0) \
            if self.initial_velocity == "uniform" else np.zeros_like(x)
        pcost = np.array(problem.cost(x), float)
        pbest = x.copy()
        history = np.empty(t_max + 1)
        limits = np.stack([vmax, lo, hi]).astype(float)
        coef = rule.schedule(np.arange(1, t_max + 1), t_max)  # row t: the move at time t + 1
        # a boundary that draws (random re-entry) takes its numbers between two moves'
        block = 1 if self.boundary == "random" else max(1, DRAW_BLOCK // (rule.n_draws * x.size))
        blocks = _draw_blocks(rng, rule, x.shape, t_max, block)
        nb = compiled()
        clip_box = nb is not None and self.boundary == "clip"  # the compiled move clips; numpy: self._handle
        kernel = swarm_kernel(problem) if clip_box and callback is None else None
        engine = nb.engine(rule.kernel, rule.needs_mean) if nb is not None else None
        if kernel is not None:  # every iteration, compiled in
            g = self._run(engine.run, kernel, x, v, pbest, pcost, history, blocks, coef, limits)
            return self._result(pbest, pcost, g, history, t_max, lo, hi)
        step = engine.step if engine is not None else partial(numpy_step, rule.kernel, rule.needs_mean)
        moves = ((True, r, c) for r, c in zip(chain.from_iterable(blocks), coef))
        g = step(x, v, pbest, pcost, pcost, *next(moves), limits, clip_box)
        history[0], nit = pcost[g], 0
        for t in range(1, t_max + 1):
            if not clip_box:
                x, v = self._handle(x, v, lo, hi, rng=rng)
            # iteration t's best updates, then iteration t + 1's move
            g = step(x, v, pbest, pcost, problem.cost(x), *next(moves, _NO_MOVE), limits, clip_box)
            history[t], nit = pcost[g], t
            if callback is not None and callback(t, pbest[g], pcost[g]):
                break
        return self._result(pbest, pcost, g, history, nit, lo, hi)

    def _result(self, pbest, pcost, g, history, nit, lo, hi) -> FitResult:
        """The :class:`FitResult` of the best ``pbest[g]`` after ``nit`` iterations."""
        history, n = history[: nit + 1], len(pcost)
        edge = on_face(pbest[g], lo, hi)  # |best - face| <= FACE_TOL (hi - lo), or on an infinite face
        return FitResult(
            x=pbest[g].copy(), fun=float(pcost[g]), nit=nit, nfev=n * (nit + 1),
            history=history, history_nfev=n * np.arange(1, nit + 2),
            message=f"{nit} iterations of {n} particles",
            metrics={"on_boundary": int(edge.sum())},  # coordinates of the best on the box's faces
        )
