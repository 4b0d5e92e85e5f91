"""Every estimator on every recording (kind ``recording_spread``, ``real_benchmark``): the spread of
the total field, the one thing a recording without a reference has to judge a calibration by.

One row per (recording, estimator): the spread ``std/mean`` of the raw readings, of the calibrated
readings the fit saw, and of the calibrated held-out block (a contiguous part of the recording
left out of the fit), each the median over seeds; the held-out spread's 95 % interval is the widest
of the seeds' block-bootstrap intervals (:func:`magexp.core.identifiability.block_bootstrap_spread`: it covers
the data's own uncertainty, which one recording cannot average away, and the seeds' differences).
``success_rate``: the share of runs where the estimator reports success and the calibrated spread
is below the raw one (:func:`magexp.core.outcomes.recording_succeeded`, as
:func:`magexp.artifacts.kinds.heatmap.table`; this table: :func:`magexp.artifacts.kinds.recording_spread.table`).
The winner per recording
(:func:`magexp.artifacts.kinds.heatmap.winners` on ``heldout_spread``) is named only where its interval
lies below every other estimator's.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.lines import Line2D

from magexp.artifacts.plots.style import panels, tidy_log_axes
from magexp.core.outcomes import failed_majority

def draw(frame: pd.DataFrame, spec, axes=None):
    """One panel per recording: per estimator, the calibrated spread on the fitted readings (dot)
    and on the held-out block (diamond, with its interval), the raw spread as a dashed line; an
    estimator whose runs mostly failed is drawn in red.
    """
    cases = list(dict.fromkeys(frame.case))
    fig, axes = panels(len(cases), width=3.6, height=3.0, rows=2 if len(cases) > 2 else 1, axes=axes)
    for ax, case in zip(axes, cases):
        sub = frame[frame.case == case].reset_index(drop=True)
        x = np.arange(len(sub))
        failed = failed_majority(sub.success_rate)
        colour = np.where(failed, "tab:red", "tab:blue")
        ax.axhline(sub.spread_before.iloc[0], color="0.4", ls="--", lw=1, label="raw readings")
        ax.scatter(x - 0.12, sub.spread_after, marker="o", s=18, c=colour, label="calibrated, fitted readings")
        err = np.vstack([sub.heldout_spread - sub.heldout_spread_lo, sub.heldout_spread_hi - sub.heldout_spread])
        for k in x:
            ax.errorbar([k + 0.12], [sub.heldout_spread[k]], yerr=err[:, k:k + 1], fmt="D", ms=4, capsize=2,
                        color=colour[k], label="calibrated, held-out block (95 % interval)" if k == 0 else None)
        ax.set_yscale("log")
        ax.set_xticks(x, [f"{e}\n{r:.0%} ok" for e, r in zip(sub.estimator, sub.success_rate)], fontsize=7)
        ax.set_title(case, fontsize=9)
        ax.set_ylabel("spread std/mean of |B|")
    handles, labels = axes[0].get_legend_handles_labels()
    handles.append(Line2D([], [], marker="o", ls="", color="tab:red"))
    labels.append("red: fewer than half the runs succeeded")
    fig.legend(handles, labels, loc="outside lower center", ncols=2, fontsize=7)
    fig.suptitle(spec.title, fontsize=10)
    return tidy_log_axes(fig)
