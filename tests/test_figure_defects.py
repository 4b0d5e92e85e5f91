"""Every artifact's figure, drawn from its committed CSV under ``results/`` (no run), is free of the
defects a reader sees: an empty panel, text printed over text, a colour bar naming another column
than the one drawn, a legend of raw override strings (:mod:`magexp.artifacts.plots.check`)."""

from __future__ import annotations

import pandas as pd
import pytest

import numpy as np
from omegaconf import OmegaConf

from magexp.artifacts.plan import paper_specs
from magexp.paths import RESULTS
from magexp.artifacts.kinds import kind
from magexp.artifacts.kinds.heatmap import bound_ratio
from magexp.artifacts.plots.check import colorbar_mismatch, defects, empty_axes, legend_defects, overlapping_text, raw_legends
from magexp.artifacts.plots.final import level_span
from magexp.artifacts.plots.style import colorbar, drawn_from, plt, shared_legend
from magexp.artifacts.paper_spec import papers


#: the figure that stands for its plot kind in ``make test`` (the quickest of the kind to lay out);
#: every other figure is a ``full`` case (``make test-full``), and is checked whenever a reproduction
#: draws it into ``results/`` (:func:`magexp.artifacts.reproduce.draw` prints each defect it finds)
KIND_CHECK = {"convergence": "ding2024_fig3", "estimates": "yan2022_table_mockup", "field": "ding2024_fig6",
              "final": "benchmark_noise", "heatmap": "benchmark_objective", "parameters": "yuan2018_table5",
              "recording": "real_table7", "recording_spread": "real_benchmark", "speed": "benchmark_speed",
              "sphere": "yuan2018_fig6", "trace": "yan2022_fig4", "tuning": "ding2024_ext_pso_tuning"}


def committed():
    """Every artifact whose CSV is committed (recordings' artifacts: when they were drawn)."""
    return [pytest.param(spec, id=spec.name, marks=[] if spec.name in KIND_CHECK.values() else [pytest.mark.full])
            for paper in papers() for spec in paper_specs(paper) if (RESULTS / paper / f"{spec.name}.csv").is_file()]


@pytest.mark.parametrize("spec", committed())
def test_figure_has_no_visible_defect(spec):
    frame = pd.read_csv(RESULTS / spec.paper / f"{spec.name}.csv")
    fig = kind(spec.kind).draw(frame, spec)
    try:
        assert defects(fig) == []
    finally:
        plt.close(fig)


def test_every_artifact_with_results_is_checked():
    names = {p.id for p in committed()}
    assert {"ding2024_table_rms", "yuan2018_fig8", "yan2022_table_sim", "benchmark_heatmap"} <= names
    kind_of = {spec.name: spec.kind for paper in papers() for spec in paper_specs(paper)}
    assert set(KIND_CHECK) == set(kind_of.values())  # a new kind needs its figure checked in make test
    assert all(kind_of[name] == kind for kind, name in KIND_CHECK.items())


def test_a_reproduction_into_results_names_each_defect_of_a_figure_it_draws(tmp_path, monkeypatch, capsys):
    """The per-figure check where every figure is made: drawn into ``results/``, a figure's defects are
    printed as warnings; drawn elsewhere (exploration, the smoke runs) it is not checked."""
    from magexp.artifacts import reproduce
    from magexp.artifacts.plots import memo, style

    spec = next(s for s in paper_specs("yan2022") if s.name == "yan2022_table_mockup")
    csv = RESULTS / spec.paper / f"{spec.name}.csv"
    monkeypatch.setattr(reproduce, "RESULTS", tmp_path / "results")
    monkeypatch.setattr(memo, "root", lambda: tmp_path / "figures-cache")
    monkeypatch.setattr(style, "save", lambda fig, path: plt.close(fig) or [])
    module = kind(spec.kind)
    real_draw = module.draw

    def with_a_defect(frame, spec):
        fig = real_draw(frame, spec)
        fig.add_axes((0.4, 0.4, 0.2, 0.2)).set_title("nothing here")
        return fig

    monkeypatch.setattr(module, "draw", with_a_defect)
    for out in (tmp_path / "explore", tmp_path / "results" / "yan2022"):
        out.mkdir(parents=True)
        capsys.readouterr()
        reproduce.draw(spec, csv, out, force=True)
        warned = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("warning: figure yan2022_table_mockup")]
        assert bool(warned) == (out.parent.name == "results") and (not warned or any("'nothing here'" in ln for ln in warned))


