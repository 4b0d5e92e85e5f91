"""The least-squares statistics of a linear ship model on recorded data (Yan & Zhou 2022, eq 1).

For a single deterministic run on recorded data a summary row's interval is the least-squares
estimate ± t(0.975, dof) standard errors (``interval: ls``, :func:`least_squares_interval`), and a
published estimate is held to the fit by an F-test (``mode: ftest``, :func:`f_test`); both read the
linear design the run stored (``design``: ``C^T C``, the coefficients, the residual sums of squares).
"""

from __future__ import annotations

import numpy as np
from scipy.special import fdtrc, stdtrit

from magexp.artifacts.plan import ArtifactRuns
from magexp.artifacts.tables import first_output
from magexp.errors import MagexpError


def least_squares_interval(runs: ArtifactRuns, ci: int, level: float = 0.95) -> dict:
    """``{parameter: (estimate, half width)}`` of the least-squares fit of a linear ship model
    (Yan & Zhou 2022, eq 1: per axis ``B_i = [A_i Be, 1] [K_i, Bp_i]^T``, 4 parameters).

    Per axis ``s^2 = RSS / (N - 4)`` and ``Cov = s^2 (C^T C)^{-1}``; the half width is
    ``t(1 - (1 - level)/2, N - 4)`` standard errors (12 readings: 8 degrees of freedom), the quantile
    from ``scipy.special.stdtrit`` (what ``scipy.stats.t.ppf`` evaluates, without importing
    ``scipy.stats``).
    """
    gram, coef, rss, n, names = _design_of(runs, ci)  # coef (4, 3): column a = axis a's [K_a1, K_a2, K_a3, Bp_a]
    p = gram.shape[0]
    dof = n - p
    cov = np.linalg.inv(gram)
    se = np.sqrt(np.outer(np.diag(cov), rss / dof))  # (4, 3)
    t = stdtrit(dof, 0.5 + level / 2)
    out = {}
    for a in range(3):
        for j in range(3):
            out[names[3 * a + j]] = (float(coef[j, a]), float(t * se[j, a]))
        out[names[9 + a]] = (float(coef[3, a]), float(t * se[3, a]))
    return out


def f_test(runs: ArtifactRuns, ci: int, theta: np.ndarray) -> list[dict]:
    """Per axis, the F-test of the hypothesis that ``theta`` (e.g. the paper's K, Bp) is the true
    parameter of the linear model: ``F = (b - b_ls)^T C^T C (b - b_ls) / p / s^2 ~ F(p, N - p)``; the
    p-value from ``scipy.special.fdtrc`` (what ``scipy.stats.f.sf`` evaluates).
    """
    gram, coef, rss, n, _ = _design_of(runs, ci)
    p = gram.shape[0]
    k, bp = np.asarray(theta[:9], float).reshape(3, 3), np.asarray(theta[9:], float)
    out = []
    for a in range(3):
        d = np.append(k[a], bp[a]) - coef[:, a]
        f = float(d @ gram @ d / p / (rss[a] / (n - p)))
        out.append({"axis": a + 1, "F": f, "dof": (p, n - p), "p_value": float(fdtrc(p, n - p, f))})
    return out


def _design_of(runs: ArtifactRuns, ci: int) -> tuple:
    """``(C^T C, least-squares coefficients, residual sums of squares per axis, N, parameter names)`` of
    the linear problem of cell ``ci``'s first seed, as its run stored them (``design``); a problem
    without a linear design cannot give a least-squares interval (one line)."""
    out = first_output(runs, ci)
    design = getattr(out, "design", None)
    if not design:
        raise MagexpError(f"{runs.spec.name}: cell {ci} has no linear design (interval: ls and mode: ftest need one)")
    return (np.asarray(design["gram"], float), np.asarray(design["coef"], float), np.asarray(design["rss"], float),
            int(design["n"]), list(out.parameter_names))
