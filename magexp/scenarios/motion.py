"""Rotation trajectories, a simulated gyro and strapdown attitude integration (Yuan 2018, sec 3).

A trajectory is a sequence of turns about body axes at a constant rate, sampled
every ``dt`` seconds. The body turns with the angular rate ``ω`` (body frame);
the body-to-navigation rotation follows ``Ṙ = R [ω]×`` and is propagated with
the exact exponential map of each step (the rate is constant within a step)

.. math:: R_{k+1} = R_k \\exp([\\omega_k]_\\times\\,\\Delta t)

(Rodrigues' formula). The attitude used by the magnetometer model, nav -> body,
is ``C_k = R_k^T``. A simulated gyro reads ``ω_m = ω + d + n`` with a constant
drift ``d`` (°/h, along ``drift_axis``) and white noise ``n`` (°/s per sample);
integrating ``ω_m`` from the known start gives the gyro attitude the vector
objective uses.

The paper's four rotation modes (Yuan 2018, sec 3.2) are named presets
(:data:`MODES`); mode 3 turns "incompletely" about X and Y, and since the arc is
not stated it is the config value ``partial_arc_deg`` (default 180°).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, List, Optional

import numpy as np

from magexp.core.limits import refuse_over
from magexp.errors import MagexpError, check, check_nonnegative, check_positive_int

AXES = {"x": 0, "y": 1, "z": 2}
FULL = 360.0
PARTIAL = "partial"  # placeholder for ``partial_arc_deg`` in a preset

#: The rotation modes of Yuan 2018, sec 3.2 (and 3.1: ``xyz``), as (axis, arc in degrees).
MODES: dict[str, list[tuple[str, float | str]]] = {
    "mode1": [("x", FULL), ("y", FULL), ("z", FULL)],  # three full turns (also Table 2)
    "mode2": [("x", FULL), ("y", FULL)],  # two full turns
    "mode3": [("x", PARTIAL), ("y", PARTIAL)],  # two incomplete turns
    "mode4": [("z", FULL)],  # one full turn about Z only (readings in one plane)
}


def segments_of(mode: str | None, segments, partial_arc_deg: float) -> list[tuple[str, float]]:
    """The list of ``(axis, arc_deg)`` of a preset ``mode`` or of explicit ``segments``.

    Yuan 2018's rotation modes (sec 3.2, :data:`MODES`).
    """
    if segments:
        out = [(str(s["axis"]).lower(), float(s["arc_deg"])) for s in segments]
    elif mode in MODES:
        out = [(ax, partial_arc_deg if arc == PARTIAL else arc) for ax, arc in MODES[mode]]
    else:
        raise MagexpError(f"rotation.mode={mode!r} is not allowed: choose one of {', '.join(MODES)} "
                          "(or give rotation.segments)")
    for ax, arc in out:
        check(ax in AXES, f"rotation axis={ax!r} is not allowed: choose x, y or z")
        check(np.isfinite(arc) and arc > 0, f"rotation arc_deg={arc!r} is not allowed: it must be > 0")
    return out


@dataclass
class RotationConf:
    """Schema of a Yuan scenario's ``rotation:`` node (the arguments of :class:`Trajectory`)."""

    mode: Optional[str] = "mode1"
    segments: Optional[List[Any]] = None
    partial_arc_deg: float = 180.0
    rate_deg_s: float = 36.0
    sample_period: float = 0.01