# the checks themselves, on figures built to have (or not have) each defect

def test_an_axes_with_only_reference_lines_is_empty():
    fig, (a, b, c) = plt.subplots(1, 3)
    a.axhline(0.0)
    a.plot([0, 1], [float("nan")] * 2)
    b.plot([0, 1], [1, 2])
    c.set_visible(False)  # deliberately hidden: not a defect
    assert len(empty_axes(fig)) == 1 and "axes 0" in empty_axes(fig)[0]
    plt.close(fig)


def test_a_title_over_a_label_overlaps_and_apart_does_not():
    fig, ax = plt.subplots(figsize=(4, 3), layout="constrained")
    ax.plot([0, 1], [0, 1])
    ax.set_title("a title")
    ax.set_ylabel("a label")
    assert overlapping_text(fig) == []
    ax.text(0.5, 1.02, "printed over the title", transform=ax.transAxes, ha="center")
    assert any("title" in d for d in overlapping_text(fig))
    plt.close(fig)


def test_a_colour_bar_must_name_the_column_it_is_drawn_from():
    fig, ax = plt.subplots()
    image = drawn_from(ax.imshow([[1.0, 2.0]]), "gram_error_ratio")
    colorbar(image, ax, column="offset_error_ratio", label="log10 offset error / sqrt(tr CRB) (median over seeds)")
    assert any("drawn from 'gram_error_ratio'" in d for d in colorbar_mismatch(fig))
    fig, ax = plt.subplots()
    image = drawn_from(ax.imshow([[1.0, 2.0]]), "bound_ratio")
    colorbar(image, ax, column="bound_ratio", label="log10 RMS over seeds")  # not the column's words
    assert any("does not name" in d for d in colorbar_mismatch(fig))
    fig, ax = plt.subplots()
    fig.colorbar(ax.imshow([[1.0, 2.0]]), ax=ax).set_label("anything")  # records nothing
    assert any("does not record" in d for d in colorbar_mismatch(fig))
    plt.close("all")


def test_raw_override_strings_in_a_legend_are_found():
    fig, ax = plt.subplots()
    ax.plot([0, 1], label="lm, scenario=real_hmc5883l_full_sphere, window=null")
    ax.plot([0, 1], label="lm, A = 2 nT")
    ax.legend()
    assert len(raw_legends(fig)) == 1
    plt.close(fig)


def test_two_series_in_one_colour_and_an_undrawn_entry_are_found():
    fig, ax = plt.subplots()
    ax.plot([0, 1], [1, 2], color="C0", label="a")
    ax.plot([0, 1], [2, 3], color="C0", label="b")
    ax.plot([0, 1], [float("inf")] * 2, color="C1", label="bound")
    ax.legend()
    found = legend_defects(fig)
    assert any("'a' and 'b' look the same" in d for d in found)
    assert any("'bound': nothing of it is drawn" in d for d in found)
    plt.close(fig)


# what the figures draw

def test_the_bound_ratio_is_over_the_successful_runs_only():
    """Two failed runs of 40 with huge errors must not move the accuracy (issue 18: 1518 vs 0.983)."""
    ratios = np.r_[np.full(38, 0.98), 7000.0, 8000.0]
    runs = pd.DataFrame({"offset_error_ratio": ratios, "succeeded": np.r_[np.ones(38), 0.0, 0.0]})
    value, lo, hi = bound_ratio(runs)
    assert value == pytest.approx(0.98) and lo <= 0.98 <= hi
    unjudged = runs.assign(succeeded=np.nan)  # no truth: every run counts
    assert bound_ratio(unjudged)[0] > 1000


