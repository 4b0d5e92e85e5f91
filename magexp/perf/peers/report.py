"""The bench's figure and the text of its report section, both drawn from its summary rows
(:func:`.bench.summarise`): no number is typed here, every one is read from the rows."""

from __future__ import annotations

import matplotlib.pyplot as plt  # the Agg backend: chosen by magexp.artifacts.plots.style (imported with the report)
import numpy as np

from magexp.artifacts.comparisons import CONTRADICTED, HOLDS, NO_DIFFERENCE, UNDECIDED
from magexp.artifacts.report import PEERS_MARK
from magexp.perf.peers import claims as peer_claims
from magexp.perf.peers import measures
from magexp.perf.peers.magexp_side import LM_NFEV, SUBSET
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
    "crb_fit": "Cramér-Rao floor (the evenly spaced subset)", "crb_all": "Cramér-Rao floor (every reading)",
}
LEVELS = {"magyc_high": "WAM (high)", "magyc_mid": "MAM (mid)", "magyc_low": "LAM (low)",
          "magyc_tiny": "tiny", "magyc_cross": "cross"}


def pick(summary, **match) -> list[dict]:
    """The summary rows whose fields equal ``match``."""
    return [r for r in summary if all(r.get(k) == v for k, v in match.items())]


def one(summary, **match) -> dict | None:
    """The first summary row whose fields equal ``match`` (:func:`pick`), else None."""
    rows = pick(summary, **match)
    return rows[0] if rows else None


def methods_of(summary) -> list[str]:
    """The methods of :data:`LABELS` the summary holds (bounds left out), in their order."""
    present = {r["method"] for r in summary if r["side"] not in ("none", "bound")}
    return [m for m in LABELS if m in present]


def fmt(row: dict | None, stat: str = "median", digits: int = 3, interval: bool = True, percent: bool = False,
        halves: bool = False) -> str:
    """``median [lo, hi]`` of a summary row (``–`` for none); ``halves``: a recording's two halves, whose
    ``lo`` and ``hi`` are the two values, printed as ``median (halves lo and hi)``, never as an interval.
    """
    if row is None or not np.isfinite(row[stat]):
        return "–"
    scale, unit = (100.0, " %") if percent else (1.0, "")
    text = f"{row[stat] * scale:.{digits}g}{unit}"
    if interval and stat == "median" and np.isfinite(row["lo"]):
        lo, hi = row["lo"] * scale, row["hi"] * scale
        text += f" (halves {lo:.{digits}g} and {hi:.{digits}g})" if halves else f" [{lo:.{digits}g}, {hi:.{digits}g}]"
    return text


def _arrays(rows: list[dict | None], scale: float = 1.0) -> tuple[np.ndarray, list[np.ndarray]]:
    """Medians of summary ``rows`` (NaN for none) and their error bars (distances to ``lo`` and ``hi``)."""
    med, lo, hi = (np.array([r[k] if r else np.nan for r in rows]) * scale for k in ("median", "lo", "hi"))
    return med, [np.maximum(med - lo, 0), np.maximum(hi - med, 0)]


def _simulated_panel(ax, summary, methods: list[str], levels: list[str], metric: str, title: str, tol: float) -> None:
    """One metric on MAGYC's data: a marker per method and motion level, the Cramér-Rao floor per level."""
    x = np.arange(len(methods))
    for k, level in enumerate(levels):
        med, err = _arrays([one(summary, dataset=level, fit_on="all", method=m, metric=metric) for m in methods])
        bar = ax.errorbar(x + (k - (len(levels) - 1) / 2) * 0.22, med, yerr=err, fmt="o", ms=4, capsize=2,
                          label=LEVELS[level])
        floor = one(summary, dataset=level, method="crb_all", metric=metric)
        if floor is not None and np.isfinite(floor["median"]):
            ax.axhline(floor["median"], color=bar[0].get_color(), ls="--", lw=0.8,
                       label=f"{LEVELS[level]}: Cramér-Rao floor (every reading)")
    ax.axhline(tol, color="0.4", ls=":", lw=1, label="success threshold")
    ax.set_yscale("log")
    ax.set_ylabel(title, fontsize=8)
    ax.set_title(f"MAGYC's synthetic data, every reading to both sides:\n{title}", fontsize=9)
    ax.set_xticks(x, [LABELS[m] for m in methods], rotation=60, ha="right", fontsize=7)


