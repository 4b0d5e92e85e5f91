"""RMS (objective) of the best particle vs iteration: median over seeds with an interquartile band."""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.plots.style import group_values, label, panels


def _stack(histories: list[np.ndarray]) -> np.ndarray:
    n = max(len(h) for h in histories)
    return np.vstack([np.pad(h, (0, n - len(h)), mode="edge") for h in histories])


def tabulate(runs) -> pd.DataFrame:
    frames = []
    for ci, cell in enumerate(runs.cells):
        seeds = sorted(s for (c, s) in runs.outputs if c == ci)
        hist = _stack([runs.outputs[(ci, s)].history for s in seeds])
        nfev = _stack([runs.outputs[(ci, s)].history_nfev for s in seeds])
        q25, q50, q75 = np.quantile(hist, [0.25, 0.5, 0.75], axis=0)
        sub = runs.table[runs.table.cell == ci]
        frames.append(pd.DataFrame({
            **{k: v for k, v in cell.items()}, "estimator": sub.estimator.iloc[0],
            "iteration": np.arange(hist.shape[1]), "nfev": np.median(nfev, axis=0),
            "median": q50, "q25": q25, "q75": q75,
            "noise_floor": float(sub.noise_floor.median()) if "noise_floor" in sub else np.nan,
            "rms_bound": float(sub.rms_bound.median()) if "rms_bound" in sub else np.nan,
            "n_seeds": len(seeds),
            "converged": int(sub.converged.sum()) if "converged" in sub else -1,
        }))
    return pd.concat(frames, ignore_index=True)


def draw(frame: pd.DataFrame, spec, axes=None):
    panel_key, hue_key = spec.plot.get("panels"), spec.plot.get("hue")
    panel_vals = group_values(frame, panel_key)
    fig, axes = panels(len(panel_vals), axes=axes)
    for ax, pv in zip(axes, panel_vals):
        sub = frame if pv is None else frame[frame[panel_key] == pv]
        for hv in group_values(sub, hue_key):
            line = sub if hv is None else sub[sub[hue_key] == hv]
            lab = line.estimator.iloc[0] if hue_key in (None, "estimator") else label(spec, hue_key, hv)
            if line.converged.iloc[0] >= 0:
                lab += f" ({line.converged.iloc[0]}/{line.n_seeds.iloc[0]} conv.)"
            floor_pos = line[["median", "q25", "q75"]].clip(lower=1e-14)
            (ln,) = ax.plot(line.iteration, floor_pos["median"], lw=1.2, label=lab)
            ax.fill_between(line.iteration, floor_pos["q25"], floor_pos["q75"], color=ln.get_color(), alpha=0.2, lw=0)
            if sub.noise_floor.nunique() > 1 and line.noise_floor.iloc[0] > 0:  # one floor per line
                ax.axhline(line.noise_floor.iloc[0], color=ln.get_color(), ls=":", lw=0.9)
        floor = float(sub.noise_floor.median())
        if sub.noise_floor.nunique() == 1 and np.isfinite(floor) and floor > 0:
            ax.axhline(floor, color="k", ls="--", lw=0.9, label="noise floor")
        bound = float(sub.rms_bound.median()) if "rms_bound" in sub else np.nan
        if sub.rms_bound.nunique() <= 1 and np.isfinite(bound) and bound > 0:
            ax.axhline(bound, color="0.4", ls=":", lw=1.1, label="Cramér-Rao floor")
        ax.set_yscale("log")
        ax.set_xlabel("iteration")
        ax.set_ylabel(spec.plot.get("ylabel", "total-field RMS (nT)"))
        if pv is not None:
            ax.set_title(label(spec, panel_key, pv))
    axes[0].legend(loc="upper right")
    fig.suptitle(spec.title, fontsize=10)
    return fig