def test_final_draws_the_papers_values_and_ratios():
    spec = OmegaConf.create({"title": "t", "kind": "final", "plot": {"x": "scenario.noise", "hue": "estimator"},
                             "summarise": [{"quantity": "final_rms", "metric": "fun"}],
                             "ratios": [{"quantity": "improvement_ratio", "metric": "fun",
                                         "numerator": {"estimator": "pso"}, "denominator": {"estimator": "ipso"}}],
                             "reported": [{"quantity": "final_rms", "match": {"estimator": "pso", "scenario.noise": 2},
                                           "value": 8.35},
                                          {"quantity": "improvement_ratio", "match": {"scenario.noise": 2},
                                           "value": 14.4}]})
    rows = [{"scenario.noise": a, "estimator": e, "objective": "scalar", "metric": "fun", "median": 0.6 * a,
             "q25": 0.5 * a, "q75": 0.7 * a} for a in (2, 5) for e in ("pso", "ipso")]
    rows += [{"scenario.noise": a, "estimator": "pso / ipso", "objective": "scalar", "metric": "improvement_ratio",
              "median": 1.0, "q25": 0.9, "q75": 1.1} for a in (2, 5)]
    fig = kind("final").draw(pd.DataFrame(rows), spec)
    rms, ratio = fig.axes[:2]
    diamonds = [ln for ax in (rms, ratio) for ln in ax.lines if ln.get_marker() == "D"]
    assert sorted(float(ln.get_ydata()[0]) for ln in diamonds) == [8.35, 14.4]
    assert ratio.get_ylabel() == "improvement ratio" and defects(fig) == []
    plt.close(fig)


def test_final_sets_log_axes_per_metric_and_draws_the_floors_over_the_lines():
    """``plot.ylog: {rms_ratio: false}``: the RMS on a log axis, its ratio to the Cramér-Rao floor on a linear
    one with the floor at 1; the floors are drawn over the lines that run on them (benchmark_noise)."""
    spec = OmegaConf.create({"title": "t", "kind": "final",
                             "plot": {"x": "scenario.noise", "hue": "estimator", "metric": ["fun", "rms_ratio"],
                                      "ylog": {"rms_ratio": False}}})
    rows = [{"scenario.noise": a, "estimator": e, "objective": "scalar", "metric": m, "noise_floor": 0.3 * a,
             "rms_bound": 0.29 * a, "median": 0.3 * a if m == "fun" else 1.01, "q25": 0.29 * a if m == "fun" else 0.98,
             "q75": 0.31 * a if m == "fun" else 1.03} for a in (2, 5, 10) for e in ("pso", "lm") for m in ("fun", "rms_ratio")]
    fig = kind("final").draw(pd.DataFrame(rows), spec)
    rms, ratio = fig.axes[:2]
    assert (rms.get_yscale(), ratio.get_yscale()) == ("log", "linear")
    floor = [ln for ln in ratio.lines if ln.get_label() == "Cramér-Rao floor (Gaussian)"]
    assert len(floor) == 1 and list(floor[0].get_ydata()) == [1.0, 1.0]
    data_z = max(c.get_zorder() for c in rms.containers for c in [c.lines[0]])
    assert all(ln.get_zorder() > data_z for ln in rms.lines if ln.get_label() in ("noise floor", "Cramér-Rao floor (Gaussian)"))
    assert defects(fig) == []
    plt.close(fig)


@pytest.mark.parametrize("per_family", [1, 2])
def test_tuning_gives_every_setting_its_own_named_tick(per_family):
    """One setting per family (an ablation's variants): the tick is the family's words; several (mode 3's
    arcs): each setting has its own tick, its values under it and its family's words (with the keys its
    settings share) once below them, so no legend has to tell them apart (yuan2018_ext_readings drew two
    arcs under one tick)."""
    spec = OmegaConf.create({"title": "t", "kind": "tuning", "plot": {}})
    rows = [{"scenario": "s", "family": fam, "family_label": fam.upper(), "label": f"w = {k}" if per_family > 1 else fam,
             "median": 1.0 + k, "q25": 0.9, "q75": 2.0, "success_rate": 0.9, "n_seeds": 30, "default": False, "role": "",
             "metric": "fun"} for fam in ("pso", "ipso", "ipso_w") for k in range(per_family)]
    fig = kind("tuning").draw(pd.DataFrame(rows), spec)
    assert [t.get_text() for legend in fig.legends for t in legend.get_texts()] == []
    families = [t.get_text() for t in fig.axes[0].get_xticklabels()]
    settings = [t.get_text() for t in fig.axes[0].get_xticklabels(minor=True)]
    if per_family == 1:
        assert families == ["PSO", "IPSO", "IPSO_W"] and set(settings) == {""}
    else:
        assert families == ["PSO: w", "IPSO: w", "IPSO_W: w"] and settings == ["0", "1"] * 3
    assert len(set(fig.axes[0].get_xticks(minor=True))) == len(rows)
    assert defects(fig) == []
    plt.close(fig)


