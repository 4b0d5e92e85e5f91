"""The bench's figure and the text of its report section, both drawn from its summary rows
(:func:`.bench.summarise`): no number is typed here, every one is read from the rows."""

from __future__ import annotations

import numpy as np

from magexp.perf.peers.data import AXIS_MAPS

#: how each method is named in the figure and the tables, in the order they are listed
LABELS = {
    "magexp_lm_gyro": "magexp lm (gyro)", "magexp_rdpso_gyro": "magexp RDPSO (gyro)",
    "magexp_ellipsoid": "magexp ellipsoid", "magexp_twostep": "magexp TWOSTEP",
    "magyc_ls": "MAGYC-LS", "magyc_nls": "MAGYC-NLS", "magyc_bfg": "MAGYC-BFG", "magyc_ifg": "MAGYC-IFG",
    "ellipsoid_fit": "MAGYC's ellipsoid fit", "sphere_fit": "MAGYC's sphere fit", "twostep_hsi": "MAGYC's TWOSTEP",
    "sar_ls": "SAR-LS", "sar_kf": "SAR-KF", "sar_aid": "SAR-AID",
    "magyc_ls_sg": "MAGYC-LS, notebook", "magyc_nls_sg": "MAGYC-NLS, notebook",
    "magyc_bfg_sg": "MAGYC-BFG, notebook", "magyc_ifg_sg": "MAGYC-IFG, notebook",
    "crb_fit": "Cramér-Rao floor (magexp's readings)", "crb_all": "Cramér-Rao floor (every reading)",
}
LEVELS = {"magyc_high": "WAM (high)", "magyc_mid": "MAM (mid)", "magyc_low": "LAM (low)",
          "magyc_tiny": "tiny", "magyc_cross": "cross"}


def pick(summary, **match) -> list[dict]:
    return [r for r in summary if all(r.get(k) == v for k, v in match.items())]


def one(summary, **match) -> dict | None:
    rows = pick(summary, **match)
    return rows[0] if rows else None


def methods_of(summary) -> list[str]:
    present = {r["method"] for r in summary if r["side"] not in ("none", "bound")}
    return [m for m in LABELS if m in present]


def fmt(row: dict | None, stat: str = "median", digits: int = 3, interval: bool = True, percent: bool = False) -> str:
    """``median [lo, hi]`` of a summary row (``–`` for none)."""
    if row is None or not np.isfinite(row[stat]):
        return "–"
    scale, unit = (100.0, " %") if percent else (1.0, "")
    text = f"{row[stat] * scale:.{digits}g}{unit}"
    if interval and stat == "median" and np.isfinite(row["lo"]):
        text += f" [{row['lo'] * scale:.{digits}g}, {row['hi'] * scale:.{digits}g}]"
    return text


