"""Every artifact's figure, drawn from its committed CSV under ``results/`` (no run), is free of the
defects a reader sees: an empty panel, text printed over text, a colour bar naming another column
than the one drawn, a legend of raw override strings (:mod:`magexp.plots.check`)."""

from __future__ import annotations

import pandas as pd
import pytest

from magexp.artifacts import paper_specs
from magexp.paths import RESULTS
from magexp.plots import kind_module
from magexp.plots.check import colorbar_mismatch, defects, empty_axes, overlapping_text, raw_legends
from magexp.plots.style import colorbar, drawn_from, plt
from magexp.spec import papers


def committed():
    """``(paper, spec)`` of every artifact whose CSV is committed (recordings' artifacts: when drawn)."""
    return [pytest.param(spec, id=spec.name) for paper in papers() for spec in paper_specs(paper)
            if (RESULTS / paper / f"{spec.name}.csv").is_file()]


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