def test_tuning_words_stay_apart_with_long_labels_titles_and_many_settings():
    """yuan2018_ext_turns and ding2024_ext_ablation_readings: a y label longer than its panel ran into the
    title, slanted ticks ("RDPSO: arc (deg) = 90") into the next panel's label, and a label repeated the
    family ("PSO: variant = PSO, boundary = reflect, iterations = 400")."""
    spec = OmegaConf.create({"title": "A long title " * 12, "kind": "tuning",
                             "plot": {"ylabel": "median largest |b error| (mG); bar: IQR",
                                      "names": {"s0": "X, then Y (mode 3)"}}})
    rows = [{"scenario": f"s{j}", "family": fam, "family_label": words, "label": f"variant = {words}, boundary = {b}, "
             f"iterations = {n}", "median": 1.0 + k, "q25": 0.9, "q75": 2.0, "success_rate": 0.5, "n_seeds": 30,
             "default": k == 0, "role": "", "metric": "fun"}
            for j in range(3) for fam, words in (("rdpso", "RDPSO"), ("local", "optimum of eq 8"))
            for k, (b, n) in enumerate((("reflect", 400), ("clip", 800), ("random", 1600)))]
    fig = kind("tuning").draw(pd.DataFrame(rows), spec)
    assert defects(fig) == []
    assert fig.axes[0].get_title() == "X, then Y (mode 3)"
    assert [t.get_text() for t in fig.axes[0].get_xticklabels(minor=True)][:3] == ["reflect\n400", "clip\n800", "random\n1600"]
    assert fig.axes[0].get_xticklabels()[1].get_text().replace("\n", " ") == "optimum of eq 8: boundary, iterations"
    plt.close(fig)


def test_tuning_draws_a_success_rate_of_zero_and_marks_the_default():
    """A success rate of 0 is a bar of no height: it is marked on the axis with its count (yuan2018_ext_turns'
    90-degree turns); the default setting is a star on top and an outlined bar below, and the legend says so."""
    spec = OmegaConf.create({"title": "t", "kind": "tuning", "plot": {}})
    rows = [{"scenario": "s", "family": "rdpso", "family_label": "RDPSO", "label": f"arc (deg) = {a}", "median": m,
             "q25": m / 2, "q75": m * 2, "success_rate": r, "n_seeds": 30, "default": a == 180, "role": "", "metric": "fun"}
            for a, m, r in ((90, 30.0, 0.0), (180, 0.2, 0.7), (270, 0.2, 0.9))]
    fig = kind("tuning").draw(pd.DataFrame(rows), spec)
    top, bottom = fig.axes[0], fig.axes[1]
    assert [t.get_text() for t in bottom.texts] == ["0 of 30"]
    zero_x = bottom.get_xticks(minor=True)[0]
    assert any(ln.get_linewidth() >= 3 and min(ln.get_xdata()) < zero_x < max(ln.get_xdata())
               and set(ln.get_ydata()) == {0} for ln in bottom.lines)
    outlined = [p for p in bottom.patches if p.get_linewidth() > 0]
    assert len(outlined) == 1 and outlined[0].get_height() == pytest.approx(0.7)
    stars = [c for c in top.collections if c.get_sizes()[0] == 90]
    assert len(stars) == 1
    assert any("default" in t.get_text() for legend in fig.legends for t in legend.get_texts())
    assert defects(fig) == []
    plt.close(fig)