def _recording_panel(ax, summary, methods: list[str]) -> None:
    """Held-out spread on the full sphere, timestamps as recorded and retimed, against the raw readings."""
    x = np.arange(len(methods))
    for k, (dataset, marker, label) in enumerate((("hmc5883l_full-sphere", "o", "timestamps as recorded"),
                                                  ("hmc5883l_full-sphere_retimed", "s", "retimed (constant-rate clocks)"))):
        med, err = _arrays([one(summary, dataset=dataset, axis_map="aligned", fit_on="halves", method=m,
                                metric="spread_held_out") for m in methods], 100.0)
        ax.errorbar(x + (k - 0.5) * 0.25, med, yerr=err, fmt=marker, ms=4, capsize=2, color=f"C{k + 3}", label=label)
    raw = one(summary, dataset="hmc5883l_full-sphere", axis_map="aligned", method="raw", metric="spread_in_sample")
    if raw:
        ax.axhline(raw["median"] * 100, color="0.3", ls="--", lw=1, label="raw readings")
    ax.set_yscale("log")
    ax.set_ylabel("held-out spread of |calibrated field|, std / mean (%)", fontsize=8)
    mag_axes = AXIS_MAPS["aligned"][0]
    ax.set_title(f"HMC5883L full sphere (magnetometer axes {mag_axes}):\nfit on one half, spread on the other",
                 fontsize=9)
    ax.set_xticks(x, [LABELS[m] for m in methods], rotation=60, ha="right", fontsize=7)


def figure(summary, path) -> None:
    """Three panels: soft-iron and hard-iron error on MAGYC's data per motion level, held-out spread on the
    full-sphere recording.
    """
    methods = methods_of(summary)
    levels = [d for d in LEVELS if pick(summary, dataset=d)]
    fig, axes = plt.subplots(1, 3, figsize=(13.5, 5.6), constrained_layout=True)
    _simulated_panel(axes[0], summary, methods, levels, "soft_iron_error", "soft-iron error (log-shape distance)",
                     measures.SOFT_TOL)
    _simulated_panel(axes[1], summary, methods, levels, "hard_iron_error", "hard-iron error / field", measures.HARD_TOL)
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower left", ncols=3, fontsize=7,
               title="MAGYC's data: median over seeds and 95 % CI of the median", title_fontsize=7)
    _recording_panel(axes[2], summary, methods)
    fig.legend(*axes[2].get_legend_handles_labels(), loc="outside lower right", ncols=2, fontsize=7,
               title="the recording: median of the two halves, bars to each half's value", title_fontsize=7)
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


#: the outcome of "magexp lm (gyro) is more accurate than X", in words
VERB = {HOLDS: "more accurate than", CONTRADICTED: "less accurate than", NO_DIFFERENCE: "not separated from",
        UNDECIDED: "not decidable at its n against"}
FULL, RETIMED = "hmc5883l_full-sphere", "hmc5883l_full-sphere_retimed"
#: the cells of a recording's held-out spread: the full sphere, axes aligned, fitted on each half
HALVES = {"kind": "recording", "axis_map": "aligned", "fit_on": ("first_half", "second_half")}
#: the methods of the full sphere's short table
SHOWN = ("magexp_lm_gyro", "magexp_ellipsoid", "magyc_nls", "magyc_nls_sg", "magyc_ifg", "twostep_hsi")


def _claim(text: str, test, evidence: str, **tags) -> dict:
    """A claim: its text, its test (:class:`magexp.artifacts.comparisons.Test`, decided by
    :func:`magexp.perf.peers.claims.adjust`) and evidence, and ``tags`` the headline picks claims by."""
    return {"text": text, "test": test, "result": "", "evidence": evidence, **tags}


def bases(args) -> dict[str, str]:
    """The two comparisons on MAGYC's data, ``fit_on`` -> the readings both sides were given, in words."""
    return {"all": f"the same {args.nsamples:,} readings", SUBSET: f"the same {args.n_fit:,} readings"}


