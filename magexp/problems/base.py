"""What a calibration problem is (the :class:`Problem` protocol), what it can offer an estimator
(its capabilities), and the parameterisation shared by the 12-parameter problems.

A problem offers some of these capabilities (:data:`CAPABILITIES`); an estimator declares the ones
it needs (``needs``, :mod:`magexp.estimators.base`) and
:func:`magexp.estimators.base.applies_to` compares the two, in one place.

* ``cost``: ``cost(thetas (n, p)) -> (n,)`` over the search box ``[lower, upper]`` (every problem);
* ``residuals``: ``residuals(theta) -> (m,)`` whose sum of squares a least-squares method minimises;
* ``linear_design``: the readings are linear in the parameters, ``B_i = S u_i + b`` with known
  reference vectors ``u_i = C_i H_i`` (attitudes and field): :class:`LinearProblem`;
* ``total_field``: the readings against a reference total field ``|W (r_i - o)| = B_a,i``
  (rotation-invariant: a scalar objective).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from magexp.errors import MagexpError

SCALAR, VECTOR = 0, 1  # the kinds of compiled swarm cost (:func:`magexp.problems._compiled.swarm_cost`)

PARAMETERISATIONS = ("inverse", "forward")
#: float64 numbers a cost call is assumed to hold per particle-reading when its problem does not say
#: (:meth:`CalibrationProblem.cost_floats`): a swarm cost that forms ``(P, N, 3)`` arrays
FLOATS_PER_PARTICLE_READING = 3

#: Every capability a problem may offer, with the words used in a refusal.
CAPABILITIES: dict[str, str] = {
    "cost": "a vectorised cost over a search box",
    "residuals": "a residual vector",
    "linear_design": "a linear design B = S u + b with known reference vectors u (attitudes and field)",
    "total_field": "a reference total field (a scalar objective)",
}


@runtime_checkable
class Problem(Protocol):
    """A calibration problem: parameters <-> calibration, a swarm cost and a residual vector.

    Attributes
    ----------
    objective : str
        Its name in :data:`magexp.problems.OBJECTIVES`.
    capabilities : frozenset of str
        The subset of :data:`CAPABILITIES` it offers.
    n_params : int
        The parameter count ``p``.
    lower, upper : ndarray, shape (p,)
        The search box.
    dataset : magexp.core.dataset.Dataset
        The data it was built on.
    """

    objective: str
    capabilities: frozenset
    n_params: int
    lower: np.ndarray
    upper: np.ndarray

    def cost(self, thetas: np.ndarray) -> np.ndarray:
        """The objective of every parameter vector.

        Parameters
        ----------
        thetas : ndarray, shape (n, p)
            Parameter vectors within ``[lower, upper]``.

        Returns
        -------
        ndarray, shape (n,)
            The cost of each.
        """

    def cost_direct(self, theta: np.ndarray) -> float:
        """The objective of one parameter vector by its textbook formula (the reported number).

        Parameters
        ----------
        theta : ndarray, shape (p,)
            One row of :meth:`cost`'s ``thetas``.

        Returns
        -------
        float
            The cost.
        """

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        """The residual vector whose sum of squares least squares minimises.

        Parameters
        ----------
        theta : ndarray, shape (p,)
            The point (within the box or not).

        Returns
        -------
        ndarray, shape (m,)
            The residuals.
        """

    def unpack(self, thetas: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The calibrations ``B = W (r - o)`` of parameter vectors.

        Parameters
        ----------
        thetas : ndarray, shape (n, p)
            Parameter vectors.

        Returns
        -------
        W, o : ndarray, shapes (n, 3, 3) and (n, 3)
            Each vector's ``W`` and ``o``.
        """

    def pack(self, w: np.ndarray, o: np.ndarray) -> np.ndarray:
        """The parameter vector of the calibration ``B = w (r - o)``.

        Parameters
        ----------
        w : ndarray, shape (3, 3)
            The calibration matrix.
        o : ndarray, shape (3,)
            The offset.

        Returns
        -------
        ndarray, shape (p,)
            The parameter vector.
        """


