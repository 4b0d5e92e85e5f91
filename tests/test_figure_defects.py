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
from magexp.artifacts.plots import kind_module
from magexp.artifacts.plots.benchmark_table import bound_ratio
from magexp.artifacts.plots.check import colorbar_mismatch, defects, empty_axes, legend_defects, overlapping_text, raw_legends
from magexp.artifacts.plots.style import colorbar, drawn_from, plt
from magexp.artifacts.spec import papers


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
    fig = kind_module(spec.kind).draw(frame, spec)
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
    module = kind_module(spec.kind)
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
    fig = kind_module("final").draw(pd.DataFrame(rows), spec)
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
    fig = kind_module("final").draw(pd.DataFrame(rows), spec)
    rms, ratio = fig.axes[:2]
    assert (rms.get_yscale(), ratio.get_yscale()) == ("log", "linear")
    floor = [ln for ln in ratio.lines if ln.get_label() == "Cramér-Rao floor (Gaussian)"]
    assert len(floor) == 1 and list(floor[0].get_ydata()) == [1.0, 1.0]
    data_z = max(c.get_zorder() for c in rms.containers for c in [c.lines[0]])
    assert all(ln.get_zorder() > data_z for ln in rms.lines if ln.get_label() in ("noise floor", "Cramér-Rao floor (Gaussian)"))
    assert defects(fig) == []
    plt.close(fig)


@pytest.mark.parametrize("per_family", [1, 2])
def test_tuning_names_settings_in_a_legend_only_where_the_axis_does_not(per_family):
    """One setting per family (an ablation's variants): the x axis names each, so no legend repeats it;
    two per family: the legend tells them apart."""
    spec = OmegaConf.create({"title": "t", "kind": "tuning", "plot": {}})
    rows = [{"scenario": "s", "family": fam, "label": f"{fam}, w = {k}", "median": 1.0 + k, "q25": 0.9, "q75": 2.0,
             "success_rate": 0.9, "default": False, "role": "", "metric": "fun"}
            for fam in ("pso", "ipso", "ipso_w") for k in range(per_family)]
    fig = kind_module("tuning").draw(pd.DataFrame(rows), spec)
    texts = [t.get_text() for legend in fig.legends for t in legend.get_texts()]
    assert texts == ([] if per_family == 1 else [r["label"] for r in rows])
    assert [t.get_text() for t in fig.axes[0].get_xticklabels()] == ["pso", "ipso", "ipso_w"]
    plt.close(fig)


def test_a_calibration_figure_shows_a_successful_run_and_says_so():
    from types import SimpleNamespace

    from magexp.artifacts.plots.field import shown_seed

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
    from magexp.artifacts.plots.parameters import cell_label
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
    fig = kind_module("final").draw(pd.DataFrame(rows), spec)
    ax = fig.axes[0]
    assert list(ax.get_xticks()) == [0.0, 0.1, 1.0]
    legends = [*fig.legends, *(a.get_legend() for a in fig.axes if a.get_legend() is not None)]
    assert "eq 8 minimised" in [t.get_text() for legend in legends for t in legend.get_texts()]
    assert defects(fig) == []
    plt.close(fig)