def test_a_calibration_figure_shows_a_successful_run_and_says_so():
    from types import SimpleNamespace

    from magexp.artifacts.kinds.field import shown_seed

    table = pd.DataFrame({"cell": [0, 0, 0, 1, 1], "seed": [0, 1, 2, 0, 1],
                          "succeeded": [0.0, 1.0, 1.0, 0.0, 0.0]})
    runs = SimpleNamespace(table=table, outputs={(c, s): None for c, s in zip(table.cell, table.seed)})
    assert shown_seed(runs, 0) == (1, "succeeded")  # seed 0 failed: not shown as "a calibration"
    assert shown_seed(runs, 1) == (0, "failed")  # none succeeded: the first, named as failed
    runs.table = table.assign(succeeded=np.nan)
    assert shown_seed(runs, 0) == (0, "not judged")


def test_scenario_names_are_readable_in_legends_and_ticks():
    """yuan2018_table3 printed ``rdpso, yuan2018_mode1``: one readable name for every kind that labels
    a scenario (the parameter tables and the recordings' figures)."""
    from magexp.artifacts.kinds.parameters import cell_label
    from magexp.artifacts.plots.style import scenario_label

    spec = OmegaConf.create({"plot": {}})
    assert cell_label({"scenario": "yuan2018_mode1"}, "rdpso", spec) == "rdpso, mode 1"
    assert [scenario_label(s) for s in ("ding2024_exp2", "yuan2018_adis16488", "real_hmc5883l_rotate_ccw_around_x",
                                        "real_fxos8700")] == ["exp 2", "adis16488", "rotate ccw around x", "fxos8700"]


def test_a_symlog_axis_from_zero_ticks_zero_then_the_decades_above_linthresh():
    """yuan2018_ext_noise printed "0" and "10⁻²" side by side (a decade inside the linear part); the
    legend names what a hue value means (``plot.names``), not its config name."""
    from magexp.artifacts.plots.final import symlog_ticks

    assert symlog_ticks(pd.Series([0, 0.05, 2.0]), 0.05) == [0.0, 0.1, 1.0]
    assert symlog_ticks(pd.Series([0, 1e-12, 1e-6]), 1e-12) == [0.0] + [10.0 ** k for k in range(-12, -5)]
    spec = OmegaConf.create({"title": "t", "kind": "final", "plot": {"x": "scenario.noise", "metric": "fg", "xscale": "symlog",
                                                                     "linthresh": 0.05, "names": {"local": "eq 8 minimised"},
                                                                     "targets": {"fg": 1.5}},
                             "summarise": [{"quantity": "F_g", "metric": "fg"}]})
    rows = [{"scenario.noise": a, "estimator": "local", "objective": "vector", "metric": "fg", "median": 1 + a,
             "q25": 0.9 + a, "q75": 1.1 + a} for a in (0, 0.05, 0.1, 1, 2)]
    fig = kind("final").draw(pd.DataFrame(rows), spec)
    ax = fig.axes[0]
    assert list(ax.get_xticks()) == [0.0, 0.1, 1.0]
    legends = [*fig.legends, *(a.get_legend() for a in fig.axes if a.get_legend() is not None)]
    assert "eq 8 minimised" in [t.get_text() for legend in legends for t in legend.get_texts()]
    assert defects(fig) == []
    plt.close(fig)


# issue 32: the defects of the listed figures, each caught or prevented by what it is

def test_a_config_name_in_a_legend_title_or_table_header_is_found():
    """yan2022_fig3's legend read ``yan2022_paper_mockup``; a case's tick label may name its scenario."""
    from magexp.artifacts.plots.check import raw_names

    fig, (a, b) = plt.subplots(1, 2)
    a.plot([0, 1], label="Be1 (yan2022_paper_mockup)")
    a.plot([0, 1], [1, 0], label="Be1 (the paper's K, Bp)")
    a.legend()
    b.table(cellText=[["1"]], colLabels=["yan2022_paper_sim"], loc="center")
    b.set_xticks([0], ["ding2024_exp1"])
    found = raw_names(fig)
    assert len(found) == 2 and all("yan2022_paper" in d for d in found)
    plt.close(fig)