@runtime_checkable
class LinearProblem(Problem, Protocol):
    """A problem with the capability ``linear_design``: ``Y = C x`` (see
    :class:`magexp.problems.vector.LinearVectorModel`)."""

    def design(self) -> tuple[np.ndarray, np.ndarray]:
        """The linear design ``Y = C x``.

        Returns
        -------
        C : ndarray, shape (N, 4)
            The regressors ``[u_i^T, 1]``.
        Y : ndarray, shape (N, 3)
            The readings.
        """

    def least_squares(self) -> np.ndarray:
        """The least-squares parameter vector of ``Y = C x``.

        Returns
        -------
        ndarray, shape (p,)
            The parameter vector.
        """

    def from_linear(self, states: np.ndarray) -> np.ndarray:
        """The parameter vectors of linear states (the Kalman filters' ``x``).

        Parameters
        ----------
        states : ndarray, shape (..., 4, 3)
            States of ``Y = C x`` (:class:`magexp.problems.vector.LinearVectorModel`).

        Returns
        -------
        ndarray, shape (..., p)
            The parameter vectors.
        """


def describe(capabilities) -> str:
    """The capabilities in words, joined by ``, ``."""
    return ", ".join(CAPABILITIES[c] for c in sorted(capabilities))


def inverse(mats: np.ndarray) -> np.ndarray:
    """Inverses of a stack of 3x3 matrices; an exactly singular one (a swarm clipped onto
    the box edges can make one) gets its pseudo-inverse instead of stopping the run.
    """
    try:
        return np.linalg.inv(mats)
    except np.linalg.LinAlgError:
        return np.linalg.pinv(mats)


def defining_class(obj, name: str):
    """The class in ``type(obj)``'s MRO that defines ``name`` (None if none): whether two methods (a derivative and
    its function) still belong together after subclassing."""
    return next((c for c in type(obj).__mro__ if name in vars(c)), None)


def swarm_kernel(problem) -> tuple | None:
    """``problem``'s compiled swarm-cost arguments (:meth:`CalibrationProblem.swarm_kernel`), or None where it has none
    or its ``cost`` is defined elsewhere (a subclass that changes the cost gets the generic path)."""
    if defining_class(problem, "swarm_kernel") is not defining_class(problem, "cost"):
        return None
    return problem.swarm_kernel()


def reference_vectors(dataset) -> np.ndarray:
    """``C_i^b H_i`` of every reading, shape ``(N, 3)``: the known attitude times the nav field."""
    return np.einsum("nij,nj->ni", dataset.attitude, dataset.field_nav)


