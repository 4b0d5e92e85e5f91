"""Total field of every reading before and after calibration (the first seed of each cell)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.plots.style import group_values, label, panels


def tabulate(runs) -> pd.DataFrame:
    frames = []
    for ci, cell in enumerate(runs.cells):
        seed = min(s for (c, s) in runs.outputs if c == ci)
        out = runs.outputs[(ci, seed)]
        calibrated = np.linalg.norm(out.calibrated, axis=1)
        frames.append(pd.DataFrame({
            **cell, "seed": seed, "reading": np.arange(len(calibrated)),
            "raw": np.linalg.norm(out.readings, axis=1), "calibrated": calibrated,
            "reference": out.reference_norm, "error": calibrated - out.reference_norm,
        }))
    return pd.concat(frames, ignore_index=True)


def draw(frame: pd.DataFrame, spec, axes=None):
    key = spec.plot.get("panels")
    values = group_values(frame, key)
    show_raw = spec.plot.get("quantity", "magnitude") == "magnitude"
    fig, axes = panels(len(values) * (2 if show_raw else 1), rows=2 if show_raw else 1, height=3.0, axes=axes)
    n = len(values)
    for i, v in enumerate(values):
        sub = frame if v is None else frame[frame[key] == v]
        title = "" if v is None else label(spec, key, v)
        rms = float(np.sqrt(np.mean(sub.error**2)))
        if show_raw:
            ax = axes[i]
            ax.plot(sub.reading, sub.raw, ".", ms=2.5, color="0.5", label="before")
            ax.plot(sub.reading, sub.reference, "k--", lw=0.8, label="reference")
            ax.set_title(f"{title}\nbefore calibration")
            ax.set_ylabel("total field (nT)")
            ax = axes[n + i]
            ax.plot(sub.reading, sub.calibrated, ".", ms=2.5, label="after")
            ax.plot(sub.reading, sub.reference, "k--", lw=0.8)
            ax.set_title(f"after (RMS {rms:.3g} nT)")
            ax.set_ylabel("total field (nT)")
            ax.ticklabel_format(axis="y", useOffset=True, style="plain")
        else:
            ax = axes[i]
            ax.plot(sub.reading, sub.error, ".", ms=2.5)
            ax.axhline(0, color="k", lw=0.8)
            ax.set_title(f"{title}\nRMS {rms:.3g} nT")
            ax.set_ylabel("total-field error (nT)")
        ax.set_xlabel("reading")
    fig.suptitle(spec.title, fontsize=10)
    return fig
