"""Yan & Zhou 2022: a ship's magnetization seen by a mast-mounted three-axis sensor.

Model (Yan & Zhou 2022, eqs 1-2)

.. math:: \\mathbf B = \\mathbf K\\,\\mathbf A\\,\\mathbf B_e + \\mathbf B_p,\\qquad
          \\mathbf A = \\mathbf R_y(\\varphi)\\,\\mathbf R_x(\\theta)\\,\\mathbf R_z(\\psi)

with ``K`` the induced-magnetization matrix, ``Bp`` the permanent magnetization (nT),
``Be`` the geomagnetic field in the geographic frame, and ``A`` exactly as eq 2 prints it:

.. math:: \\mathbf R_y = \\begin{bmatrix}\\cos\\varphi&0&\\sin\\varphi\\\\0&1&0\\\\-\\sin\\varphi&0&\\cos\\varphi\\end{bmatrix},\\
          \\mathbf R_x = \\begin{bmatrix}1&0&0\\\\0&\\cos\\theta&\\sin\\theta\\\\0&-\\sin\\theta&\\cos\\theta\\end{bmatrix},\\
          \\mathbf R_z = \\begin{bmatrix}\\cos\\psi&\\sin\\psi&0\\\\-\\sin\\psi&\\cos\\psi&0\\\\0&0&1\\end{bmatrix}

(``psi`` heading, ``theta`` roll, ``phi`` trim: the columns of Table 1). Note the mixed
signs: ``R_y`` is an active rotation, ``R_x`` and ``R_z`` passive ones.

Two scenarios: :class:`ShipSimulation` (sec 2.2) and :class:`ShipRecording` (sec 3, a
``magexp-recording v1`` file such as ``data/yan2022_mockup.csv``, Table 1).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import List, Optional

import numpy as np
from omegaconf import MISSING

from magexp.core.dataset import Dataset, Truth
from magexp.errors import MagexpError, check_nonnegative, check_positive_int
from magexp.core.geometry import ship_attitude
from magexp.core.recordings import load_recording
from magexp.scenarios.noise import Noise
from magexp.scenarios.search import ScenarioConf, SearchBox, SimulationConf


def _array(value, name: str, shape) -> np.ndarray:
    """``value`` as finite floats of ``shape``, else one line naming ``name``."""
    arr = np.asarray(value, dtype=float)
    if arr.shape != shape or not np.all(np.isfinite(arr)):
        raise MagexpError(f"{name}={value!r} is not allowed: it must be {shape} finite numbers")
    return arr


def _range(value, name: str) -> tuple[float, float]:
    """``value`` as ``(low, high)`` with low <= high (:func:`_array`)."""
    lo, hi = _array(value, name, (2,))
    if lo > hi:
        raise MagexpError(f"{name}={value!r} is not allowed: it must be [low, high] with low <= high")
    return float(lo), float(hi)


def bounded_noise(bound: float, kind: str, name: str) -> Noise:
    """Noise of at most ``bound``: ``uniform`` on ``[-bound, bound]`` (std ``bound/sqrt(3)``);
    ``gaussian`` with standard deviation ``bound`` (not bounded; for comparison).

    Yan & Zhou 2022's errors "at most" 100 nT and 0.05° (sec 2.2).
    """
    bound = check_nonnegative(bound, name)
    return Noise(2.0 * bound if kind == "uniform" else bound, kind, name)


def ship_dataset(readings, angles, field, *, angles_true=None, truth=None, noise=None, meta=None) -> Dataset:
    """A :class:`Dataset` of the ship model: ``attitude`` from the measured angles (N, 3)
    ``[heading, roll, trim]``, ``field_nav`` the ambient field per reading.

    The attitude ``A`` is Yan & Zhou 2022's eq 2 (:func:`magexp.core.geometry.ship_attitude`).
    """
    angles = np.asarray(angles, float)
    angles_true = angles if angles_true is None else np.asarray(angles_true, float)
    attitude_true = ship_attitude(*angles_true.T)
    n = len(readings)
    return Dataset(
        readings=np.asarray(readings, float),
        reference_norm=np.full(n, float(np.linalg.norm(field))),
        field_nav=np.broadcast_to(field, (n, 3)).copy(),
        attitude=ship_attitude(*angles.T),
        attitude_true=attitude_true,
        field_body_true=attitude_true @ field,
        truth=truth,
        noise_std=None if noise is None else noise.std,
        noise_kind=None if noise is None else noise.kind,
        unit="nT",
        meta=meta or {},
        extra={"angles": angles, "angles_true": angles_true, "field": np.asarray(field, float)},
    )


@dataclass
class ShipSimulationConf(SimulationConf):
    """Schema of a :class:`ShipSimulation` config."""

    _target_: str = "magexp.scenarios.ship.ShipSimulation"
    field: List[float] = MISSING
    K: List[List[float]] = MISSING
    Bp: List[float] = MISSING
    heading_deg: List[float] = MISSING
    roll_deg: List[float] = MISSING
    trim_deg: List[float] = MISSING
    angle_noise_deg: float = MISSING
    noise_kind: str = "uniform"


class ShipSimulation:
    """Yan & Zhou's simulation (sec 2.2): random attitudes, ``B = K A Be + Bp`` plus noise.

    Parameters
    ----------
    name : str
        The config's name (``yan2022_sim``).
    field : sequence of float
        ``Be`` (nT), geographic frame.
    K, Bp : array_like
        The true induced matrix (3x3) and permanent vector (nT).
    heading_deg, roll_deg, trim_deg : [low, high]
        Ranges of the uniformly drawn angles.
    n_readings : int
        Number of attitudes (12 in the paper).
    noise : float
        Bound (nT) of the error on each component of ``B`` ("at most 100 nT").
    angle_noise_deg : float
        Bound (degrees) of the error on each recorded angle ("at most 0.05°").
    search : dict
        The box of ``[vec(K), Bp]`` (for swarm estimators).
    noise_kind : str
        ``uniform`` (on ``[-bound, bound]``: "at most" reads as a bounded error) or ``gaussian`` (standard
        deviation = bound).
    """

    Config = ShipSimulationConf
    objective = "ship"

    def __init__(self, *, name: str, field, K, Bp, heading_deg, roll_deg, trim_deg, n_readings: int,
                 noise: float, angle_noise_deg: float, search: dict, noise_kind: str = "uniform"):
        self.name = name
        self.field = _array(field, "scenario.field", (3,))
        self.k = _array(K, "scenario.K", (3, 3))
        self.bp = _array(Bp, "scenario.Bp", (3,))
        self.ranges = np.deg2rad([_range(heading_deg, "scenario.heading_deg"), _range(roll_deg, "scenario.roll_deg"),
                                  _range(trim_deg, "scenario.trim_deg")])
        self.n_readings = check_positive_int(n_readings, "scenario.n_readings")
        self.noise = bounded_noise(noise, noise_kind, "scenario.noise")
        self.angle_noise = bounded_noise(np.deg2rad(check_nonnegative(angle_noise_deg, "scenario.angle_noise_deg")),
                                         noise_kind, "scenario.angle_noise_deg")
        self.search = SearchBox.from_config(search)

    def generate(self, *, rng: np.random.Generator) -> Dataset:
        """Draw ``n_readings`` attitudes, the exact readings, then the reading and angle errors.

        Yan & Zhou 2022's model ``B = K A Be + Bp`` (eqs 1-2).
        """
        lo, hi = self.ranges.T
        angles_true = lo + (hi - lo) * rng.random((self.n_readings, 3))
        exact = ship_attitude(*angles_true.T) @ self.field @ self.k.T + self.bp
        readings = exact + self.noise.sample(exact.shape, rng=rng)
        angles = angles_true + self.angle_noise.sample(angles_true.shape, rng=rng)
        truth = Truth(matrix=np.linalg.inv(self.k), offset=self.bp.copy(), extra={"K": self.k.copy()})
        return ship_dataset(readings, angles, self.field, angles_true=angles_true, truth=truth, noise=self.noise,
                            meta={"scenario": self.name})


@dataclass
class ShipRecordingConf(ScenarioConf):
    """Schema of a :class:`ShipRecording` config."""

    _target_: str = "magexp.scenarios.ship.ShipRecording"
    path: str = MISSING
    field: Optional[List[float]] = None


class ShipRecording:
    """A recorded ship dataset (Yan & Zhou's mock-up, Table 1, or a user's own file). The data are fixed:
    ``generate`` ignores ``rng``, and the truth is unknown.

    Parameters
    ----------
    name : str
        The config's name (``yan2022_mockup``).
    path : str
        A ``magexp-recording v1`` CSV (:mod:`magexp.core.recordings`), relative to ``data/``.
    search : dict
        As :class:`ShipSimulation`.
    field : sequence of float or None
        ``Be`` (nT); None to take the file's ``# field:`` line.
    """

    Config = ShipRecordingConf
    objective = "ship"

    def __init__(self, *, name: str, path: str, search: dict, field=None):
        self.name = name
        self.recording = load_recording(path)
        if self.recording.angles is None:
            raise MagexpError(f"{self.recording.path.name}: missing column heading, roll, trim: "
                              f"scenario {name!r} needs the ship attitude of every reading")
        if field is None and self.recording.field is None:
            raise MagexpError(f"scenario.field=None is not allowed for {path!r}: the file has no '# field:' line, "
                              "give scenario.field=[Be1,Be2,Be3]")
        self.field = self.recording.field if field is None else _array(field, "scenario.field", (3,))
        self.search = SearchBox.from_config(search)

    def generate(self, *, rng: np.random.Generator | None = None) -> Dataset:
        """The recording's dataset (Yan & Zhou 2022 Table 1, or a user's file)."""
        rec = self.recording
        return ship_dataset(rec.readings, rec.angles, self.field, meta={"scenario": self.name, **rec.meta})