def figure(summary, path) -> None:
    """Three panels: soft-iron and hard-iron error on MAGYC's data per motion level, held-out spread on the
    full-sphere recording."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    methods = methods_of(summary)
    levels = [d for d in LEVELS if pick(summary, dataset=d)]
    fig, axes = plt.subplots(1, 3, figsize=(13.5, 5.6), constrained_layout=True)
    x = np.arange(len(methods))
    for ax, metric, title in ((axes[0], "soft_iron_error", "soft-iron error (log-shape distance)"),
                              (axes[1], "hard_iron_error", "hard-iron error / field")):
        for k, level in enumerate(levels):
            rows = [one(summary, dataset=level, method=m, metric=metric) for m in methods]
            med = np.array([r["median"] if r else np.nan for r in rows])
            lo = np.array([r["lo"] if r else np.nan for r in rows])
            hi = np.array([r["hi"] if r else np.nan for r in rows])
            shift = (k - (len(levels) - 1) / 2) * 0.22
            bar = ax.errorbar(x + shift, med, yerr=[np.maximum(med - lo, 0), np.maximum(hi - med, 0)], fmt="o",
                              ms=4, capsize=2, label=LEVELS[level])
            floor = one(summary, dataset=level, method="crb_all", metric=metric)
            if floor is not None and np.isfinite(floor["median"]):
                ax.axhline(floor["median"], color=bar[0].get_color(), ls="--", lw=0.8,
                           label=f"{LEVELS[level]}: Cramér-Rao floor")
        tol = 0.05
        ax.axhline(tol, color="0.4", ls=":", lw=1, label="success threshold")
        ax.set_yscale("log")
        ax.set_title(f"MAGYC's synthetic data: {title}", fontsize=9)
        ax.set_xticks(x, [LABELS[m] for m in methods], rotation=60, ha="right", fontsize=7)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower left", ncols=4, fontsize=7,
               title="MAGYC's data: median over seeds and 95 % CI of the median", title_fontsize=7)
    ax = axes[2]
    raw = one(summary, dataset="hmc5883l_full-sphere", axis_map="aligned", method="raw", metric="spread_in_sample")
    for k, (dataset, marker, label) in enumerate((("hmc5883l_full-sphere", "o", "timestamps as recorded"),
                                                  ("hmc5883l_full-sphere_retimed", "s", "retimed (constant-rate clocks)"))):
        rows = [one(summary, dataset=dataset, axis_map="aligned", fit_on="halves", method=m, metric="spread_held_out")
                for m in methods]
        med = np.array([r["median"] if r else np.nan for r in rows]) * 100
        lo = np.array([r["lo"] if r else np.nan for r in rows]) * 100
        hi = np.array([r["hi"] if r else np.nan for r in rows]) * 100
        ax.errorbar(x + (k - 0.5) * 0.25, med, yerr=[np.maximum(med - lo, 0), np.maximum(hi - med, 0)], fmt=marker,
                    ms=4, capsize=2, color=f"C{k + 3}", label=label)
    if raw:
        ax.axhline(raw["median"] * 100, color="0.3", ls="--", lw=1, label="raw readings")
    ax.set_yscale("log")
    ax.set_ylabel("held-out spread of |calibrated field| (std / mean, %)")
    ax.set_title("HMC5883L full sphere, magnetometer -x,-y,z: fit on one half,\nspread on the other (median of the two)",
                 fontsize=9)
    ax.set_xticks(x, [LABELS[m] for m in methods], rotation=60, ha="right", fontsize=7)
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower right", ncols=3, fontsize=7,
               title="the recording: median of the two halves and their range", title_fontsize=7)
    fig.savefig(path, dpi=130)
    plt.close(fig)


def _table(summary, datasets: dict, metrics: list[tuple[str, str, tuple[dict, dict]]], methods, **match) -> list[str]:
    """A markdown table: one row per dataset and method, one column per metric
    (``(metric, header, (row match, fmt options))``)."""
    lines = ["| data | method | " + " | ".join(h for _, h, _ in metrics) + " |",
             "|---|---|" + "---|" * len(metrics)]
    for dataset, name in datasets.items():
        for m in methods:
            cells = [fmt(one(summary, dataset=dataset, method=m, metric=metric, **match, **extra), **opts)
                     for metric, _, (extra, opts) in metrics]
            if any(c != "–" for c in cells):
                lines.append(f"| {name} | {LABELS.get(m, m)} | " + " | ".join(cells) + " |")
    return lines


def _say(summary, method: str, **match) -> str:
    """``soft-iron e, hard-iron h, success p`` of a method on MAGYC's data at one level."""
    cells = [fmt(one(summary, method=method, metric=m, **match), interval=False) for m in
             ("soft_iron_error", "hard_iron_error")]
    ok = fmt(one(summary, method=method, metric="success", **match), stat="mean", interval=False, percent=True)
    return f"{LABELS[method]} {cells[0]} / {cells[1]} (success {ok})"