def simulated_claims(frame, summary, args) -> list[dict]:
    """Per comparison (:func:`bases`: every reading to both sides, and magexp's readings to both) and motion level
    of MAGYC's data: the most accurate method, and magexp lm (gyro) against MAGYC-NLS (called directly, and, on
    every reading, as its example notebook calls it).
    """
    out = []
    for basis, readings in bases(args).items():
        for level in (d for d in LEVELS if pick(summary, dataset=d, fit_on=basis)):
            where = {"kind": "magyc_synthetic", "dataset": level, "fit_on": basis}
            tags = {"level": LEVELS[level], "basis": basis}
            methods = [m for m in methods_of(summary) if one(summary, method=m, **where)]
            best, test, tied = peer_claims.winner_test(frame, peer_claims.ERROR, methods, **where)
            best_v = peer_claims.values(frame, peer_claims.ERROR, method=best, **where)
            out.append(_claim(f"{LEVELS[level]}, {readings}: the most accurate method is {LABELS[best]}", test,
                              f"worse error {peer_claims.said(best_v)}"
                              + ("; not separated from " + ", ".join(LABELS[m] for m in tied) if tied else ""),
                              best=best, tied=tied, **tags))
            lm = peer_claims.values(frame, peer_claims.ERROR, method="magexp_lm_gyro", **where)
            for peer in ("magyc_nls", "magyc_nls_sg"):
                other = peer_claims.values(frame, peer_claims.ERROR, method=peer, **where)
                if len(lm) and len(other):
                    out.append(_claim(f"{LEVELS[level]}, {readings}: magexp lm (gyro) is more accurate than "
                                      f"{LABELS[peer]}", peer_claims.tested(lm, other),
                                      f"{peer_claims.said(lm)} vs {peer_claims.said(other)}", peer=peer, **tags))
    return out


def _held(frame, dataset: str, method: str, metric: str = "spread_held_out"):
    """The held-out spreads of ``method`` on ``dataset``, one per recording half."""
    return peer_claims.values(frame, metric, dataset=dataset, method=method, **HALVES)


def recording_claims(frame) -> list[dict]:
    """The full sphere (axes aligned), fitted on each half: magexp lm (gyro) against MAGYC-NLS as its notebook
    calls it, with the timestamps as recorded and retimed; what retiming does to each; the gyro bias.
    """
    out = []
    pct = {"scale": 100.0, "unit": " %"}
    for dataset, clock in ((FULL, "timestamps as recorded"), (RETIMED, "clocks retimed")):
        lm, nb = _held(frame, dataset, "magexp_lm_gyro"), _held(frame, dataset, "magyc_nls_sg")
        if len(lm) and len(nb):
            out.append(_claim(f"Full sphere, {clock}: magexp lm (gyro)'s held-out spread is below MAGYC-NLS, "
                              "notebook's", peer_claims.tested(lm, nb),
                              f"{peer_claims.said(lm, **pct)} vs {peer_claims.said(nb, **pct)}"))
    for method in ("magyc_nls", "magyc_nls_sg", "magexp_lm_gyro"):
        after, before = _held(frame, RETIMED, method), _held(frame, FULL, method)
        if len(after) and len(before):
            out.append(_claim(f"Full sphere: retiming the clocks lowers {LABELS[method]}'s held-out spread",
                              peer_claims.tested(after, before),
                              f"{peer_claims.said(before, **pct)} → {peer_claims.said(after, **pct)}", retimed=method))
    after, before = (_held(frame, d, "magexp_lm_gyro", "gyro_bias_vs_rest") for d in (RETIMED, FULL))
    if len(after) and len(before):
        out.append(_claim("Full sphere: retiming brings magexp lm (gyro)'s gyro bias closer to the rest recording's "
                          "mean rate", peer_claims.tested(after, before),
                          f"‖bias − rest‖ {peer_claims.said(before)} → {peer_claims.said(after)} °/s, fitted on each half"))
    return out


def _cell(row: dict | None, **opts) -> str:
    """A table cell of ``row`` without its interval."""
    return fmt(row, interval=False, **opts)


