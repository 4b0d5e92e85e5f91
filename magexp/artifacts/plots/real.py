"""Recorded data (``experiments/real``): what a recording has, with no truth to subtract.

A recording carries no true calibration, so nothing here draws "estimate - truth". Kind
``recording`` (gyro-aided fits: ``real_table7``, ``real_modes``) draws, per estimator or per
recording (the hue):

* the fit's objective per seed (``plot.metric``: ``fg``, Yuan 2018's ``F_g = sum_j |R_j^T h - S^-1 (B_j - b)|``
  in gauss, or ``vector_residual_fraction``), filled where the run succeeded, open where it failed;
  a run succeeds when it is within ``success.factor`` of the best value any run of the artifact
  reached on the same recording (``success: {reference: best}``, :data:`magexp.artifacts.plan.BEST`);
* the spread ``std/mean`` of the total field before (raw) and after the calibration;
* the estimates of ``S``, ``b`` and the gyroscope bias, each the median over the successful seeds
  with its standard error from the Jacobian at the estimate (``se_*``,
  :func:`magexp.core.identifiability.identifiability`); the rest recording's mean rate beside the bias;
* the smallest relative singular value of the scaled Jacobian (what the motion leaves undetermined).

The gyro-aided objective cannot tell ``(S, b, h)`` from ``(-S, b, -h)`` (both give the same residual
norm), so each estimate is shown as the member of the pair with ``det S > 0``
(:func:`magexp.artifacts.kinds.recording.canonical_sign`; the tables:
:func:`magexp.artifacts.kinds.recording.table` and :func:`~magexp.artifacts.kinds.recording_spread.table`).

Kind ``recording_spread`` (``real_benchmark``, scalar objective on every recording) draws per
recording the spread of the raw readings, of the calibrated fitted readings and of the calibrated
held-out block, with the held-out spread's 95 % block-bootstrap interval
(:func:`magexp.core.identifiability.block_bootstrap_spread`), per estimator.
"""

from __future__ import annotations

import textwrap

import numpy as np
import pandas as pd
from matplotlib.lines import Line2D

from magexp.artifacts.plots.style import panels, tidy_log_axes

#: the estimate panels of the ``recording`` figure: title, parameters
ESTIMATE_PANELS = (("matrix S (dimensionless)", ["S11", "S12", "S13", "S21", "S22", "S23", "S31", "S32", "S33"]),
                   ("offset b (G)", ["b1", "b2", "b3"]),
                   ("gyroscope bias (deg/s)", ["gyro_bias_x", "gyro_bias_y", "gyro_bias_z"]))
#: a standard error larger than this many times the spread of the panel's estimates is drawn as
#: "larger than the panel" (an open marker) instead of an error bar that would hide every other one
SE_SHOWN = 3.0


def _dots(ax, frame: pd.DataFrame, quantity: str, labels: list[str], colours: dict) -> None:
    """Per label, one dot per seed: filled if the run succeeded, open if not."""
    for j, lab in enumerate(labels):
        sub = frame[(frame.label == lab) & (frame.quantity == quantity)]
        good = sub.succeeded != 0
        x = j + np.linspace(-0.12, 0.12, max(len(sub), 1))[: len(sub)]
        ax.plot(x[good.to_numpy()], sub.value[good], "o", ms=5, color=colours[lab])
        ax.plot(x[~good.to_numpy()], sub.value[~good], "o", ms=5, mfc="none", color=colours[lab])


def _ticks(ax, frame: pd.DataFrame, labels: list[str]) -> None:
    """Label ticks with the success count (``k/n ok``)."""
    first = frame.drop_duplicates("label").set_index("label")
    texts = [textwrap.fill(lab, 11) + (f"\n{first.n_success[lab]}/{first.n_seeds[lab]} ok" if first.n_seeds[lab] > 1 else "")
             for lab in labels]
    ax.set_xticks(range(len(labels)), texts, fontsize=7)
    ax.set_xlim(-0.6, len(labels) - 0.4)


