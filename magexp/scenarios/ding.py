"""Ding 2024's simulation: a fluxgate with scale, non-orthogonality, soft and hard iron.

Model (Ding 2024, eqs 1-8)::

    Br = M B + I,   M = K C (E + S),   I = K C Bh + b

with ``K = diag(k)``, ``C(phi, theta, psi)`` the non-orthogonality matrix, ``S``
the soft-iron matrix, ``Bh`` the hard-iron field and ``b`` the sensor bias.
The calibration (eq 9) is ``B = M^-1 (Br - I)``.
"""

from __future__ import annotations

from dataclasses import dataclass, field as _field
from typing import List

import numpy as np
from omegaconf import MISSING

from magexp.core.dataset import Dataset, Truth
from magexp.errors import MagexpError, check, check_positive_int
from magexp.core.geometry import field_ned, random_rotations
from magexp.scenarios.noise import Noise
from magexp.scenarios.search import SearchBox, SimulationConf


def nonorthogonality(phi_deg: float, theta_deg: float, psi_deg: float) -> np.ndarray:
    """Ding's non-orthogonality matrix ``C`` for angles (phi, theta, psi) in degrees.

    .. math:: C = \\begin{bmatrix}\\cos\\theta\\cos\\varphi & \\sin\\theta\\cos\\varphi & \\sin\\varphi\\\\
              0 & \\cos\\psi & \\sin\\psi\\\\ 0 & 0 & 1\\end{bmatrix}

    (Ding 2024, the ``C`` of eqs 1-8.)
    """
    ph, th, ps = np.deg2rad([phi_deg, theta_deg, psi_deg])
    return np.array(
        [
            [np.cos(th) * np.cos(ph), np.sin(th) * np.cos(ph), np.sin(ph)],
            [0.0, np.cos(ps), np.sin(ps)],
            [0.0, 0.0, 1.0],
        ]
    )


def _vector(value, name: str, shape) -> np.ndarray:
    """``value`` as finite floats of ``shape``, else one line naming ``name``."""
    arr = np.asarray(value, dtype=float)
    if arr.shape != shape or not np.all(np.isfinite(arr)):
        raise MagexpError(f"{name}={value!r} is not allowed: it must be {shape} finite numbers")
    return arr


def error_model(*, scale, nonorthogonality_deg, soft_iron, hard_iron, bias) -> tuple[np.ndarray, np.ndarray]:
    """``(M, I)`` from Ding's physical error parameters (eqs 1-8).

    Ding 2024's error model ``Br = M B + I`` with ``M = K C (E + S)`` and ``I = K C Bh + b``.
    """
    k = _vector(scale, "errors.scale", (3,))
    c = nonorthogonality(*_vector(nonorthogonality_deg, "errors.nonorthogonality_deg", (3,)))
    s = _vector(soft_iron, "errors.soft_iron", (3, 3))
    kc = np.diag(k) @ c
    m = kc @ (np.eye(3) + s)
    check(np.all(k != 0), f"errors.scale={list(map(float, k))!r} is not allowed: each axis's scale must be non-zero "
          "(a zero scale loses that axis)")
    check(abs(np.linalg.det(m)) > 1e-9 * max(np.abs(m).max(), 1e-300) ** 3,
          "errors.nonorthogonality_deg and errors.soft_iron are not allowed together: they make the error matrix "
          "singular (an axis lost); keep each angle below 90 degrees and I + soft_iron invertible")
    i = kc @ _vector(hard_iron, "errors.hard_iron", (3,)) + _vector(bias, "errors.bias", (3,))
    return m, i


@dataclass
class DingFieldConf:
    """Schema of Ding's ``field:`` node."""

    total: float = MISSING        # nT
    declination: float = MISSING  # deg
    inclination: float = MISSING  # deg


@dataclass
class DingErrorsConf:
    """Schema of Ding's ``errors:`` node (the arguments of :func:`error_model`)."""

    scale: List[float] = MISSING
    nonorthogonality_deg: List[float] = MISSING
    soft_iron: List[List[float]] = MISSING
    hard_iron: List[float] = MISSING
    bias: List[float] = MISSING


@dataclass
class DingScenarioConf(SimulationConf):
    """Schema of a :class:`DingScenario` config."""

    _target_: str = "magexp.scenarios.ding.DingScenario"
    field: DingFieldConf = _field(default_factory=DingFieldConf)
    errors: DingErrorsConf = _field(default_factory=DingErrorsConf)
    noise_kind: str = "uniform"
    objective: str = "scalar"


class DingScenario:
    """Random 3-D rotations of a sensor with Ding's error model (``conf/scenario/ding2024_*.yaml``).

    Parameters
    ----------
    name : str
        The config's name (``ding2024_exp1``...).
    field : dict
        ``{total, declination, inclination}`` in nT and degrees.
    errors : dict
        ``{scale, nonorthogonality_deg, soft_iron, hard_iron, bias}`` (Ding 2024 Tables 1-2).
    noise : float
        Maximum amplitude ``A`` (nT) of the per-axis noise ``A (U - 0.5)``.
    n_readings : int
        Number of random attitudes.
    search : dict
        The search box of the calibration parameters (:class:`~magexp.scenarios.search.SearchBox`).
    noise_kind : str
        ``uniform`` (:class:`~magexp.scenarios.noise.Noise`) or ``gaussian``.
    objective : str
        The problem used by default.
    """

    Config = DingScenarioConf

    def __init__(self, *, name: str, field: dict, errors: dict, noise: float, n_readings: int,
                 search: dict, noise_kind: str = "uniform", objective: str = "scalar"):
        self.name = name
        self.field = field_ned(field["total"], field["declination"], field["inclination"])
        self.m, self.i = error_model(**errors)
        self.noise = Noise(noise, noise_kind)
        self.n_readings = check_positive_int(n_readings, "scenario.n_readings")
        self.search = SearchBox.from_config(search)
        self.objective = objective

    def generate(self, *, rng: np.random.Generator) -> Dataset:
        """Simulate ``n_readings`` readings at uniformly random attitudes."""
        r = random_rotations(self.n_readings, rng=rng)  # nav -> body
        body = r @ self.field
        readings = body @ self.m.T + self.i + self.noise.sample(body.shape, rng=rng)
        total = float(np.linalg.norm(self.field))
        return Dataset(
            readings=readings,
            reference_norm=np.full(self.n_readings, total),
            field_nav=np.broadcast_to(self.field, body.shape).copy(),
            attitude=r,
            attitude_true=r,
            field_body_true=body,
            truth=Truth(matrix=np.linalg.inv(self.m), offset=self.i.copy()),
            noise_std=self.noise.std,
            noise_kind=self.noise.kind,
            unit="nT",
            meta={"scenario": self.name},
        )
