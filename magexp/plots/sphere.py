"""Readings before and after calibration against the sphere of radius |H| (Yuan 2018 figs 2-4).

The first seed of each cell; 3-D scatter: grey the raw readings, colour the calibrated ones,
wireframe the sphere of radius the median reference total field.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.plots.style import group_values, label, plt


def tabulate(runs) -> pd.DataFrame:
    frames = []
    for ci, cell in enumerate(runs.cells):
        seed = min(s for (c, s) in runs.outputs if c == ci)
        out = runs.outputs[(ci, seed)]
        raw, cal = np.asarray(out.readings), np.asarray(out.calibrated)
        frames.append(pd.DataFrame({
            **cell, "seed": seed, "reading": np.arange(len(raw)),
            "raw_x": raw[:, 0], "raw_y": raw[:, 1], "raw_z": raw[:, 2],
            "cal_x": cal[:, 0], "cal_y": cal[:, 1], "cal_z": cal[:, 2], "radius": out.reference_norm,
            "radial_error": np.linalg.norm(cal, axis=1) - out.reference_norm,
        }))
    return pd.concat(frames, ignore_index=True)


def draw(frame: pd.DataFrame, spec, axes=None):
    key = spec.plot.get("panels")
    values = group_values(frame, key)
    axes = None if axes is None else ([axes] if hasattr(axes, "plot") else list(axes))  # the caller's 3-D axes
    fig = plt.figure(figsize=(4.2 * len(values), 4.2)) if axes is None else axes[0].figure
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 25), np.linspace(0, np.pi, 13))
    for i, val in enumerate(values):
        sub = frame if val is None else frame[frame[key] == val]
        ax = fig.add_subplot(1, len(values), i + 1, projection="3d") if axes is None else axes[i]
        r = float(sub.radius.median())
        ax.plot_wireframe(r * np.cos(u) * np.sin(v), r * np.sin(u) * np.sin(v), r * np.cos(v),
                          color="0.8", lw=0.4)
        ax.scatter(sub.raw_x, sub.raw_y, sub.raw_z, s=6, color="0.45", label="before")
        ax.scatter(sub.cal_x, sub.cal_y, sub.cal_z, s=8, color="C0", label="after")
        rms = float(np.sqrt(np.mean(sub.radial_error**2)))
        title = "" if val is None else label(spec, key, val) + "\n"
        ax.set_title(f"{title}RMS of |B| - |H| after: {rms:.3g}", fontsize=8)
        ax.set_box_aspect((1, 1, 1))
        ax.set_xlabel("x")
        ax.set_ylabel("y")
        ax.set_zlabel("z")
        if i == 0:
            ax.legend(loc="upper left", fontsize=7)
    fig.suptitle(spec.title, fontsize=10)
    return fig
