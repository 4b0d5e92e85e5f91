"""The search box of a calibration's scalar fit: centred on the closed-form ellipsoid fit of the same readings.

``magexp calibrate`` fits ``|W (r - o)| = B`` by an iterative estimator (the swarms ``pso``, ``ipso``,
``rdpso``, the black-box ``cmaes`` and ``de``) inside a box of ``[vec(W) (row-major, 9), o (3)]``
(:func:`calibration_box`). The box is derived so that it holds the optimum:

* its centre is the closed-form ellipsoid fit of the readings at the fit's radius ``B`` (the mean reference
  total): the symmetric positive-definite ``W_e`` and the centre ``o_e`` (Gander, Golub & Strebel 1994;
  :func:`magexp.core.ellipsoid.quadric_calibration`), the symmetric member of the scalar objective's
  orbit ``{Q W_e}`` (``|Q W (r - o)|`` is the same for every orthogonal ``Q``), which is also the form
  :func:`magexp.core.identifiability.canonical` reports;
* every matrix entry lies within :data:`MATRIX_MARGIN` times ``λ_max(W_e)`` of ``W_e``'s, and every offset
  within :data:`OFFSET_MARGIN` times the ellipsoid's shortest semi-axis ``a_min = B / λ_max(W_e)`` of
  ``o_e``'s:

  .. math:: |W_{ij} - W_{e,ij}| \\le m_W\\,\\lambda_{max},\\qquad |o_k - o_{e,k}| \\le m_o\\,a_{min}.

Both widths follow the fitted ellipsoid, in the readings' own unit and the reference's: a sensor whose
offset lies far outside the readings' centre, a soft-iron anisotropy of 4, raw counts calibrated to nT
all keep the optimum inside, where the box of the readings' range
(:func:`magexp.scenarios.search.search_box`, kept for the papers' scenarios) clips it: its diagonal
``[0.5 s, 1.5 s]`` excluded the QMC5883L log's ``W_22 = 1.67 s`` (anisotropy 2.25). The offset's width is
bounded for a second reason: the scalar objective has a valley of false minima with the offset far from
the readings and ``W`` flattening the cloud along that direction (every magnitude then nearly ``B``), and an
offset box as wide as the readings' range (up to 2.3 radii from the centre on the FXOS8700 recording) let
the swarms end there, on the offset's faces, on the held-out regions' fits. The matrix's width is bounded
for a like reason: the faces cut the orbit ``{Q W_e}`` of equal cost, and a rotated optimum pressed onto
them is a false minimum. With ``W`` within 0.5 ``λ_max`` CMA-ES ended so on a held-out region of the
QMC5883L log (four entries of ``W`` on faces, objective 78.54 against the optimum's 77.35); within 0.25
``λ_max`` (rotations up to about 14 degrees inside) it did not. On the shared recordings the ellipsoid
calibrates, and on each of their held-out regions' fits, the objective's least-squares optimum lies within
a sixth of these margins of the algebraic fit (tests/test_calibrate_swarms.py checks it lies in the box's
inner half).

When the closed form fails (the readings do not lie on an ellipsoid) or gives no finite box around its
centre, the box is the readings' range (:func:`~magexp.scenarios.search.search_box`) and
:attr:`CalibrationBox.how` says so in one line, which the printed report shows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from magexp.core.ellipsoid import LINEAR_TWICE, normalise, quadratic_features, quadric_calibration
from magexp.scenarios.search import search_box

#: half-width of every matrix entry, relative to the largest eigenvalue of the closed-form ``W`` (module docstring)
MATRIX_MARGIN = 0.25
#: half-width of every offset entry, relative to the closed-form ellipsoid's shortest semi-axis (module docstring)
OFFSET_MARGIN = 0.5


@dataclass(frozen=True)
class CalibrationBox:
    """Per-entry bounds of ``[vec(W) (row-major, 9), o (3)]`` and how they were derived."""

    lower: np.ndarray
    upper: np.ndarray
    how: str
    centred: bool = True

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The box as bound vectors (copies)."""
        return self.lower.copy(), self.upper.copy()

    def contains(self, x: np.ndarray) -> bool:
        """Whether ``x`` lies inside the box (faces included)."""
        return bool(np.all((self.lower <= x) & (x <= self.upper)))

    def record(self) -> dict:
        """The box for ``calibration.json``."""
        return {"lower": self.lower.tolist(), "upper": self.upper.tolist(), "how": self.how}


def closed_form(readings: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray] | None:
    """``(W, o)`` of the algebraic ellipsoid fit (:func:`magexp.core.ellipsoid.fit_ellipsoid`'s quadric), its
    null vector from the 10 x 10 scatter of the normalised features (5 ms on 22 744 readings, 90 ms by an
    SVD of the whole design); None when it is not an ellipsoid."""
    c, s, u = normalise(readings)
    design = quadratic_features(u) * LINEAR_TWICE
    p = np.linalg.eigh(design.T @ design)[1][:, 0]
    return quadric_calibration(p, c, s, radius)


def _range_box(readings: np.ndarray, radius: float, why: str) -> CalibrationBox:
    """The readings' range box (:func:`~magexp.scenarios.search.search_box`, ``aligned``) with ``why`` it is used."""
    lower, upper = search_box(readings, radius).bounds()
    return CalibrationBox(lower, upper, f"{why}: the box is the readings' range, which may not hold the optimum",
                          centred=False)


def calibration_box(readings: np.ndarray, radius: float) -> CalibrationBox:
    """The search box of a scalar calibration fit (module docstring): the closed-form ellipsoid fit of
    ``readings`` at ``radius``, ``W`` within :data:`MATRIX_MARGIN` ``λ_max`` and ``o`` within
    :data:`OFFSET_MARGIN` ``a_min`` of it; the readings' range where that fit fails."""
    fitted = closed_form(readings, radius)
    if fitted is None:
        return _range_box(readings, radius, "the closed-form ellipsoid fit failed (the readings do not lie on an "
                                            "ellipsoid)")
    w, o = fitted
    largest = float(np.linalg.eigvalsh(w)[-1])
    centre = np.concatenate([w.ravel(), o])
    half = np.concatenate([np.full(9, MATRIX_MARGIN * largest), np.full(3, OFFSET_MARGIN * radius / largest)])
    box = CalibrationBox(centre - half, centre + half,
                         f"centred on the closed-form ellipsoid fit: W within {MATRIX_MARGIN:g} x its largest "
                         f"eigenvalue, the offset within {OFFSET_MARGIN:g} x its shortest semi-axis")
    if not (np.all(np.isfinite(half)) and np.all(half > 0) and box.contains(centre)):
        return _range_box(readings, radius, "the closed-form ellipsoid fit gave no finite box around it")
    return box
