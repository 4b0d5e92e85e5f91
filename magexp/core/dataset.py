"""The dataset every estimator sees: readings plus what is known about them."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Truth:
    """The true calibration, when a scenario is simulated.

    ``matrix`` and ``offset`` are written in the calibration form
    ``B = matrix @ (reading - offset)`` (Ding's ``M^-1`` and ``I``; Yuan's
    ``S^-1`` and ``b``). ``extra`` holds model-specific truths (e.g. Yan's ``K``).
    """

    matrix: np.ndarray
    offset: np.ndarray
    extra: dict = field(default_factory=dict)


@dataclass
class Dataset:
    """Readings of one run and everything the scenario knows about them.

    Attributes
    ----------
    readings : (N, 3) raw magnetometer readings.
    reference_norm : (N,) reference total field per reading.
    field_nav : (N, 3) or None, field vector in the navigation frame per reading.
    attitude : (N, 3, 3) or None, the attitude the estimator may use (nav -> body),
        e.g. gyro-integrated; ``attitude_true`` is the exact one.
    field_body_true : (N, 3) or None, exact body-frame field (simulations only).
    truth : Truth or None.
    noise_std : per-axis standard deviation of the reading noise (None if unknown).
    noise_kind : ``"uniform"``, ``"gaussian"`` or ``None``.
    unit : unit of the readings.
    meta : free-form description (scenario name, parameters).
    """

    readings: np.ndarray
    reference_norm: np.ndarray
    field_nav: np.ndarray | None = None
    attitude: np.ndarray | None = None
    attitude_true: np.ndarray | None = None
    field_body_true: np.ndarray | None = None
    truth: Truth | None = None
    noise_std: float | None = None
    noise_kind: str | None = None
    unit: str = "nT"
    meta: dict = field(default_factory=dict)
    extra: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        """The number of readings."""
        return int(self.readings.shape[0])