class CalibrationProblem:
    """A 12-parameter calibration ``B = W (reading - o)``.

    Parameters
    ----------
    dataset : magexp.core.dataset.Dataset
        The readings (and, by problem, the attitudes, gyro rates or reference field) to calibrate.
    search : magexp.scenarios.search.SearchBox
        The search box: its ``bounds()`` are ``lower`` and ``upper``.
    parameterisation : {"inverse", "forward"}, optional
        ``"inverse"``: ``theta = [vec(W), o]`` (Ding 2024: ``W = M^-1``, ``o = I``);
        ``"forward"``: ``theta = [vec(S), b]`` with ``W = S^-1`` (Yuan 2018). ``vec`` is row-major.

    Raises
    ------
    MagexpError
        When ``parameterisation`` is neither.
    """

    n_params = 12
    capabilities = frozenset({"cost", "residuals"})
    #: the parameter names of each parameterisation (:meth:`parameter_names`): the runs table's estimate columns
    PARAMETERS = {p: (*(f"{m}{i + 1}{j + 1}" for i in range(3) for j in range(3)), *(f"{o}{i + 1}" for i in range(3)))
                  for p, (m, o) in {"inverse": ("Minv", "I"), "forward": ("S", "b")}.items()}
    #: the columns :meth:`metrics` writes (``fg`` with known attitudes, the errors with a known truth)
    METRICS = ("fg", "gram_error", "offset_error", "matrix_error", "param_matrix_error", "param_offset_error")
    #: the prefixes of the columns :meth:`metrics` names after each parameter (``se_`` writes ``se_<parameter>``)
    PARAMETER_METRICS: tuple = ()

    def __init__(self, dataset, search, *, parameterisation: str = "inverse"):
        if parameterisation not in PARAMETERISATIONS:
            raise MagexpError(
                f"parameterisation={parameterisation!r} is not allowed: choose one of {', '.join(PARAMETERISATIONS)}"
            )
        self.dataset = dataset
        self.parameterisation = parameterisation
        self.options = {"parameterisation": parameterisation}
        self.lower, self.upper = search.bounds()

    @classmethod
    def cost_floats(cls, n_readings: int, n_particles: int) -> int:
        """float64 numbers one :meth:`cost` call holds beyond the problem's data (what :mod:`magexp.run.budget`
        adds to a run's memory); here, for a problem that does not say, :data:`FLOATS_PER_PARTICLE_READING`
        per particle-reading.

        Parameters
        ----------
        n_readings, n_particles : int
            The readings ``N`` and the particles ``P`` of one call.

        Returns
        -------
        int
            The float64 numbers held.
        """
        return FLOATS_PER_PARTICLE_READING * n_readings * n_particles

    def swarm_kernel(self) -> tuple | None:
        """``(kind, data, reference, params)``: the arguments, prepared once, of the compiled swarm cost
        (:func:`magexp.problems.kernels.swarm_cost`) equal to :meth:`cost` bit for bit, or None (here: a
        problem without one). Read it through :func:`swarm_kernel`.

        Returns
        -------
        tuple or None
            The prepared arguments, or None.
        """
        return None

    # -- parameters <-> model ---------------------------------------------------------------
    def unpack(self, thetas: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`Problem.unpack` for ``p = 12``.

        Parameters
        ----------
        thetas : ndarray, shape (n, 12) or (12,)
            ``[vec(W), o]`` (inverse) or ``[vec(S), b]`` with ``W = S^-1`` (forward), row-major.

        Returns
        -------
        W, o : ndarray, shapes (n, 3, 3) and (n, 3)
            As in :meth:`Problem.unpack`.
        """
        thetas = np.atleast_2d(thetas)
        mat = thetas[:, :9].reshape(-1, 3, 3)
        if self.parameterisation == "forward":
            mat = inverse(mat)
        return mat, thetas[:, 9:]

    def pack(self, w: np.ndarray, o: np.ndarray) -> np.ndarray:
        """:meth:`Problem.pack` for ``p = 12``, the inverse of :meth:`unpack`.

        Parameters
        ----------
        w, o
            As in :meth:`Problem.pack`.

        Returns
        -------
        ndarray, shape (12,)
            ``[vec(W), o]`` (inverse) or ``[vec(W^-1), o]`` (forward), row-major.
        """
        mat = np.linalg.inv(w) if self.parameterisation == "forward" else w
        return np.concatenate([np.asarray(mat, float).ravel(), np.asarray(o, float).ravel()])

    def truth_theta(self) -> np.ndarray | None:
        """The true parameter vector, if the dataset knows it.

        Returns
        -------
        ndarray, shape (12,) or None
            :meth:`pack` of the truth's matrix and offset, or None (no truth: a recording).
        """
        t = self.dataset.truth
        return None if t is None else self.pack(t.matrix, t.offset)

    def calibrate(self, theta: np.ndarray, readings: np.ndarray | None = None) -> np.ndarray:
        """Calibrated readings ``W (r_i - o)``.

        Parameters
        ----------
        theta : ndarray, shape (12,)
            A parameter vector (:meth:`unpack`).
        readings : ndarray, shape (N, 3), optional
            The raw readings (default the dataset's).

        Returns
        -------
        ndarray, shape (N, 3)
            ``W (r_i - o)`` of every reading.
        """
        w, o = self.unpack(theta)
        readings = self.dataset.readings if readings is None else readings
        return (readings - o[0]) @ w[0].T

    def residual_stack(self, thetas: np.ndarray, of=None) -> np.ndarray:
        """:meth:`residuals` of each parameter vector of a stack: the residual function
        :func:`magexp.core.identifiability.identifiability` takes.

        Parameters
        ----------
        thetas : ndarray, shape (n, p)
            Parameter vectors (this problem's, or ``of``'s).
        of : callable, optional
            ``row -> theta``, from another parameterisation to this problem's (e.g. the 9 parameters of a
            symmetric matrix part, :func:`magexp.problems.symmetric.expand`; ``magexp calibrate``'s
            ``[vec W, o]`` or ``[s, o]``).

        Returns
        -------
        ndarray, shape (n, m)
            :meth:`residuals` of each row.
        """
        return np.array([self.residuals(row if of is None else of(row)) for row in np.atleast_2d(thetas)])

    def parameter_names(self) -> list[str]:
        """The names of the 12 parameters, in :meth:`pack`'s order.

        Returns
        -------
        list of str
            ``Minv11``...``Minv33``, ``I1``...``I3`` (inverse, Ding 2024's ``M^-1`` and ``I``) or ``S11``...``S33``,
            ``b1``...``b3`` (forward, Yuan 2018's ``S`` and ``b``).
        """
        return list(self.PARAMETERS[self.parameterisation])

    # -- metrics ---------------------------------------------------------------------------
    def metrics(self, theta: np.ndarray) -> dict:
        """Problem-specific metrics of a fitted ``theta`` (subclasses may add their own).

        With a known truth: ``gram_error``: relative Frobenius error of ``W^T W`` (rotation-invariant, what a
        scalar fit identifies); ``offset_error``: Euclidean error of the offset;
        ``matrix_error``: largest absolute error of an entry of ``W`` (needs a vector fit);
        ``param_matrix_error`` / ``param_offset_error``: largest absolute error of an entry of
        the parameter vector's matrix part (``S`` in the forward form) / offset part.
        With known attitudes, ``fg``: Yuan 2018's ``F_g`` (eq 8) at ``theta``, whatever the objective.

        Parameters
        ----------
        theta : ndarray, shape (12,)
            The fitted parameter vector.

        Returns
        -------
        dict
            Metric name -> float (the keys above present when their data are).
        """
        out = {}
        if self.dataset.attitude is not None and self.dataset.field_nav is not None:
            out["fg"] = self.fg(theta)
        truth = self.dataset.truth
        if truth is None:
            return out
        w, o = self.unpack(theta)
        w, o = w[0], o[0]
        gt = truth.matrix.T @ truth.matrix
        out.update({
            "gram_error": float(np.linalg.norm(w.T @ w - gt) / np.linalg.norm(gt)),
            "offset_error": float(np.linalg.norm(o - truth.offset)),
            "matrix_error": float(np.max(np.abs(w - truth.matrix))),
        })
        err = np.abs(np.asarray(theta, float) - self.truth_theta())
        out.update({"param_matrix_error": float(err[:9].max()), "param_offset_error": float(err[9:].max())})
        return out

    # -- derivatives (analytic; see magexp.core.bounds) ---------------------------------------------
    def _dr_db(self, b: np.ndarray) -> np.ndarray | None:
        """``D_i = ∂r_i/∂b_i`` of the residuals at the calibrated readings ``b`` (N, 3), shape
        ``(N, m, 3)``; None (the default) when a problem has no analytic form."""
        return None

    def jacobians(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """Analytic ``(J, G)`` of :meth:`residuals` ``r_i(b_i)``, ``b_i = W (x_i - o)``, or None
        (no :meth:`_dr_db`, or one not defined beside the class's :meth:`residuals`).

        With ``D_i = ∂r_i/∂b_i`` (:meth:`_dr_db`) and ``G_i = D_i W`` (chain rule):

        .. math:: \\frac{∂r_i}{∂x_i} = G_i,\\quad \\frac{∂r_i}{∂o} = -G_i,\\quad
                  \\frac{∂r_i}{∂W_{jk}} = D_{i,\\cdot j}\\,(x_i - o)_k,\\quad
                  \\frac{∂r_i}{∂S_{jk}} = -G_{i,\\cdot j}\\,b_{i,k}

        (the last for the forward form ``W = S^{-1}``: ``dW = -W\\,dS\\,W``).
        ``J = ∂r/∂θ`` has shape ``(N m, 12)`` (rows as :meth:`residuals`; a transposed view of
        ``12`` contiguous rows), ``G`` ``(N, m, 3)``. Vectorised: one product per parameter
        block, no loop over readings.

        Parameters
        ----------
        theta : ndarray, shape (12,)
            The parameter vector the derivatives are taken at.

        Returns
        -------
        tuple of ndarray or None
            ``(J, G)``, or None without an analytic form.
        """
        if defining_class(self, "_dr_db") is not defining_class(self, "residuals"):
            return None  # residuals changed by a subclass (or none here): no analytic form
        w, o = self.unpack(theta)
        w, o = w[0], o[0]
        d = self.dataset.readings - o
        b = d @ w.T
        dr_db = self._dr_db(b)
        if dr_db is None:
            return None
        n, m = dr_db.shape[:2]
        g = (dr_db.reshape(n * m, 3) @ w).reshape(n, m, 3)  # one (N m x 3) @ (3 x 3) product
        left, right = (-g, b) if self.parameterisation == "forward" else (dr_db, d)
        rows = np.empty((12, n, m))  # row 3 j + k: left[:, :, j] * right[:, k]
        np.multiply(np.moveaxis(left, 2, 0)[:, None], np.ascontiguousarray(right.T)[None, :, :, None],
                    out=rows[:9].reshape(3, 3, n, m))
        np.negative(np.moveaxis(g, 2, 0), out=rows[9:])
        return rows.reshape(12, n * m).T, g

    # -- what the data can identify (see magexp.core.bounds) ----------------------------------------
    def invariants(self, theta: np.ndarray) -> np.ndarray:
        """The identifiable functions of ``theta``: here every parameter, as ``[vec(W), o]``.

        Parameters
        ----------
        theta : ndarray, shape (12,)
            The point whose invariants are taken.

        Returns
        -------
        ndarray, shape (12,)
            ``[vec(W), o]``.
        """
        w, o = self.unpack(theta)
        return np.concatenate([w[0].ravel(), o[0]])

    def invariant_bounds(self, theta: np.ndarray, cov: np.ndarray) -> dict:
        """Expected error sizes from the CRB covariance of :meth:`invariants`.

        Parameters
        ----------
        theta : ndarray, shape (12,)
            The parameter vector the covariance is taken at.
        cov : ndarray, shape (k, k)
            The Cramér-Rao covariance of :meth:`invariants` (:mod:`magexp.core.bounds`).

        Returns
        -------
        dict
            ``offset_bound`` (root of the offset block's trace) and ``matrix_bound`` (largest standard
            deviation of a matrix entry).
        """
        return {"offset_bound": float(np.sqrt(np.trace(cov[-3:, -3:]))),
                "matrix_bound": float(np.sqrt(np.max(np.diag(cov)[:-3])))}

    def fg(self, theta: np.ndarray) -> float:
        """Yuan 2018's ``F_g`` (eq 8): ``sum_i ||C_i H_i - W (r_i - o)||`` with the dataset's attitudes.

        Parameters
        ----------
        theta : ndarray, shape (12,)
            Any fit's estimate (``fg`` is reported whatever the objective).

        Returns
        -------
        float
            ``F_g`` at ``theta``.
        """
        return float(np.linalg.norm(reference_vectors(self.dataset) - self.calibrate(theta), axis=1).sum())
