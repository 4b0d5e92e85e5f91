"""The one swarm engine behind every PSO variant in magexp.

Variants differ only by small strategy pieces passed in: the velocity rule
(:mod:`magexp.estimators.velocity`), its coefficient schedules
(:mod:`magexp.estimators.schedules`) and the initialiser
(:mod:`magexp.estimators.initialisers`). One iteration is

.. math::

    v &\\leftarrow \\mathrm{clip}(\\mathrm{rule}(x, v, p, g, t), -v_{max}, v_{max}) \\\\
    (x, v) &\\leftarrow \\mathrm{boundary}(x + v, v, l, u)

(the new velocity moves the particle: Ding 2024 eq 11 prints ``v^t``, a typo; the boundary
handling, :mod:`magexp.estimators.boundaries`, is ``clip`` unless configured),
followed by the personal-best and global-best updates. The whole swarm is
evaluated with one call of ``problem.cost``.

With numba (:func:`compiled`), a rule whose class has a ``step`` method beside its ``__call__``
(the built-in ones) makes one
compiled call per iteration of the best updates and the next iteration's rule, clamp, move and
``clip`` (:mod:`magexp.estimators._compiled`), on random numbers drawn several iterations per
call (:func:`_draw_blocks`; the same stream): the same numbers, bit for bit, as the numpy path, which
runs otherwise (``MAGEXP_NUMBA=0``, numba missing, or a rule without ``step``).

When, besides, the problem offers a compiled cost (:func:`magexp.problems.base.swarm_kernel`),
the boundary is ``clip``, the rule has ``coefficients`` and no callback watches the iterations,
the cost joins the compiled call and one call runs a whole block of draws' iterations
(:meth:`SwarmOptimizer._run`, :func:`magexp.estimators._compiled.run`): no Python, no dispatch
and no argument conversion per iteration, and again the same numbers, bit for bit.
"""

from __future__ import annotations

from functools import cache
from itertools import chain

import numpy as np

from magexp.core.outcomes import on_face
from magexp.errors import check, check_nonnegative, check_positive_int
from magexp.estimators import boundaries
from magexp.estimators.initialisers import Uniform
from magexp.estimators.result import FitResult
from magexp.estimators.velocity import InertiaVelocity
from magexp.problems import kernels
from magexp.problems.base import defining_class, swarm_kernel


DRAW_BLOCK = 1 << 14  # random numbers drawn per call by the compiled path (128 kB: they stay in cache)


def _draw_blocks(rng: np.random.Generator, shape: tuple, t_max: int, block: int):
    """The random numbers of iterations ``1..t_max``, ``shape`` each, drawn ``block`` iterations
    per call (arrays ``(k, *shape)``): the same stream as one ``rng.random(shape)`` per iteration
    (a generator fills an array in order), with less overhead per call. Every block is drawn into
    the same buffer (no fresh pages per block): a block is used up before the next is drawn."""
    buffer = np.empty((min(block, t_max), *shape))
    for start in range(1, t_max + 1, block):
        yield rng.random(out=buffer[: min(block, t_max + 1 - start)])


def _has_step(rule, name: str = "step") -> bool:
    """Whether ``rule`` has a compiled ``step`` (or ``coefficients``) of its own rule: one defined
    by the class that defines its ``__call__`` (a subclass that changes the rule but not the step
    runs in numpy)."""
    owner = defining_class(rule, name)
    return owner is not None and owner is defining_class(rule, "__call__")


@cache
def compiled():
    """The compiled swarm steps (a namespace), or None when numba is unavailable or
    ``MAGEXP_NUMBA=0`` (the switch of :func:`magexp.problems.kernels.compiled`)."""
    if kernels.compiled() is None:
        return None
    # lazy: numba, measured 205 ms CPU to import (min of 5, after numpy); this module is imported by every lm run
    # (magexp.estimators.reduced), which must not pay for it
    from magexp.estimators import _compiled

    return _compiled


def check_speed(value, name: str, per: str) -> float:
    """``value`` as a float, refused unless finite and > 0: a ``v_max`` of 0 (or none) leaves the velocity
    unbounded, its uniform initial draw ``U(-inf, inf)`` is not a number."""
    v = check_nonnegative(value, name)
    check(v > 0, f"{name}={value!r} is not allowed: it must be a number > 0 (v_max = {name.rpartition('.')[2]}"
                 f"{' x ' + per if per else ''}; 0 leaves the velocity unbounded)")
    return v