def test_a_marker_cut_by_the_axes_edge_is_found_and_a_padded_symlog_axis_draws_it_whole():
    """yan2022_fig_noise drew the paper's diamonds at x = 100, on the right edge, and the points at 0 on
    the left one."""
    from magexp.artifacts.plots.check import clipped_markers

    fig, ax = plt.subplots()
    ax.plot([0, 1, 2], [1, 2, 3], "o")
    ax.plot([2], [2], "D", ms=8, label="paper's value")
    ax.set_xlim(0, 2)
    fig.draw_without_rendering()
    found = clipped_markers(fig)
    assert len(found) == 1 and "3 marker(s)" in found[0] and "paper's value" in found[0]
    ax.set_xlim(-0.2, 2.2)
    fig.draw_without_rendering()
    assert clipped_markers(fig) == []
    plt.close(fig)
    spec = OmegaConf.create({"title": "t", "kind": "final", "plot": {"x": "scenario.noise", "metric": "k_error", "xscale": "symlog",
                                                                     "linthresh": 1.0},
                             "summarise": [{"quantity": "k_error", "metric": "k_error"}],
                             "reported": [{"quantity": "k_error", "match": {"scenario.noise": 100}, "value": 1e-4}]})
    rows = [{"scenario.noise": a, "estimator": "kf", "objective": "ship", "metric": "k_error", "median": 1e-6 * (1 + a),
             "q25": 0.9e-6 * (1 + a), "q75": 1.1e-6 * (1 + a)} for a in (0, 0.3, 1, 10, 100)]
    fig = kind("final").draw(pd.DataFrame(rows), spec)
    assert defects(fig) == [] and fig.axes[0].get_xlim()[0] < 0
    plt.close(fig)


def test_a_log_axis_labelled_at_one_decade_is_found_and_tidy_ticks_label_its_range():
    """benchmark_speed labelled its ratio axis only at 0.9 and 1 while points reached 1.8."""
    from magexp.artifacts.plots.check import unlabelled_log_range
    from magexp.artifacts.plots.style import narrow_log_ticks, tidy_log_axes

    fig, ax = plt.subplots()
    ax.plot([1e-3, 1e-2], [0.88, 1.8], "o")
    ax.set_yscale("log")
    ax.set_ylim(0.85, 1.9)
    fig.draw_without_rendering()
    assert len(unlabelled_log_range(fig)) == 1
    tidy_log_axes(fig)
    fig.draw_without_rendering()
    assert unlabelled_log_range(fig) == []
    assert [t.get_text() for t in ax.get_yticklabels() if ax.get_ylim()[0] <= t.get_position()[1] <= 1.9] == ["0.9", "1", "1.2", "1.5"]
    plt.close(fig)
    assert narrow_log_ticks(0.5, 2.0) == [0.5, 1.0, 2.0]
    assert narrow_log_ticks(0.5, 2.0, at_least=5) == [0.5, 0.7, 1.0, 1.5, 2.0]
    assert len(narrow_log_ticks(0.56, 0.601)) >= 2  # too narrow for any mantissa set: round values


def test_text_below_the_readable_size_is_found():
    from magexp.artifacts.plots.check import small_text

    fig, ax = plt.subplots()
    ax.plot([0, 1])
    ax.text(0.5, 0.5, "7 px", fontsize=6)
    assert len(small_text(fig)) == 1
    plt.close(fig)


def _heatmap_frame():
    rows = [{"case": c, "estimator": e, "bound_ratio": v, "bound_ratio_lo": 0.9 * v, "bound_ratio_hi": 1.1 * v,
             "success_rate": 1.0, "n_seeds": 40, "n_failed": 0}
            for c, e, v in (("a", "lm", 1.8), ("a", "pso", 0.8), ("b", "lm", 1.0), ("b", "pso", 1.2))]
    rows += [{"case": "mockup", "estimator": e, "bound_ratio": np.nan, "bound_ratio_lo": np.nan, "bound_ratio_hi": np.nan,
              "success_rate": 1.0, "n_seeds": 40, "n_failed": 0} for e in ("lm", "pso")]
    return pd.DataFrame(rows)


