"""The search box of the 12-parameter calibration problems.

A box derived from a recording (:func:`search_box`) scales the matrix entries by ``s``, the ratio of
the reference total to the radius ``R0`` of the sphere fitted to the readings
(:func:`magexp.core.ellipsoid.fit_sphere`).
It has one of two shapes (:data:`BOXES`):

* ``aligned``: diagonal in ``[0.5 s, 1.5 s]``, off-diagonal in ``[-0.5 s, 0.5 s]``, every offset
  within the range of the readings. Right when the objective leaves the orientation of ``W`` free
  (the scalar objective: ``|Q W (B - o)|`` is the same for every orthogonal ``Q``, and the orbit of
  the optimum holds its symmetric positive-definite member, whose diagonal is positive), or when the
  magnetometer's axes are known to match the reference's;
* ``signed``: Yuan 2018's matrix width (Table 1: ``S`` in ``[-3, 3]``), taken relative to the data:
  every matrix entry in ``[-m s, m s]`` (``m = matrix_bound``, 3); the offset as in ``aligned``
  (within the range of the readings: the box of every shape holds every offset the data allow), or,
  with ``offset_width`` set, within ``offset_width`` times ``R0`` of the closed-form sphere centre
  (one interval for the three axes; Yuan's own ``b`` in ``[-100, 100]`` mG of a 527 mG field is
  0.19: on the HMC5883L full sphere that narrow box leaves the swarms stranded on the faces of
  ``S``, 0 of 5 RDPSO seeds within 1.1x the best F_g, measured 2026-11-24). Needed when the objective fixes the orientation and the
  magnetometer's axes may point anywhere relative to the reference's (a gyro-aided fit: ``S`` holds
  the rotation, and any axis flip, between the magnetometer's and the gyroscope's axes): a scaled
  orthogonal matrix ``k Q`` has every entry in ``[-k, k]``, so the box holds every rotation and
  reflection with scale errors up to ``m``, and both members of the pair ``(S, h)``, ``(-S, -h)``
  that the gyro-aided objective cannot tell apart. The matrix part is centred on zero, not on an
  estimate: the sign and rotation of ``S`` are what the swarm must find.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import List

import numpy as np
from omegaconf import MISSING

from magexp.core.ellipsoid import fit_sphere
from magexp.errors import LARGEST, MagexpError


def _interval(value, name: str) -> tuple[float, float]:
    """``value`` as a finite ``(low, high)``, low < high, within :data:`LARGEST`; else one line naming ``search.<name>``."""
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        raise MagexpError(f"search.{name}={value!r} is not allowed: it must be [low, high]") from None
    if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
        raise MagexpError(f"search.{name}={value!r} is not allowed: it must be finite with low < high")
    if max(abs(lo), abs(hi)) > LARGEST:
        raise MagexpError(f"search.{name}={value!r} is not allowed: bounds must be of magnitude <= {LARGEST:g}")
    return lo, hi


@dataclass(frozen=True)
class SearchBox:
    """Bounds for ``[vec(matrix) (row-major, 9), offset (3)]``: ``diag`` and ``offdiag`` ``(low, high)`` of the
    diagonal and off-diagonal matrix entries, ``offset`` of the three offset entries (reading units)."""

    diag: tuple[float, float]
    offdiag: tuple[float, float]
    offset: tuple[float, float]

    @classmethod
    def from_config(cls, cfg) -> "SearchBox":
        """The box of a scenario's ``search:`` node (:class:`SearchConf`)."""
        if cfg is None:
            raise MagexpError("search=None is not allowed: the scenario must give search.diag, .offdiag, .offset")
        missing = [k for k in ("diag", "offdiag", "offset") if k not in cfg]
        if missing:
            raise MagexpError(f"search is missing {', '.join(missing)}: give [low, high] for diag, offdiag and offset")
        return cls(*(_interval(cfg[k], k) for k in ("diag", "offdiag", "offset")))

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The box as bound vectors."""
        eye = np.eye(3, dtype=bool).ravel()
        lo = np.where(eye, self.diag[0], self.offdiag[0])
        hi = np.where(eye, self.diag[1], self.offdiag[1])
        return (np.concatenate([lo, np.full(3, self.offset[0])]), np.concatenate([hi, np.full(3, self.offset[1])]))

    def record(self) -> dict:
        """The box for a calibration's JSON."""
        return {"diag": list(self.diag), "offdiag": list(self.offdiag), "offset": list(self.offset)}


@dataclass
class SearchConf:
    """Schema of a ``search:`` node (:class:`SearchBox`): ``[low, high]`` per kind of entry."""

    diag: List[float] = MISSING
    offdiag: List[float] = MISSING
    offset: List[float] = MISSING


@dataclass
class ScenarioConf:
    """Schema of what every simulated or modelled scenario config has: the class it builds, its name,
    its search box. A field without a default (``MISSING``) must be given by the config."""

    _target_: str = MISSING
    name: str = MISSING
    search: SearchConf = field(default_factory=SearchConf)


@dataclass
class SimulationConf(ScenarioConf):
    """Schema of a simulated scenario: its reading noise and number of readings."""

    noise: float = MISSING
    n_readings: int = MISSING


def centroid_radius(readings: np.ndarray) -> float:
    """Radius of the sphere fitted to ``readings`` (:func:`magexp.core.ellipsoid.fit_sphere`): unlike the
    mean distance from the centroid it stays right when the readings cover only part of the sphere.
    """
    return fit_sphere(readings)[1]


#: shapes of a box from the data (module docstring)
BOXES = ("aligned", "signed")


def search_box(readings: np.ndarray, reference: float, *, forward: bool = False, shape: str = "aligned",
               matrix_bound: float = 3.0, offset_width: float | None = None) -> SearchBox:
    """The parameter box of swarm estimators, derived from the data (module docstring).

    ``forward``: the matrix parameters are ``S = W^-1`` (the vector problem's parameterisation,
    which the ``ekf`` state uses), so their scale is ``1 / s``. ``shape``: ``aligned`` or ``signed``;
    ``matrix_bound`` (``m``) and ``offset_width`` (relative to ``R0``; None: the readings' range):
    the widths of ``signed``.
    """
    if shape not in BOXES:
        raise MagexpError(f"box={shape!r} is not allowed: choose one of {', '.join(BOXES)}")
    widths = [("matrix_bound", matrix_bound, 1.0, "[1, ")] + ([] if offset_width is None else [("offset_width", offset_width, 0.0, "(0, ")])
    for name, value, low, allowed in widths:
        ok = isinstance(value, (int, float)) and np.isfinite(value) and value <= LARGEST
        if not ok or value < low or (low == 0.0 and value == 0.0):
            raise MagexpError(f"{name}={value!r} is not allowed: it must be a number in {allowed}{LARGEST:g}]")
    centre, radius = fit_sphere(readings)
    s = reference / (radius or 1.0)
    s = 1.0 / s if forward else s
    lo, hi = float(readings.min()), float(readings.max())
    if hi <= lo:
        hi = lo + 1.0
    if shape == "signed":
        m = float(matrix_bound) * s
        if offset_width is not None:
            w = float(offset_width) * radius
            lo, hi = float(centre.min()) - w, float(centre.max()) + w
        return SearchBox(diag=(-m, m), offdiag=(-m, m), offset=(lo, hi))
    return SearchBox(diag=(0.5 * s, 1.5 * s), offdiag=(-0.5 * s, 0.5 * s), offset=(lo, hi))