class Trajectory:
    """Turns about body axes in sequence, each at ``rate_deg_s``, sampled every ``sample_period`` s.

    Parameters
    ----------
    mode : str or None
        A preset of :data:`MODES` (``mode1``..``mode4``), or None with ``segments``.
    segments : list of dict, optional
        Explicit ``[{axis: x, arc_deg: 360}, ...]`` (overrides ``mode``).
    partial_arc_deg : float
        The arc of an incomplete turn (mode 3; not stated in the paper).
    rate_deg_s : float
        Turn rate; 36 °/s makes a full turn 1000 samples at 0.01 s, so three turns are the paper's 3000 samples.
    sample_period : float
        Seconds (0.01 in the paper's simulations, 1/205 for the ADIS16488).
    """

    def __init__(self, *, mode: str | None = "mode1", segments=None, partial_arc_deg: float = 180.0,
                 rate_deg_s: float = 36.0, sample_period: float = 0.01):
        arc = check_nonnegative(partial_arc_deg, "scenario.rotation.partial_arc_deg")
        check(arc > 0, f"scenario.rotation.partial_arc_deg={partial_arc_deg!r} is not allowed: it must be > 0")
        self.segments = segments_of(mode, segments, arc)
        self.rate = check_nonnegative(rate_deg_s, "scenario.rotation.rate_deg_s")
        self.dt = check_nonnegative(sample_period, "scenario.rotation.sample_period")
        check(self.rate > 0, f"scenario.rotation.rate_deg_s={rate_deg_s!r} is not allowed: it must be > 0")
        check(self.dt > 0, f"scenario.rotation.sample_period={sample_period!r} is not allowed: it must be > 0")
        refuse_over(self.samples(), "readings", f"scenario.rotation.sample_period={sample_period!r}",
                    "its turns at this rate and period are samples")  # counted before any array is made

    def samples(self) -> float:
        """The number of steps of :meth:`rates`, counted without making them."""
        return sum(max(round(arc / (self.rate * self.dt)), 1) for _, arc in self.segments)

    def rates(self) -> np.ndarray:
        """True body rates of every step."""
        parts = []
        for ax, arc in self.segments:
            n = max(int(round(arc / (self.rate * self.dt))), 1)
            w = np.zeros((n, 3))
            w[:, AXES[ax]] = np.deg2rad(arc) / (n * self.dt)  # the arc is exact
            parts.append(w)
        return np.concatenate(parts)

    def duration(self) -> float:
        """The trajectory's length in time."""
        return len(self.rates()) * self.dt


#: the widest full-scale range of a MEMS rate gyroscope (°/s; the ICM-42686-P's ±4000 °/s, twice the usual
#: ±2000 °/s): a drift or a noise level beyond it is no gyroscope's, the bound of :class:`Gyro`'s values
GYRO_RANGE_DEG_S = 4000.0


@dataclass
class GyroConf:
    """Schema of a Yuan scenario's ``gyro:`` node (the arguments of :class:`Gyro`)."""

    drift_deg_h: float = 6.25
    drift_axis: List[float] = field(default_factory=lambda: [1.0, 1.0, 1.0])
    noise_deg_s: float = 0.0


class Gyro:
    """A rate gyro: true rate + constant drift + white noise.

    Parameters
    ----------
    drift_deg_h : float
        Magnitude of the constant drift (°/h), along ``drift_axis``.
    drift_axis : sequence of float
        Direction of the drift (normalised; default equal on the three axes).
    noise_deg_s : float
        Standard deviation of the white noise of each sample (°/s).
    """

    def __init__(self, *, drift_deg_h: float = 6.25, drift_axis=(1.0, 1.0, 1.0), noise_deg_s: float = 0.0):
        self.drift_deg_h = check_nonnegative(drift_deg_h, "scenario.gyro.drift_deg_h")
        self.noise_deg_s = check_nonnegative(noise_deg_s, "scenario.gyro.noise_deg_s")
        for key, value, limit in (("drift_deg_h", self.drift_deg_h, GYRO_RANGE_DEG_S * 3600),
                                  ("noise_deg_s", self.noise_deg_s, GYRO_RANGE_DEG_S)):
            check(value <= limit, f"scenario.gyro.{key}={value:g} is not allowed: it must be <= {limit:g} (a rate "
                                  f"beyond a gyroscope's widest full-scale range, {GYRO_RANGE_DEG_S:g} deg/s)")
        axis = np.asarray(drift_axis, float)
        check(axis.shape == (3,) and np.all(np.isfinite(axis)) and np.linalg.norm(axis) > 0,
              f"gyro.drift_axis={drift_axis!r} is not allowed: it must be 3 finite numbers, not all 0")
        self.drift = np.deg2rad(self.drift_deg_h / 3600.0) * axis / np.linalg.norm(axis)  # rad/s

    def measure(self, rates: np.ndarray, *, rng: np.random.Generator) -> np.ndarray:
        """Gyro output (rad/s) for true ``rates`` ``(K, 3)``.

        Yuan 2018's gyro ``ω_m = ω + d + n`` (module docstring).
        """
        noise = np.deg2rad(self.noise_deg_s) * rng.standard_normal(rates.shape) if self.noise_deg_s > 0 else 0.0
        return rates + self.drift + noise


def even_subsample(n_total: int, n: int) -> np.ndarray:
    """``n`` evenly spaced indices of ``0..n_total-1`` (first and last included)."""
    n = check_positive_int(n, "scenario.n_readings")
    check(n <= n_total, f"scenario.n_readings={n} is not allowed: the trajectory has only {n_total} samples")
    return np.round(np.linspace(0, n_total - 1, n)).astype(int)