def spread_table(summary) -> list[str]:
    """The full sphere (axes aligned) per method: spread in sample and held out, recorded and retimed clocks, and
    the gyro bias against the rest recording.
    """
    lines = ["| method | in sample | held out, recorded | held out, retimed | ‖bias − rest‖ (°/s), recorded → retimed |",
             "|---|---|---|---|---|"]
    for m in SHOWN:
        cell = {d: {k: one(summary, dataset=d, axis_map="aligned", method=m, metric=k, fit_on=f)
                    for k, f in (("spread_in_sample", "all"), ("spread_held_out", "halves"),
                                 ("gyro_bias_vs_rest", "all"))} for d in (FULL, RETIMED)}
        if cell[FULL]["spread_held_out"] is None:
            continue
        bias = " → ".join(_cell(cell[d]["gyro_bias_vs_rest"]) for d in (FULL, RETIMED))
        lines.append(f"| {LABELS[m]} | {_cell(cell[FULL]['spread_in_sample'], percent=True)} | "
                     f"{fmt(cell[FULL]['spread_held_out'], percent=True, halves=True)} | "
                     f"{fmt(cell[RETIMED]['spread_held_out'], percent=True, halves=True)} | "
                     f"{bias if '–' not in bias else '–'} |")
    return lines


def _simulated_headline(claims: list[dict], args) -> str:
    """The headline's sentences on MAGYC's data, one per comparison (:func:`bases`): the winner per motion level,
    magexp lm (gyro) against MAGYC-NLS."""
    def against(basis: str, peer: str) -> str:
        return ", ".join(f"{VERB[c['result']]} it at {c['level']}" for c in claims
                         if c.get("peer") == peer and c.get("basis") == basis)

    out = [f"On MAGYC's own synthetic data both sides get the same readings and the same budget (magexp's lm at most "
           f"{LM_NFEV} evaluations, as MAGYC-LS, -NLS and -BFG), both ways."]
    for basis, readings in bases(args).items():
        said = "; ".join(f"{c['level']} {LABELS[c['best']]}, " + (
            "separated from every other" if c["result"] == HOLDS else
            f"not separated from {', '.join(LABELS[m] for m in c['tied'])}" if c["tied"] else
            f"{c['result']} against every other after Holm's correction")
            for c in claims if "best" in c and c["basis"] == basis)
        if not said:
            continue
        vs = [f"against MAGYC-NLS as its example notebook calls it (a Savitzky-Golay prefilter): "
              f"{against(basis, 'magyc_nls_sg')}" if against(basis, "magyc_nls_sg") else "",
              f"against MAGYC-NLS on the raw readings: {against(basis, 'magyc_nls')}"]
        which = (" (every reading)" if basis == "all" else
                 ", evenly spaced (magexp's fit; the gyroscope between them as one mean rate per interval)")
        out.append(f"On {readings}{which}, the most accurate method per motion "
                   f"level (lowest worse error of soft and hard iron) is: {said}. magexp's gyro-aided lm, "
                   + "; ".join(v for v in vs if v) + ".")
    return " ".join(out)


def _recording_headline(claims: list[dict], frame, summary) -> str:
    """The headline's sentence on the full sphere: the peer with the timestamps as recorded and retimed."""
    raw = one(summary, dataset=FULL, axis_map="aligned", method="raw", metric="spread_in_sample")
    nls, lm, nls_rt = (_held(frame, d, m) for d, m in ((FULL, "magyc_nls_sg"), (FULL, "magexp_lm_gyro"),
                                                         (RETIMED, "magyc_nls_sg")))
    retimed = [c["result"] for c in claims if c.get("retimed") == "magyc_nls_sg"]
    if not (raw and len(nls) and len(lm) and len(nls_rt) and retimed):
        return ""
    pct = {"scale": 100.0, "unit": " %"}
    cause = ("the recorded, bursty timestamps defeat the peer, not its method" if retimed[0] == HOLDS
             else "two halves of one recording cannot decide it" if retimed[0] == UNDECIDED
             else "retiming does not separate it")
    return (f" On the real full-sphere recording with its timestamps as recorded, MAGYC-NLS (notebook) leaves a "
            f"held-out spread of {peer_claims.said(nls, **pct)} (raw readings {fmt(raw, percent=True, interval=False)}), "
            f"magexp lm (gyro) {peer_claims.said(lm, **pct)}; with both clocks retimed to constant rates MAGYC-NLS "
            f"reaches {peer_claims.said(nls_rt, **pct)} ({retimed[0]}): {cause}. Figure `peers.png`.")


def headline(claims: list[dict], frame, summary, args) -> str:
    """The section's first paragraph: the claims' outcomes in words, every number read from the rows."""
    return "**Headline.** " + _simulated_headline(claims, args) + _recording_headline(claims, frame, summary)