def test_a_heat_map_colours_each_cell_by_the_ratio_it_prints_on_a_bar_labelled_in_ratios():
    """benchmark_heatmap coloured log10 of the ratio, printed the ratio in 6 pt and kept a column of "—"."""
    spec = OmegaConf.create({"title": "t", "kind": "heatmap", "plot": {"metric": "bound_ratio"}})
    fig = kind("heatmap").draw(_heatmap_frame(), spec)
    ax, bar = fig.axes
    image = ax.images[0]
    printed = [float(t.get_text().split("\n")[0]) for t in ax.texts]
    assert sorted(np.ma.compressed(image.get_array()).tolist()) == sorted(printed) == [0.8, 1.0, 1.2, 1.8]
    assert image.norm(1.0) == pytest.approx(0.5) and image.norm(2.0) == pytest.approx(1.0)  # 1 at the centre
    assert [t.get_text() for t in ax.get_xticklabels()] == ["a", "b"]  # no column without a value
    assert [t.get_text() for t in bar.get_yticklabels()] == ["0.5", "0.7", "1", "1.5", "2"]
    assert min(t.get_fontsize() for t in ax.texts) >= 8 and defects(fig) == []
    plt.close(fig)


def test_a_panel_of_round_off_errors_draws_zero_and_says_so():
    """ding2024_fig6's A = 0 panel drew the ±1e-9 the CSV writes for round-off, as if it were data."""
    spec = OmegaConf.create({"title": "t", "kind": "field", "plot": {"panels": "scenario.noise", "quantity": "error"}})
    frame = pd.DataFrame({"scenario.noise": [0] * 4 + [2] * 4, "reading": list(range(4)) * 2, "seed": 0,
                          "outcome": "succeeded", "error": [1e-9, -1e-9, 0.0, 1e-9, 0.5, -1.2, 0.3, 0.9]})
    fig = kind("field").draw(frame, spec)
    exact, noisy = fig.axes
    assert list(exact.lines[0].get_ydata()) == [0.0] * 4 and "round-off" in exact.get_title()
    assert exact.get_ylim() == noisy.get_ylim() and "RMS" in noisy.get_title()
    plt.close(fig)


def test_a_table_prints_a_stated_value_in_the_estimators_cell_and_no_empty_column():
    """yan2022_table_sim had a "paper states" column empty on 14 of its 16 rows."""
    spec = OmegaConf.create({"title": "t", "kind": "estimates", "plot": {"names": {"paper_sim": "paper's estimate"}},
                             "summarise": [{"quantity": "k_error", "metric": "k_error"}],
                             "reported": [{"quantity": "k_error", "match": {"estimator": "kf"}, "value": 1e-4}]})
    frame = pd.DataFrame([{"estimator": e, "quantity": q, "median": v, "q25": v, "q75": v, "truth": t, "n_seeds": 30}
                          for e, q, v, t in (("paper_sim", "K11", 0.9499, 0.95), ("kf", "K11", 0.95, 0.95),
                                             ("paper_sim", "k_error", 6e-4, np.nan), ("kf", "k_error", 4e-3, np.nan))])
    fig = kind("estimates").draw(frame, spec)
    cells = fig.axes[0].tables[0].get_celld()
    header = [cells[(0, c)].get_text().get_text() for c in range(3)]
    assert header == ["truth", "paper's estimate", "kf"]
    assert cells[(2, 2)].get_text().get_text().endswith("paper: 0.0001") and defects(fig) == []
    plt.close(fig)


def test_final_draws_a_papers_levels_in_the_panels_they_match():
    """ding2024_ext_pso_settings did not draw the paper's PSO values, the point of the figure."""
    spec = OmegaConf.create({"title": "t", "kind": "final",
                             "plot": {"x": "w", "panels": "scenario.noise",
                                      "levels": [{"label": "paper's PSO value", "match": {"scenario.noise": 2}, "value": 8.35},
                                                 {"label": "paper's PSO value", "match": {"scenario.noise": 5}, "value": 87.7}]}})
    rows = [{"w": w, "scenario.noise": a, "estimator": "pso", "objective": "scalar", "metric": "fun", "median": a * w,
             "q25": a * w, "q75": a * w} for a in (2, 5, 10) for w in (0.4, 0.9)]
    fig = kind("final").draw(pd.DataFrame(rows), spec)
    drawn = [[ln.get_ydata()[0] for ln in ax.lines if ln.get_label() == "paper's PSO value"] for ax in fig.axes[:3]]
    assert drawn == [[8.35], [87.7], []] and defects(fig) == []
    plt.close(fig)