def _estimates(ax, frame: pd.DataFrame, title: str, names: list[str], labels: list[str], colours: dict) -> None:
    """Median estimate of each parameter per label, with its standard error as the bar; open markers
    where the error is undetermined or larger than :data:`SE_SHOWN` times the estimates' span."""
    est = frame[(frame.row == "estimate") & frame.quantity.isin(names)]
    values = est.value.to_numpy(float)
    span = np.ptp(values[np.isfinite(values)]) if np.isfinite(values).any() else 1.0
    cap = SE_SHOWN * max(span, 1e-3 * np.nanmax(np.abs(values)) if np.isfinite(values).any() else 1.0, 1e-12)
    width = 0.8 / max(len(labels), 1)
    for j, lab in enumerate(labels):
        sub = est[est.label == lab].set_index("quantity").reindex(names)
        x = np.arange(len(names)) - 0.4 + width * (j + 0.5)
        shown = np.isfinite(sub.se.to_numpy(float)) & (sub.se.to_numpy(float) <= cap)
        ax.errorbar(x[shown], sub.value[shown], yerr=sub.se[shown], fmt="o", ms=3.5, capsize=2, lw=1,
                    color=colours[lab])
        ax.plot(x[~shown], sub.value[~shown], "o", ms=5, mfc="none", color=colours[lab])
    if names[0].startswith("gyro_bias"):  # the same gyroscope at rest: its mean rate
        rest = frame[frame.quantity.isin([f"gyro_bias_rest_{a}" for a in "xyz"])]
        for k, axis in enumerate("xyz"):
            v = rest[rest.quantity == f"gyro_bias_rest_{axis}"].value
            if len(v):
                ax.hlines(float(v.iloc[0]), k - 0.45, k + 0.45, color="k", lw=1.5,
                          label="mean rate at rest (10-min recording)" if k == 0 else None)
        if len(rest):
            ax.legend(loc="best", fontsize=7)
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xticks(np.arange(len(names)), names, fontsize=7)
    ax.set_xlim(-0.6, len(names) - 0.4)
    ax.set_title(f"{title}\nmedian over the successful seeds, bar ± 1 SE", fontsize=8)


def draw(frame: pd.DataFrame, spec, axes=None):
    """Six panels (module docstring); the hue is the estimator (one recording) or the recording."""
    metric = spec.plot.get("metric", "fg")
    labels = list(dict.fromkeys(frame.label))
    colours = {lab: f"C{k}" for k, lab in enumerate(labels)}
    fig, axes = panels(6, width=4.3, height=3.0, rows=3, axes=axes)
    runs = frame[frame.row == "run"]
    ax = axes[0]
    _dots(ax, runs, metric, labels, colours)
    factor = spec.success.factor if spec.success is not None else None
    fit = runs[runs.quantity == metric]
    if factor and fit.scenario.nunique() == 1 and len(fit):
        ax.axhline(factor * fit.value.min(), color="k", ls="--", lw=0.8, label=f"success: <= {factor:g} x best")
        ax.legend(loc="best", fontsize=7)
    ax.set_yscale("log")
    name = {"fg": "F_g (G, sum over the readings)"}.get(metric, metric.replace("_", " "))
    ax.set_title(name + ("\nper seed; open: failed" if (runs.drop_duplicates("label").n_seeds > 1).any() else ""),
                 fontsize=8)
    _ticks(ax, runs, labels)
    ax = axes[1]
    for j, lab in enumerate(labels):
        sub = runs[(runs.label == lab) & (runs.quantity == "spread_before")]
        ax.plot([j], sub.value.iloc[:1], "x", ms=7, color="0.4")
    _dots(ax, runs, "spread_after", labels, colours)
    ax.set_yscale("log")
    ax.set_title("total-field spread std/mean: x raw, dots calibrated", fontsize=8)
    _ticks(ax, runs, labels)
    for ax, (title, names) in zip(axes[2:5], ESTIMATE_PANELS):
        _estimates(ax, frame, title, names, labels, colours)
    ax = axes[5]
    _dots(ax, runs, "weakest_relative_sv", labels, colours)
    ax.set_yscale("log")
    ax.set_title("identifiability: smallest / largest singular value\nof the column-scaled Jacobian", fontsize=8)
    _ticks(ax, runs, labels)
    handles = [Line2D([], [], marker="o", ls="", color=colours[lab], label=lab) for lab in labels]
    handles.append(Line2D([], [], marker="o", ls="", mfc="none", color="0.3",
                          label=f"open estimate: SE undetermined or > {SE_SHOWN:g} x the panel's span"))
    fig.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), 4), fontsize=7)
    fig.suptitle(spec.title, fontsize=10)
    return tidy_log_axes(fig)
