"""Before/after figure of a calibrated recording: the raw ellipsoid becoming a sphere.

A recording of more than :data:`MAX_POINTS` readings is drawn thinned: the projections and the
magnitude trace show :data:`MAX_POINTS` evenly spaced readings (every k-th, in time order, the
first and the last included; the trace's axis says how many of how many), the histogram counts
every reading. A figure of 8 million points would take minutes and hundreds of MB to draw and
show nothing more."""

from __future__ import annotations

import textwrap

import numpy as np

from magexp.artifacts.plots.style import plt
from magexp.core.identifiability import CELLS, fibonacci_sphere

PAIRS = ((0, 1, "x", "y"), (0, 2, "x", "z"), (1, 2, "y", "z"))
#: most readings drawn as points (module docstring)
MAX_POINTS = 20_000


def drawn(n: int, most: int = MAX_POINTS) -> np.ndarray:
    """Indices of the readings drawn out of ``n``: all, or ``most`` evenly spaced ones."""
    return np.arange(n) if n <= most else np.unique(np.linspace(0, n - 1, most).round().astype(int))


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
    k = drawn(len(before))
    ax_trace.plot(k, before[k], ".", ms=3, color="0.6", label="raw")
    ax_trace.plot(k, after[k], ".", ms=3, color="C0", label="calibrated")
    ax_trace.plot(k, reference[k], "k--", lw=0.8, label="reference")
    ax_trace.set_xlabel("reading" if len(k) == len(before) else
                        f"reading ({len(k)} of {len(before)} drawn, evenly spaced)")
    ax_trace.set_ylabel(f"total field ({unit})")
    ax_trace.legend(loc="best")
    bins = np.linspace(min(before.min(), after.min()), max(before.max(), after.max()), 50)
    ax_hist.hist(before, bins=bins, color="0.6", label="raw")
    ax_hist.hist(after, bins=bins, color="C0", alpha=0.8, label="calibrated")
    ax_hist.set_xlabel(f"total field ({unit})")
    ax_hist.set_ylabel("readings")


def coverage_map(ax, raw: np.ndarray, centre: np.ndarray) -> None:
    """The sphere's :data:`~magexp.core.identifiability.CELLS` equal-area cells (their centres, in
    azimuth and ``z = sin(elevation)``, an equal-area map), filled where the raw directions about the
    fitted centre reach: what the recording covered (the report's ``coverage_cells``)."""
    u = raw - centre
    u = u / np.maximum(np.linalg.norm(u, axis=1, keepdims=True), 1e-300)
    cells = fibonacci_sphere(CELLS)
    hit = np.bincount(np.argmax(u @ cells.T, axis=1), minlength=CELLS) > 0
    k = drawn(len(u), 2000)
    ax.plot(np.degrees(np.arctan2(u[k, 1], u[k, 0])), u[k, 2], ".", ms=2, color="0.6", label="raw directions")
    az, z = np.degrees(np.arctan2(cells[:, 1], cells[:, 0])), cells[:, 2]
    ax.scatter(az[hit], z[hit], s=90, marker="s", color="C0", label="cell reached")
    ax.scatter(az[~hit], z[~hit], s=90, marker="s", facecolors="none", edgecolors="C3", label="cell missed")
    ax.set_xlim(-180, 180)
    ax.set_ylim(-1.1, 1.1)
    ax.set_xticks([-180, -90, 0, 90, 180])
    ax.set_xlabel("azimuth about the centre (deg)")
    ax.set_ylabel("z of the direction")
    ax.set_title(f"coverage: {int(hit.sum())} of {CELLS} cells", fontsize="medium")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=3, fontsize="x-small", markerscale=0.6,
              handletextpad=0.2, columnspacing=0.8, frameon=False)


#: the floor of the heading-error panel's log axis (degrees): smaller errors (float32 rounding) are drawn on it
HEADING_FLOOR = 1e-3


def heading_panel(ax, curves: dict, note: str) -> None:
    """Heading error against heading, log scale: the worst ``|e|`` over attitudes (and folds) of each stage
    (:func:`magexp.calibration.heading.curves`), at the floor :data:`HEADING_FLOOR` where smaller."""
    colours = {"raw": "0.5", "calibrated (held out)": "C0", "as exported": "C1"}
    for label, err in curves.items():
        psi = 360.0 * np.arange(len(err)) / len(err)
        ax.plot(psi, np.maximum(err, HEADING_FLOOR), color=colours.get(label),
                label=f"{label}: worst {err.max():.3g}°" if err.max() >= HEADING_FLOOR else f"{label}: < {HEADING_FLOOR:g}°")
    ax.set_yscale("log")
    ax.set_ylim(HEADING_FLOOR / 2, 360)
    ax.set_xlim(0, 360)
    ax.set_xticks([0, 90, 180, 270, 360])
    ax.set_xlabel("heading (deg)")
    ax.set_ylabel("worst heading error (deg)")
    ax.set_title("\n".join(textwrap.wrap(note, 48)), fontsize="small")
    ax.legend(loc="best", fontsize="x-small")


def calibration_figure(raw: np.ndarray, calibrated: np.ndarray, reference: np.ndarray, *, unit: str, title: str,
                       centre: np.ndarray | None = None, heading: tuple[dict, str] | None = None):
    """The whole figure: projections and (with the fitted ``centre``) the coverage map on top,
    magnitude trace and histogram (and with ``heading`` the heading error, :func:`heading_panel`) below;
    returns it."""
    fig = plt.figure(figsize=(13.5 if centre is not None else 10.5, 6.6), layout="constrained")
    grid = fig.add_gridspec(2, 4 if centre is not None else 3)
    k = drawn(len(raw))
    projections([fig.add_subplot(grid[0, j]) for j in range(3)], raw[k], calibrated[k], float(np.mean(reference)),
                unit)
    if centre is not None:
        coverage_map(fig.add_subplot(grid[0, 3]), raw, centre)
    columns = 4 if centre is not None else 3
    if heading is None:
        magnitudes(fig.add_subplot(grid[1, :2]), fig.add_subplot(grid[1, 2:]), raw, calibrated, reference, unit)
    else:
        magnitudes(fig.add_subplot(grid[1, :columns - 2]), fig.add_subplot(grid[1, columns - 2]), raw, calibrated,
                   reference, unit)
        heading_panel(fig.add_subplot(grid[1, columns - 1]), *heading)
    fig.suptitle(title)
    return fig
