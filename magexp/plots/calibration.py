"""Before/after figure of a calibrated recording: the raw ellipsoid becoming a sphere."""

from __future__ import annotations

import numpy as np

from magexp.plots.style import plt

PAIRS = ((0, 1, "x", "y"), (0, 2, "x", "z"), (1, 2, "y", "z"))


def projections(axes, raw: np.ndarray, calibrated: np.ndarray, radius: float, unit: str) -> None:
    """Three plane projections: raw and calibrated readings, and the reference circle."""
    t = np.linspace(0, 2 * np.pi, 200)
    for ax, (i, j, a, b) in zip(axes, PAIRS):
        ax.scatter(raw[:, i], raw[:, j], s=4, color="0.6", label="raw")
        ax.scatter(calibrated[:, i], calibrated[:, j], s=4, color="C0", label="calibrated")
        ax.plot(radius * np.cos(t), radius * np.sin(t), "k--", lw=0.8, label="reference")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(f"{a} ({unit})")
        ax.set_ylabel(f"{b} ({unit})")
    axes[0].legend(loc="upper right", markerscale=2)


def magnitudes(ax_trace, ax_hist, raw: np.ndarray, calibrated: np.ndarray, reference: np.ndarray, unit: str) -> None:
    """Total field per reading, and its histogram, before and after."""
    before, after = np.linalg.norm(raw, axis=1), np.linalg.norm(calibrated, axis=1)
    ax_trace.plot(before, ".", ms=3, color="0.6", label="raw")
    ax_trace.plot(after, ".", ms=3, color="C0", label="calibrated")
    ax_trace.plot(reference, "k--", lw=0.8, label="reference")
    ax_trace.set_xlabel("reading")
    ax_trace.set_ylabel(f"total field ({unit})")
    ax_trace.legend(loc="best")
    bins = np.linspace(min(before.min(), after.min()), max(before.max(), after.max()), 50)
    ax_hist.hist(before, bins=bins, color="0.6", label="raw")
    ax_hist.hist(after, bins=bins, color="C0", alpha=0.8, label="calibrated")
    ax_hist.set_xlabel(f"total field ({unit})")
    ax_hist.set_ylabel("readings")


def calibration_figure(raw: np.ndarray, calibrated: np.ndarray, reference: np.ndarray, *, unit: str, title: str):
    """The whole figure: projections on top, magnitude trace and histogram below; returns it."""
    fig = plt.figure(figsize=(10.5, 6.6), layout="constrained")
    grid = fig.add_gridspec(2, 3)
    projections([fig.add_subplot(grid[0, k]) for k in range(3)], raw, calibrated, float(np.mean(reference)), unit)
    magnitudes(fig.add_subplot(grid[1, :2]), fig.add_subplot(grid[1, 2]), raw, calibrated, reference, unit)
    fig.suptitle(title)
    return fig