def notes(frame, summary) -> list[str]:
    """The two magyc 1.0.0 bugs the bench found, and what magexp should learn, every number read from the rows."""
    out = []
    real = {"dataset": RETIMED, "axis_map": "aligned", "fit_on": "all", "method": "magyc_nls"}
    own, applied = one(summary, metric="own_output_spread", **real), one(summary, metric="spread_in_sample", **real)
    if own and applied:
        out.append(f"* magyc 1.0.0 bug: every method's returned `calibrated_magnetic_field` applies its matrix to "
                   "`magnetic_field.reshape(3, -1)` of the N x 3 readings, mixing the axes of different readings: on "
                   f"the retimed full sphere MAGYC-NLS's own output spreads {_cell(own, percent=True)}, its estimates "
                   f"applied to the readings {_cell(applied, percent=True)}. The bench applies every method's estimates "
                   "itself.")
    where = {"kind": "magyc_synthetic", "dataset": "magyc_high", "fit_on": "all"}
    theirs, ours = (peer_claims.values(frame, "soft_iron_error", method=m, **where)
                    for m in ("ellipsoid_fit", "magexp_ellipsoid"))
    if len(theirs) and len(ours):
        result, test = peer_claims.compare(ours, theirs)
        out.append("* magyc 1.0.0 bug: `ellipsoid_fit` returns the correction SI⁻¹ under the name `soft_iron`, and "
                   "transposes its eigenvector matrix before rebuilding it: its eigenvalues are right, its axes are "
                   "not (`tests/test_peers.py` checks the eigenvalues on an exact ellipsoid). On WAM's readings its "
                   f"soft-iron error is {peer_claims.said(theirs)}, magexp's ellipsoid fit's {peer_claims.said(ours)} "
                   f"(magexp lower: {result}, {test}).")
    bias = [one(summary, dataset=d, axis_map="aligned", fit_on="all", method="magexp_lm_gyro",
                metric="gyro_bias_vs_rest") for d in (FULL, RETIMED)]
    turn = [one(summary, dataset=d, axis_map="aligned", fit_on="all", method="magexp_lm_gyro",
                metric="gyro_consistency") for d in (FULL, RETIMED)]
    fit = [one(summary, dataset=d, axis_map="aligned", fit_on="all", method="magexp_lm_gyro",
               metric="spread_in_sample") for d in (FULL, RETIMED)]
    if all(bias) and all(turn) and all(fit):
        out.append("* What magexp should learn: the recording's timestamps are the arrival times of buffered bursts, "
                   "and magexp's `real_*` scenarios integrate the gyroscope over them. Retimed to constant-rate "
                   f"clocks, magexp lm (gyro)'s gyro bias against the rest recording goes {_cell(bias[0])} → "
                   f"{_cell(bias[1])} °/s and its calibrated directions follow the gyroscope to "
                   f"{_cell(turn[0])}° → {_cell(turn[1])}° (median over 1 s); fitted on every reading, its spread goes "
                   f"{_cell(fit[0], percent=True)} → {_cell(fit[1], percent=True)} (one fit each): the `real_*` scenarios should retime "
                   "bursty timestamps before integrating. What the peer can take: it differentiates the readings, so "
                   "it needs its prefilter and regular timestamps; its symmetric soft iron needs the axes aligned.")
    return out


def top(rows, summary, args) -> list[str]:
    """The part of the section the report shows (:data:`magexp.artifacts.report.PEERS_MARK` ends it): the
    headline, the claims with their outcomes, the full sphere's spreads and the notes.
    """
    frame = peer_claims.frame_of(rows)
    claims = peer_claims.adjust(simulated_claims(frame, summary, args) + recording_claims(frame))
    held = sum(c["result"] == HOLDS for c in claims)
    return [headline(claims, frame, summary, args), "",
            f"**Claims** ({held} of {len(claims)} hold; a comparison holds only where a one-sided paired Wilcoxon "
            f"test over seeds separates the two sides at alpha {peer_claims.ALPHA} after Holm's correction over "
            f"these {len(claims)} claims; at {args.seeds} seeds its smallest p is 1/{2 ** args.seeds}, on the recording's two halves 1/4: "
            "those cannot be decided; brackets: 95 % bootstrap interval of the median over seeds):", "",
            "| claim | result | evidence |", "|---|---|---|",
            *(f"| {c['text']} | {c['result']} | {c['evidence']} |" for c in claims), "",
            "**Full sphere, axes aligned** (held out: fit on one half, spread on the other; median of the two halves "
            "and each half's value):",
            "", *spread_table(summary), "", *notes(frame, summary)]


