"""Parameters vs filter step: median and interquartile band over seeds, references as lines.

Reads ``trace[key]`` (``plot.trace``, default ``"x"``) of every run, shape ``(steps + 1, p)``,
named by ``trace[key + "_names"]`` or the run's ``parameter_names``. Cells without that trace
(closed-form estimators, a paper's fixed solution) are drawn as horizontal lines (dotted, dash-dot,
...) at their final estimate; a known truth (``truth_<name>`` metrics) as dashed lines.

``plot.groups``: lists of parameter names, one panel each (default: one panel per parameter);
``plot.start``: first step drawn (to hide the transient from ``x(0) = 0``; default 0);
``plot.names``: ``{estimator: words}`` for the legend and the title.

``plot.relative_to``: an estimator of the artifact (e.g. ``ls``) whose final estimate the traces are
measured against. A second row of panels then draws, on a log axis, per parameter the distance
``|x(step) - x_ref|`` of each seed's trace from the reference's estimate on the same seed (median
over seeds, interquartile band), the distance of every other estimate from it (the paper's: dash-dot;
the truth: dashed) and ``plot.tolerances`` (one per group: the accuracy at which the caption calls the
trace converged) as a black line: differences of 1e-4 that the estimates' own scale hides.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.artifacts.plots.style import panels, plt, tidy_log_axes

TINY = 1e-12  # a log axis draws a distance of 0 (the reference's own seed, round-off) here
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


def _distances(runs, key: str, names: list[str], traced: set) -> list[pd.DataFrame]:
    """Rows of ``|x - x_ref|`` per parameter (``plot.relative_to``: the reference estimator): each
    traced cell's trace per step (kind ``distance``), every other cell's estimate and the truth
    (kind ``distance_reference``, ``distance_truth``), quantiles over the seeds they share."""
    ref = runs.spec.plot.get("relative_to")
    table = runs.table
    ref_rows = table[table.estimator == ref].set_index("seed")[names] if ref else None
    if ref_rows is None or not len(ref_rows):
        return []
    frames = []
    for ci, cell in enumerate(runs.cells):
        sub = table[table.cell == ci].set_index("seed")
        est, seeds = sub.estimator.iloc[0], sorted(set(sub.index) & set(ref_rows.index))
        if est == ref or not seeds:
            continue
        if ci in traced:
            stack = np.stack([np.abs(np.asarray(runs.outputs[(ci, s)].trace[key]) - ref_rows.loc[s].to_numpy(float))
                              for s in seeds])
            frames.append(_quantile_rows(stack, names, {**cell, "estimator": est, "kind": "distance"}))
            truth = [f"truth_{n}" for n in names]
            if set(truth) <= set(sub.columns):
                gap = np.abs(sub.loc[seeds, truth].to_numpy(float) - ref_rows.loc[seeds].to_numpy(float))
                frames.append(_quantile_rows(gap[:, None, :], names, {**cell, "estimator": est, "kind": "distance_truth"}, step=np.nan))
        else:
            gap = np.abs(sub.loc[seeds, names].to_numpy(float) - ref_rows.loc[seeds].to_numpy(float))
            frames.append(_quantile_rows(gap[:, None, :], names, {**cell, "estimator": est, "kind": "distance_reference"}, step=np.nan))
    return frames


def _quantile_rows(stack: np.ndarray, names: list[str], fixed: dict, step=None) -> pd.DataFrame:
    """Median and quartiles over seeds (axis 0) of ``stack`` (seeds, steps, p), one row per (step, name)."""
    q25, q50, q75 = np.quantile(stack, [0.25, 0.5, 0.75], axis=0)
    steps = np.arange(stack.shape[1]) if step is None else np.full(stack.shape[1], step)
    return pd.concat([pd.DataFrame({**fixed, "parameter": name, "step": steps, "median": q50[:, j], "q25": q25[:, j],
                                    "q75": q75[:, j], "n_seeds": stack.shape[0]}) for j, name in enumerate(names)],
                     ignore_index=True)


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
    return pd.concat(frames + [truth] + _distances(runs, key, names, traced), ignore_index=True)


def _name(spec, estimator: str) -> str:
    """An estimator in words (``plot.names``), else its config name."""
    return str(dict(spec.plot.get("names", {}) or {}).get(estimator, estimator))


def draw(frame: pd.DataFrame, spec, axes=None):
    traces = frame[(frame.kind == "trace") & (frame.step >= float(spec.plot.get("start", 0)))]
    groups = [list(g) for g in spec.plot.get("groups", [])] or [[p] for p in dict.fromkeys(traces.parameter)]
    distance = "distance" in set(frame.kind)
    fig, top, bottom = _layout(len(groups), distance, axes)
    several = traces.estimator.nunique() > 1
    refs = list(dict.fromkeys(frame[frame.kind == "reference"].estimator))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, group in zip(top, groups):
        for k, (name, est) in enumerate((p, e) for e in dict.fromkeys(traces.estimator) for p in group):
            _draw_parameter(ax, frame, traces, name, _name(spec, est), est, colours[k % len(colours)], several=several, refs=refs)
        ax.set_xlabel("filter step")
        ax.set_ylabel(spec.plot.get("ylabel", "estimate"))
        ax.legend(loc="best", ncol=len(group) if not several else 1)
    tolerances = list(spec.plot.get("tolerances", []) or [])
    for j, (ax, group) in enumerate(zip(bottom, groups)):
        _draw_distances(ax, frame, group, colours, dict(zip(refs, REFERENCE_STYLES)),
                        tolerances[j] if j < len(tolerances) else None)
        ax.set_xlabel("filter step")
        ax.set_ylabel(f"|estimate - {_name(spec, spec.plot.relative_to)}|")
    lines = (["dashed: truth"] if (frame.kind == "truth").any() else []) + [
        f"{word}: {_name(spec, ref)}" for ref, word in zip(refs, REFERENCE_STYLES.values())]
    if distance:
        lines.append(f"bottom: distance from {_name(spec, spec.plot.relative_to)} on the same seed, same styles; "
                     "black: the stated accuracy")
    note = "; ".join(lines)
    fig.suptitle(f"{spec.title}\n{note}".strip(), fontsize=9)
    return tidy_log_axes(fig)


def _layout(n: int, distance: bool, axes):
    """The figure, the panels of the estimates and those of the distances (``distance``: a second
    row, one column per group; else none, and the groups two a row)."""
    if distance:
        fig, axes = panels(2 * n, width=3.4, height=2.9, rows=2, axes=axes)
        return fig, axes[:n], axes[n:]
    fig, top = panels(n, width=3.6, rows=-(-n // 2) if n > 2 else 1, axes=axes)
    return fig, top, []


def _draw_distances(ax, frame: pd.DataFrame, group: list[str], colours, styles: dict, tolerance) -> None:
    """Per parameter of ``group``: the distance of the trace from the reference (median, IQR band)
    and of the other estimates (truth dashed, the reference estimators in their ``styles``), on a
    log axis, and the ``tolerance`` as a black line."""
    for k, name in enumerate(group):
        colour = colours[k % len(colours)]
        line = frame[(frame.kind == "distance") & (frame.parameter == name)]
        ax.plot(line.step, line["median"].clip(lower=TINY), lw=1.1, color=colour, label=name)
        ax.fill_between(line.step, line.q25.clip(lower=TINY), line.q75.clip(lower=TINY), color=colour, alpha=0.2, lw=0)
        for _, row in frame[(frame.kind == "distance_truth") & (frame.parameter == name)].iterrows():
            ax.axhline(max(row["median"], TINY), color=colour, ls="--", lw=0.9)
        for _, row in frame[(frame.kind == "distance_reference") & (frame.parameter == name)].iterrows():
            ax.axhline(max(row["median"], TINY), color=colour, ls=styles.get(row.estimator, "-."), lw=0.9)
    if tolerance is not None:
        ax.axhline(float(tolerance), color="k", lw=1.0)
    ax.set_yscale("log")
    ax.legend(loc="best", ncol=len(group))


def _draw_parameter(ax, frame: pd.DataFrame, traces: pd.DataFrame, name: str, shown: str, est: str, colour, *,
                    several: bool, refs: list) -> None:
    """The trace of parameter ``name`` by estimator ``est`` (``shown``: its name in the legend;
    median over seeds, interquartile band), its true value (dashed; black when several estimators
    share the panel) and the final values of the reference estimators ``refs`` (one line style
    each, :data:`REFERENCE_STYLES`)."""
    line = traces[(traces.parameter == name) & (traces.estimator == est)]
    ax.plot(line.step, line["median"], lw=1.1, color=colour, label=f"{name} ({shown})" if several else name)
    ax.fill_between(line.step, line.q25, line.q75, color=colour, alpha=0.2, lw=0)
    for _, row in frame[(frame.kind == "truth") & (frame.parameter == name)].iterrows():
        ax.axhline(row["median"], color="k" if several else colour, ls="--", lw=0.9)
    for ref, style in zip(refs, REFERENCE_STYLES):
        for _, row in frame[(frame.kind == "reference") & (frame.parameter == name) & (frame.estimator == ref)].iterrows():
            ax.axhline(row["median"], color=colour, ls=style, lw=0.9)