def findings(summary) -> list[str]:
    """The headline bullets, every number read from ``summary``."""
    out = []
    for level, name in LEVELS.items():
        if not pick(summary, dataset=level):
            continue
        said = [_say(summary, m, dataset=level) for m in ("magexp_lm_gyro", "magyc_nls", "magyc_nls_sg", "magyc_ifg",
                                                          "magexp_ellipsoid") if one(summary, dataset=level, method=m)]
        out.append(f"* **{name}** (median soft-iron / hard-iron error): " + "; ".join(said) + ".")
    real = dict(dataset="hmc5883l_full-sphere", axis_map="aligned")
    own = one(summary, method="magyc_nls", metric="own_output_spread", fit_on="all", **real)
    applied = one(summary, method="magyc_nls", metric="spread_in_sample", fit_on="all", **real)
    if own and applied:
        out.append(f"* MAGYC's own calibrated output is not its calibration: on the full sphere MAGYC-NLS's returned "
                   f"`calibrated_magnetic_field` spreads {fmt(own, percent=True, interval=False)}, its estimates "
                   f"applied to the readings {fmt(applied, percent=True, interval=False)} (magyc 1.0.0 reshapes the "
                   "N x 3 readings to 3 x N before applying them); the bench applies every method's estimates itself.")
    for dataset, clock in (("hmc5883l_full-sphere", "timestamps as recorded"),
                           ("hmc5883l_full-sphere_retimed", "retimed: constant-rate clocks")):
        where = dict(real, dataset=dataset)
        held = {m: one(summary, method=m, metric="spread_held_out", fit_on="halves", **where)
                for m in ("magexp_lm_gyro", "magexp_ellipsoid", "magyc_nls", "magyc_nls_sg", "magyc_ifg",
                          "twostep_hsi")}
        turn = {m: one(summary, method=m, metric="gyro_consistency", fit_on="all", **where) for m in held}
        raw = one(summary, method="raw", metric="spread_in_sample", **where)
        if raw and all(held.values()):
            out.append(f"* Full sphere, {clock}; spread held out (fit on one half, the other half) and, fitted on all, "
                       "the median angle between calibrated directions and the gyroscope's 1 s ahead: " + "; ".join(
                           f"{LABELS[m]} {fmt(r, percent=True)}, {fmt(turn[m], interval=False)}°"
                           for m, r in held.items()) + f"; raw {fmt(raw, percent=True, interval=False)}.")
    for method in ("magexp_ellipsoid",):  # the peer fails on the recorded timestamps whatever the map
        maps = {m: one(summary, dataset="hmc5883l_full-sphere", axis_map=m, fit_on="all", method=method,
                       metric="gyro_consistency") for m in AXIS_MAPS}
        if all(maps.values()):
            out.append(f"* Axis map, full sphere: {LABELS[method]}'s calibrated directions turn as the gyroscope says "
                       "to within " + ", ".join(f"{fmt(r, interval=False)}° with `{m}`" for m, r in maps.items())
                       + " (median angle over 1 s).")
    lm = {d: one(summary, dataset=d, axis_map="aligned", fit_on="all", method="magexp_lm_gyro", metric=m)
          for d in ("hmc5883l_full-sphere", "hmc5883l_full-sphere_retimed") for m in ("gyro_bias_vs_rest",)}
    if all(lm.values()):
        before, after = lm.values()
        out.append("* What magexp can take from this: its gyro-aided fit of the full sphere also improves when the "
                   "clocks are retimed (gyro bias against the rest recording's mean rate "
                   f"{fmt(before, interval=False)} → {fmt(after, interval=False)} °/s); the real scenarios "
                   "(`real_*`) integrate the gyroscope over the recorded, bursty timestamps. What the peer can take: "
                   "it differentiates the readings, so it needs its prefilter and regular timestamps, where magexp "
                   "integrates the gyroscope; its symmetric soft iron needs the sensors' axes aligned beforehand.")
    return out