def test_final_draws_a_level_of_one_x_at_that_x_only_and_keeps_the_x_range():
    """ding2024_ext_pso_readings drew the paper's PSO value at A = 2 nT across A = 5 and 10 nT too."""
    spec = OmegaConf.create({"title": "t", "kind": "final",
                             "plot": {"x": "scenario.noise", "hue": "estimator",
                                      "levels": [{"label": "paper's PSO value", "match": {"scenario.noise": a}, "value": v}
                                                 for a, v in ((2, 8.35), (5, 87.7), (10, 162.26))]}})
    rows = [{"scenario.noise": a, "estimator": "pso", "objective": "scalar", "metric": "fun", "median": 10.0 * a,
             "q25": 9.0 * a, "q75": 11.0 * a} for a in (2, 5, 10)]
    fig = kind("final").draw(pd.DataFrame(rows), spec)
    ax = fig.axes[0]
    spans = sorted((ln.get_xdata()[0], ln.get_xdata()[1], ln.get_ydata()[0]) for ln in ax.lines
                   if ln.get_label() == "paper's PSO value")
    assert [v for *_, v in spans] == [8.35, 87.7, 162.26]
    assert all(lo < a < hi for (lo, hi, _), a in zip(spans, (2, 5, 10)))
    assert all(hi < nxt_lo for (_, hi, _), (nxt_lo, _, _) in zip(spans, spans[1:]))  # each only at its own A
    left, right = ax.get_xlim()
    assert spans[0][0] >= left and spans[-1][1] <= right and right < 10.5  # the lines do not widen the axis
    assert defects(fig) == []
    plt.close(fig)


def test_level_span_is_centred_on_its_x_on_linear_and_log_axes():
    assert level_span(5, [2, 5, 10]) == pytest.approx((3.8, 7.0))
    assert level_span(10, [2, 5, 10]) == pytest.approx((8.0, 10.4))
    lo, hi = level_span(10, [1, 10, 100], log=True)
    assert (lo, hi) == pytest.approx((10 ** 0.6, 10 ** 1.4))
    assert level_span(3, [3]) == pytest.approx((2.5, 3.5))


def test_a_legend_below_the_panels_fits_the_figures_width():
    """Long legend entries (ding2024_ext_pso_readings' sourced readings) in four columns made the legend,
    and with it the saved figure, twice as wide as the panel: fewer columns, never wider than the figure."""
    fig, axes = plt.subplots(1, 1, figsize=(6.0, 4.2), layout="constrained")
    for k in range(8):
        axes.plot([0, 1], [k, k], label=f"a long legend entry naming a source and its settings, number {k}")
    legend = shared_legend(fig, [axes])
    renderer = fig.canvas.get_renderer()
    assert legend.get_window_extent(renderer).width <= fig.bbox.width
    plt.close(fig)
    fig, axes = plt.subplots(1, 1, figsize=(6.0, 4.2), layout="constrained")
    for k in range(8):
        axes.plot([0, 1], [k, k], label=f"line {k}")
    assert shared_legend(fig, [axes])._ncols == 4  # short entries keep their four columns
    plt.close(fig)


def test_the_distances_from_least_squares_agree_with_the_runs():
    """yan2022_fig3's lower row (|estimate - ls| per parameter) recomputes the runs' own k_vs_ls and
    bp_vs_ls (largest distance of K and of Bp from least squares) for the filter's last step and for the
    paper's values: what the caption discusses is drawn from the same numbers."""
    frame = pd.read_csv(RESULTS / "yan2022" / "yan2022_fig3.csv")
    runs = pd.read_csv(RESULTS / "yan2022" / "yan2022_fig3_runs.csv").set_index("estimator")
    last = frame[(frame.kind == "distance") & (frame.step == frame.step.max())].set_index("parameter")["median"]
    paper = frame[frame.kind == "distance_reference"].set_index("parameter")["median"]
    for est, dist in (("kf", last), ("yan2022_paper_mockup", paper)):
        assert dist.filter(like="K").max() == pytest.approx(runs.loc[est, "k_vs_ls"], rel=1e-4)
        assert dist.filter(like="Bp").max() == pytest.approx(runs.loc[est, "bp_vs_ls"], rel=1e-4)