class SwarmOptimizer:
    """Global-best particle swarm over a box-bounded problem.

    Parameters
    ----------
    name : config name of this estimator.
    n_particles, n_iterations : swarm size and number of iterations.
    velocity : velocity rule (default: traditional inertia-weight PSO).
    init : initialiser (default: uniform).
    velocity_clamp : ``v_max = velocity_clamp * (upper - lower)``, > 0 (0 would leave the velocity unbounded:
        the first uniform initial velocity ``U(-inf, inf)`` is not a number).
    velocity_limit : absolute ``v_max``, the same for every dimension (Yuan 2018 Table 1:
        1.5), > 0; when given it replaces ``velocity_clamp``.
    initial_velocity : ``"uniform"`` (``U(-v_max, v_max)``) or ``"zero"``.
    boundary : what a particle leaving the box does: ``clip``, ``reflect`` or ``random``
        (:mod:`magexp.estimators.boundaries`).
    references : the paper(s) the variant comes from.
    label : its name in the report's row labels (pso, ipso, rdpso: PSO, IPSO, RDPSO); empty: the class's.
    """

    needs = ("cost",)
    iterative = True
    label = ""
    smoke = {"n_particles": 6, "n_iterations": 6}

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
        """Per-dimension ``v_max``: absolute limit, fraction of the box, or ``inf`` (no clamp)."""
        if self.velocity_limit is not None:
            return np.full(lo.shape, self.velocity_limit)
        return self.velocity_clamp * (hi - lo)

    def _run(self, nb, kernel, x, v, pbest, pcost, history, blocks, limits) -> int:
        """Every iteration with the cost compiled in (:func:`magexp.estimators._compiled.run`): one
        call per block of draws, from the initial move (iteration 0, on the costs in ``pcost``) to
        the last iteration (no move), which joins the last block's call. The same numbers as one
        :meth:`velocity.step` and one ``problem.cost`` per iteration. Returns the global best's index."""
        rule, t, t_max = self.velocity, 0, len(history) - 1
        coef = rule.coefficients(np.arange(1, t_max + 1), t_max)  # iteration t moves at time t + 1: row t
        for r in blocks:
            k = len(r)
            nb.run(x, v, pbest, pcost, history, t, k, r, rule.log_u(r), coef[t: t + k], rule.drift, limits, True,
                   kernel)
            t += k
        return nb.run(x, v, pbest, pcost, history, t_max, 1, r[:0], rule.log_u(r[:0]), coef[:0], rule.drift, limits,
                      True, kernel)

    def fit(self, problem, *, rng: np.random.Generator, callback=None) -> FitResult:
        """Minimise ``problem.cost`` within ``[problem.lower, problem.upper]``.

        ``callback(t, gbest, gbest_cost)`` is called after every iteration; a
        true return value stops the run.
        """
        lo, hi = problem.lower, problem.upper
        n, t_max = self.n_particles, self.n_iterations
        vmax = self.velocity_max(lo, hi)
        x = self.init(n, lo, hi, rng=rng)
        v = rng.uniform(-1.0, 1.0, x.shape) * np.where(np.isfinite(vmax), vmax, 0.0) \
            if self.initial_velocity == "uniform" else np.zeros_like(x)
        cost = problem.cost(x)
        pbest, pcost = x.copy(), cost.copy()
        g = int(np.argmin(pcost))
        history = np.empty(t_max + 1)
        history[0] = pcost[g]
        nit = 0
        neg_vmax = -vmax
        nb = compiled() if _has_step(self.velocity) else None
        clip_box = self.boundary == "clip"
        kernel = None
        if nb is not None:  # moved in place, one compiled call per iteration (module docstring)
            x, v, pcost = np.array(x, float, order="C"), np.array(v, float, order="C"), np.array(pcost, float)
            limits = np.empty((3, lo.size))
            limits[0], limits[1], limits[2] = vmax, lo, hi
            # a boundary that draws (random re-entry) takes its numbers between two moves'
            block = 1 if self.boundary == "random" else max(1, DRAW_BLOCK // (self.velocity.n_draws * x.size))
            blocks = _draw_blocks(rng, (self.velocity.n_draws, *x.shape), t_max, block)
            if clip_box and callback is None and _has_step(self.velocity, "coefficients"):
                kernel = swarm_kernel(problem)
            if kernel is not None:  # every iteration, compiled in
                g, nit = self._run(nb, kernel, x, v, pbest, pcost, history, blocks, limits), t_max
            else:
                draws = chain.from_iterable(blocks)
                g = self.velocity.step(nb, x, v, pbest, pcost, pcost, next(draws), 1, t_max, limits, clip_box)
        for t in range(1, 1 if kernel is not None else t_max + 1):
            if nb is not None:
                if not clip_box:
                    x, v = self._handle(x, v, lo, hi, rng=rng)
                # iteration t's best updates, then iteration t + 1's move
                g = self.velocity.step(nb, x, v, pbest, pcost, problem.cost(x), next(draws, None), t + 1, t_max,
                                       limits, clip_box)
            else:
                # clip as min(max(.)): the same numbers as np.clip without its per-call overhead
                v = np.minimum(np.maximum(self.velocity(x, v, pbest, pbest[g], t, t_max, rng=rng), neg_vmax), vmax)
                x, v = self._handle(x + v, v, lo, hi, rng=rng)
                cost = problem.cost(x)
                better = cost < pcost
                np.copyto(pbest, x, where=better[:, None])
                np.copyto(pcost, cost, where=better)
                g = int(pcost.argmin())
            history[t] = pcost[g]
            nit = t
            if callback is not None and callback(t, pbest[g], pcost[g]):
                break
        history = history[: nit + 1]
        edge = on_face(pbest[g], lo, hi)  # |best - face| <= FACE_TOL (hi - lo), or on an infinite face
        return FitResult(
            x=pbest[g].copy(), fun=float(pcost[g]), nit=nit, nfev=n * (nit + 1),
            history=history, history_nfev=n * np.arange(1, nit + 2),
            message=f"{nit} iterations of {n} particles",
            metrics={"on_boundary": int(edge.sum())},  # coordinates of the best on the box's faces
        )