def section(summary, args) -> str:
    """The markdown of the section "magexp beside MAGYC"."""
    methods = methods_of(summary)
    levels = {d: LEVELS[d] for d in LEVELS if pick(summary, dataset=d)}
    yuan = {d: d.removeprefix("yuan2018_") for d in sorted({r["dataset"] for r in pick(summary, kind="yuan_stream")})}
    sim_metrics = [("soft_iron_error", "soft-iron error", ({}, {})),
                   ("hard_iron_error", "hard-iron error / field", ({}, {})),
                   ("gyro_bias_error", "gyro-bias error (°/s)", ({}, {})),
                   ("success", "success rate", ({}, {"stat": "mean", "interval": False, "percent": True})),
                   ("seconds", "time (s)", ({}, {"digits": 2, "interval": False}))]
    real_metrics = [("spread_in_sample", "spread, in sample", ({"fit_on": "all"}, {"percent": True, "interval": False})),
                    ("spread_held_out", "spread, held out [two halves]", ({"fit_on": "halves"}, {"percent": True})),
                    ("gyro_consistency", "gyro consistency (°, 1 s)", ({"fit_on": "all"}, {"interval": False})),
                    ("gyro_bias_x", "bias x (°/s)", ({"fit_on": "all"}, {"interval": False})),
                    ("gyro_bias_y", "bias y", ({"fit_on": "all"}, {"interval": False})),
                    ("gyro_bias_z", "bias z", ({"fit_on": "all"}, {"interval": False})),
                    ("gyro_bias_vs_rest", "|bias − rest| (°/s)", ({"fit_on": "all"}, {"interval": False})),
                    ("own_output_spread", "peer's own calibrated output", ({"fit_on": "all"}, {"percent": True, "interval": False})),
                    ("seconds", "time (s)", ({"fit_on": "all"}, {"digits": 2, "interval": False}))]
    recs = {}
    for r in pick(summary, kind="recording", fit_on="all", method="raw"):
        recs[(r["dataset"], r["axis_map"])] = r
    out = ["## magexp beside MAGYC", "",
           f"Produced by `python -m magexp.perf.peers.bench` (MAGYC's generator: {args.seeds} seeds x "
           f"{args.nsamples} readings per motion level; Yuan's scenarios: {args.yuan_seeds} seeds at 100 Hz; "
           "figure `peers.png`). Medians over seeds with the 95 % bootstrap interval of the median in brackets. "
           "Soft iron compared as the unit-determinant shape (D Dᵀ)^½ (log-Euclidean distance), hard iron as a "
           "fraction of the readings' sphere radius; a run succeeds when both are within 0.05 and its gyro bias, "
           "where it estimates one, within 0.1 °/s. *notebook*: the peer as its example notebook calls it, after a "
           "Savitzky-Golay filter (50 samples, order 2) of the magnetometer and the gyroscope.", "",
           *findings(summary), "",
           "### MAGYC's synthetic data (its generator, its paper's settings)", ""]
    out += _table(summary, levels, sim_metrics, methods, kind="magyc_synthetic")
    out += ["", "The Cramér-Rao floor of the gyro-aided problem (magexp.core.bounds at the truth, Gaussian magnetometer noise, "
            "a noise-free gyroscope: a floor below the real one), median over seeds:", ""]
    out += _table(summary, levels, sim_metrics[:3], ["crb_fit", "crb_all"], kind="magyc_synthetic")
    if yuan:
        out += ["", "### Yuan 2018's scenarios as 100 Hz streams", ""]
        out += _table(summary, yuan, sim_metrics, methods, kind="yuan_stream")
        out += ["", "Cramér-Rao floor (every reading):", ""]
        out += _table(summary, yuan, sim_metrics[:3], ["crb_all"], kind="yuan_stream")
    out += ["", "### The HMC5883L + MPU6050 recordings", "",
            "Axis maps (magnetometer; gyroscope): " + "; ".join(
                f"`{k}` = {v[0]}; {v[1]}" for k, v in AXIS_MAPS.items())
            + ". Gyro rate at each magnetometer reading: the MPU6050's rate averaged over the interval since the "
              "previous reading; timestamps as recorded. Gyro bias in °/s in the gyroscope's axes; the rest "
              "recording's mean rate is the reference.", ""]
    for (dataset, axis_map), raw in sorted(recs.items()):
        out += [f"**{dataset}, axes `{axis_map}`** (raw spread {fmt(raw, percent=True, interval=False)})", ""]
        out += _table(summary, {dataset: dataset.removeprefix("hmc5883l_")}, real_metrics, methods,
                      kind="recording", axis_map=axis_map)
        out.append("")
    return "\n".join(out) + "\n"
