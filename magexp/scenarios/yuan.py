"""Yuan 2018's simulation: a magnetometer turned about its axes, with a drifting gyro.

Model (Yuan 2018, eq 1)

.. math:: \\mathbf B_{b,i} = S\\,C_i^b\\,\\mathbf H_i + \\mathbf b + \\boldsymbol\\varepsilon_i

with ``S`` a full 3x3 matrix, ``b`` the offset, ``ε`` white Gaussian noise of
standard deviation ``noise`` (mG) per axis. ``C_i^b`` is the true attitude
(nav -> body) along a :class:`~magexp.scenarios.motion.Trajectory`; the dataset
also carries the attitude obtained by integrating the simulated gyro from the
known start, which is what the vector objective (eq 8) may use. The calibration
is ``B̂ = S^-1 (B_b - b)`` (eq 3), i.e. ``W = S^-1``, ``o = b`` in magexp's form.

The field is Harbin's IGRF-12 vector ``H = [242.367, -46.225, -465.459]`` mG
(nav frame). ``field_scale = [start, end]`` makes its magnitude change linearly
along the run (sec 3.3, range not stated in the paper); ``H_i`` of every reading
is known to the objective through ``Dataset.field_nav``.
"""

from __future__ import annotations

from dataclasses import dataclass, field as _field
from typing import List

import numpy as np
from omegaconf import MISSING

from magexp.core.dataset import Dataset, Truth
from magexp.core.geometry import integrate_rates
from magexp.errors import MagexpError, check, check_nonnegative
from magexp.scenarios.motion import Gyro, GyroConf, RotationConf, Trajectory, even_subsample
from magexp.scenarios.noise import Noise
from magexp.scenarios.search import SearchBox, SimulationConf


def _array(value, name: str, shape) -> np.ndarray:
    """``value`` as finite floats of ``shape``, else one line naming ``name``."""
    arr = np.asarray(value, dtype=float)
    if arr.shape != shape or not np.all(np.isfinite(arr)):
        raise MagexpError(f"{name}={value!r} is not allowed: it must be {shape} finite numbers")
    return arr


@dataclass
class YuanScenarioConf(SimulationConf):
    """Schema of a :class:`YuanScenario` config."""

    _target_: str = "magexp.scenarios.yuan.YuanScenario"
    field: List[float] = MISSING
    field_scale: List[float] = _field(default_factory=lambda: [1.0, 1.0])
    S: List[List[float]] = MISSING
    b: List[float] = MISSING
    rotation: RotationConf = _field(default_factory=RotationConf)
    gyro: GyroConf = _field(default_factory=GyroConf)
    objective: str = "vector"


class YuanScenario:
    """Turns of a sensor with a full error matrix, and a drifting gyro.

    Parameters
    ----------
    name : str
        The config's name (``yuan2018_...``).
    field : sequence of float
        The navigation-frame field vector (mG).
    S, b : array_like
        The true error matrix and offset (mG).
    rotation : dict
        Keyword arguments of :class:`~magexp.scenarios.motion.Trajectory`.
    gyro : dict
        Keyword arguments of :class:`~magexp.scenarios.motion.Gyro`.
    noise : float
        Per-axis standard deviation of the Gaussian reading noise (mG).
    n_readings : int
        Readings used, evenly spaced over the run (30 in the paper).
    search : dict
        The search box of ``[vec(S), b]``.
    field_scale : [start, end]
        Factor on the field magnitude, linear over the run.
    objective : str
        The default problem; ``problem_options`` selects the forward parameterisation ``[vec(S), b]``.
    """

    Config = YuanScenarioConf
    problem_options = {"parameterisation": "forward"}

    def __init__(self, *, name: str, field, S, b, rotation: dict, gyro: dict, noise: float, n_readings: int,
                 search: dict, field_scale=(1.0, 1.0), objective: str = "vector"):
        self.name = name
        self.field = _array(field, "scenario.field", (3,))
        self.field_scale = _array(field_scale, "scenario.field_scale", (2,))
        check(np.all(self.field_scale > 0), f"scenario.field_scale={list(field_scale)!r} is not allowed: "
              "both factors must be > 0")
        self.s = _array(S, "scenario.S", (3, 3))
        check(abs(np.linalg.det(self.s)) > 1e-9, f"scenario.S={S!r} is not allowed: it must be invertible")
        self.b = _array(b, "scenario.b", (3,))
        self.trajectory = Trajectory(**rotation)
        self.gyro = Gyro(**gyro)
        self.noise = Noise(check_nonnegative(noise, "scenario.noise"), "gaussian")
        self.n_readings = n_readings
        self.search = SearchBox.from_config(search)
        self.objective = objective

    def generate(self, *, rng: np.random.Generator) -> Dataset:
        """Simulate the run and keep ``n_readings`` evenly spaced readings.

        Yuan 2018's model ``B_b = S C_i^b H_i + b + ε`` (eq 1) along the trajectory.
        """
        rates = self.trajectory.rates()
        dt = self.trajectory.dt
        true_bn = integrate_rates(rates, dt)[:-1]  # body -> nav at every sample
        gyro_bn = integrate_rates(self.gyro.measure(rates, rng=rng), dt)[:-1]
        keep = even_subsample(len(rates), self.n_readings)
        ramp = np.linspace(self.field_scale[0], self.field_scale[1], len(rates))[keep]
        field_nav = ramp[:, None] * self.field
        c_true = np.swapaxes(true_bn[keep], 1, 2)  # nav -> body
        c_gyro = np.swapaxes(gyro_bn[keep], 1, 2)
        body = np.einsum("nij,nj->ni", c_true, field_nav)
        readings = body @ self.s.T + self.b + self.noise.sample(body.shape, rng=rng)
        return Dataset(
            readings=readings,
            reference_norm=np.linalg.norm(field_nav, axis=1),
            field_nav=field_nav,
            attitude=c_gyro,
            attitude_true=c_true,
            field_body_true=body,
            truth=Truth(matrix=np.linalg.inv(self.s), offset=self.b.copy()),
            noise_std=self.noise.std,
            noise_kind=self.noise.kind,
            unit="mG",
            meta={"scenario": self.name, "duration_s": len(rates) * dt, "sample_index": keep},
        )