def section(rows, summary, args) -> str:
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
                    ("spread_held_out", "spread, held out (two halves)", ({"fit_on": "halves"}, {"percent": True, "halves": True})),
                    ("gyro_consistency", "gyro consistency (°, 1 s)", ({"fit_on": "all"}, {"interval": False})),
                    ("gyro_bias_x", "bias x (°/s)", ({"fit_on": "all"}, {"interval": False})),
                    ("gyro_bias_y", "bias y", ({"fit_on": "all"}, {"interval": False})),
                    ("gyro_bias_z", "bias z", ({"fit_on": "all"}, {"interval": False})),
                    ("gyro_bias_vs_rest", "‖bias − rest‖ (°/s)", ({"fit_on": "all"}, {"interval": False})),
                    ("own_output_spread", "peer's own calibrated output", ({"fit_on": "all"}, {"percent": True, "interval": False})),
                    ("seconds", "time (s)", ({"fit_on": "all"}, {"digits": 2, "interval": False}))]
    recs = {}
    for r in pick(summary, kind="recording", fit_on="all", method="raw"):
        recs[(r["dataset"], r["axis_map"])] = r
    out = ["## magexp beside MAGYC", "", "### Headline claims", "", *top(rows, summary, args), "", PEERS_MARK, "",
           f"Produced by `python -m magexp.perf.peers.bench` (MAGYC's generator: {args.seeds} seeds x "
           f"{args.nsamples} readings per motion level; Yuan's scenarios: {args.yuan_seeds} seeds at 100 Hz; "
           "figure `peers.png`). Medians over seeds with the 95 % bootstrap interval of the median in brackets. "
           "Soft iron compared as the unit-determinant shape (D Dᵀ)^½ (log-Euclidean distance), hard iron as a "
           f"fraction of the readings' sphere radius; a run succeeds when they are within {measures.SOFT_TOL} and "
           f"{measures.HARD_TOL} and its gyro bias, where it estimates one, within {measures.BIAS_TOL} °/s. "
           "*notebook*: the peer as its example notebook calls it, after a Savitzky-Golay filter (50 samples, "
           "order 2) of the magnetometer and the gyroscope.", "",
           "### MAGYC's synthetic data (its generator, its paper's settings)", "",
           f"Both sides on the same readings with the same budget, both ways: every reading, and the {args.n_fit} "
           "readings evenly spaced of magexp's fit (the gyroscope between them given to both as one mean rate per "
           "interval, the rotation preintegrated over every gyro sample). Budget: magexp's lm at most "
           f"{LM_NFEV} evaluations; magyc 1.0.0's MAGYC-LS and -NLS call scipy's least_squares with max_nfev = 1000, "
           "MAGYC-BFG gtsam with max_iter = 1000; MAGYC-IFG updates iSAM2 once per ten windows of 25 readings, with no "
           "iteration budget. The notebook's prefilter (50 samples: 5 s of the 10 Hz "
           "stream) is run on every reading only. Yuan's streams and the recordings: magexp's gyro-aided fit on "
           f"{args.n_fit} readings, the peer on every reading.", "",
           f"**On {bases(args)['all']} (every reading, both sides)**", ""]
    out += _table(summary, levels, sim_metrics, methods, kind="magyc_synthetic", fit_on="all")
    out += ["", f"**On {bases(args)[SUBSET]} (magexp's evenly spaced readings, both sides)**", ""]
    out += _table(summary, levels, sim_metrics, methods, kind="magyc_synthetic", fit_on=SUBSET)
    out += ["", "The Cramér-Rao floor of the gyro-aided problem (magexp.core.bounds at the truth, Gaussian magnetometer noise, "
            "a noise-free gyroscope: a floor below the real one), median over seeds:", ""]
    out += _table(summary, levels, sim_metrics[:3], ["crb_fit", "crb_all"], kind="magyc_synthetic", fit_on="all")
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
