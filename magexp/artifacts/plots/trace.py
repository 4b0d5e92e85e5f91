"""Parameters vs filter step: median and interquartile band over seeds, references as lines.

Reads ``trace[key]`` (``plot.trace``, default ``"x"``) of every run, shape ``(steps + 1, p)``,
named by ``trace[key + "_names"]`` or the run's ``parameter_names``. Cells without that trace
(closed-form estimators, a paper's fixed solution) are drawn as horizontal lines (dotted, dash-dot,
...) at their final estimate; a known truth (``truth_<name>`` metrics) as dashed lines.

``plot.groups``: lists of parameter names, one panel each (default: one panel per parameter);
``plot.start``: first step drawn (to hide the transient from ``x(0) = 0``; default 0).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.artifacts.plots.style import panels, plt

REFERENCE_STYLES = {":": "dotted", "-.": "dash-dot", (0, (5, 1, 1, 1, 1, 1)): "dash-dot-dot"}


def _names(out, key: str) -> list[str]:
    return list(out.trace.get(f"{key}_names", out.parameter_names))


def _traced(runs, ci: int, seeds: list[int], key: str, cell: dict, estimator: str) -> pd.DataFrame:
    stack = np.stack([np.asarray(runs.outputs[(ci, s)].trace[key]) for s in seeds])  # (seeds, steps, p)
    q25, q50, q75 = np.quantile(stack, [0.25, 0.5, 0.75], axis=0)
    steps = np.arange(stack.shape[1])
    return pd.concat([pd.DataFrame({**cell, "estimator": estimator, "kind": "trace", "parameter": name, "step": steps,
                                    "median": q50[:, j], "q25": q25[:, j], "q75": q75[:, j], "n_seeds": len(seeds)})
                      for j, name in enumerate(_names(runs.outputs[(ci, seeds[0])], key))], ignore_index=True)


def _levels(sub: pd.DataFrame, names: list[str], prefix: str, kind: str, cell: dict, estimator: str) -> list[dict]:
    rows = []
    for name in names:
        col = f"{prefix}{name}"
        if col in sub and sub[col].notna().any():
            v = sub[col].astype(float)
            rows.append({**cell, "estimator": estimator, "kind": kind, "parameter": name, "step": np.nan,
                         "median": float(v.median()), "q25": float(v.quantile(0.25)), "q75": float(v.quantile(0.75)),
                         "n_seeds": len(sub)})
    return rows


def tabulate(runs) -> pd.DataFrame:
    key = runs.spec.plot.get("trace", "x")
    traced = {ci for (ci, s), out in runs.outputs.items() if key in out.trace}
    names = _names(runs.outputs[min(k for k in runs.outputs if k[0] in traced)], key) if traced else []
    frames, levels = [], []
    for ci, cell in enumerate(runs.cells):
        seeds = sorted(s for (c, s) in runs.outputs if c == ci)
        sub = runs.table[runs.table.cell == ci]
        est = sub.estimator.iloc[0]
        if ci in traced:
            frames.append(_traced(runs, ci, seeds, key, cell, est))
            levels += _levels(sub, names, "truth_", "truth", cell, est)
        else:
            levels += _levels(sub, names, "", "reference", cell, est)
    truth = pd.DataFrame(levels)
    if len(truth):  # one truth line per parameter
        truth = pd.concat([truth[truth.kind == "truth"].drop_duplicates("parameter"), truth[truth.kind != "truth"]])
    return pd.concat(frames + [truth], ignore_index=True)


def draw(frame: pd.DataFrame, spec, axes=None):
    traces = frame[(frame.kind == "trace") & (frame.step >= float(spec.plot.get("start", 0)))]
    groups = [list(g) for g in spec.plot.get("groups", [])] or [[p] for p in dict.fromkeys(traces.parameter)]
    fig, axes = panels(len(groups), width=3.6, rows=-(-len(groups) // 2) if len(groups) > 2 else 1, axes=axes)
    several = traces.estimator.nunique() > 1
    refs = list(dict.fromkeys(frame[frame.kind == "reference"].estimator))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, group in zip(axes, groups):
        for k, (name, est) in enumerate((p, e) for e in dict.fromkeys(traces.estimator) for p in group):
            _draw_parameter(ax, frame, traces, name, est, colours[k % len(colours)], several=several, refs=refs)
        ax.set_xlabel("filter step")
        ax.set_ylabel(spec.plot.get("ylabel", "estimate"))
        ax.legend(loc="best", ncol=len(group) if not several else 1)
    lines = (["dashed: truth"] if (frame.kind == "truth").any() else []) + [
        f"{word}: {ref}" for ref, word in zip(refs, REFERENCE_STYLES.values())]
    note = "; ".join(lines)
    fig.suptitle(f"{spec.title}\n{note}".strip(), fontsize=9)
    return fig


def _draw_parameter(ax, frame: pd.DataFrame, traces: pd.DataFrame, name: str, est: str, colour, *,
                    several: bool, refs: list) -> None:
    """The trace of parameter ``name`` by estimator ``est`` (median over seeds, interquartile band),
    its true value (dashed; black when several estimators share the panel) and the final values of
    the reference estimators ``refs`` (one line style each, :data:`REFERENCE_STYLES`)."""
    line = traces[(traces.parameter == name) & (traces.estimator == est)]
    ax.plot(line.step, line["median"], lw=1.1, color=colour, label=f"{name} ({est})" if several else name)
    ax.fill_between(line.step, line.q25, line.q75, color=colour, alpha=0.2, lw=0)
    for _, row in frame[(frame.kind == "truth") & (frame.parameter == name)].iterrows():
        ax.axhline(row["median"], color="k" if several else colour, ls="--", lw=0.9)
    for ref, style in zip(refs, REFERENCE_STYLES):
        for _, row in frame[(frame.kind == "reference") & (frame.parameter == name) & (frame.estimator == ref)].iterrows():
            ax.axhline(row["median"], color=colour, ls=style, lw=0.9)
