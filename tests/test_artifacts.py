"""Every artifact file (the benchmark's included) runs end to end at tiny size, and its summary rows
keep the contract: the columns, the verdict vocabulary, and verdicts that agree with their intervals."""

import dataclasses

import numpy as np
import pandas as pd
import pytest

from magexp.artifacts.plan import cells, overrides_of
from magexp.artifacts.report import build
from magexp.artifacts.reproduce import reproduce
from magexp.artifacts.spec import load
from magexp.artifacts.paper_spec import artifact_paths, papers
from magexp.artifacts.summary import COLUMNS, VERDICTS
from magexp.core.outcomes import failed_majority
from magexp.run.compose import GROUPS, check_choice

WHOLE_PAPER = "yan2022"  # its artifacts run once, together, through reproduce_paper (test_whole_paper_runs_tiny)
ARTIFACTS = [p for paper in papers() if paper != WHOLE_PAPER for p in artifact_paths(paper)]

#: the artifact whose smoke run stands for its plot kind (the cheapest of the kind); in ``make test`` only
#: those of the kinds of :data:`IN_MAKE_TEST`, one per plot family. Every other smoke run is a ``full`` case
#: (``make test-full``): its configs' names are checked in ``make test`` by
#: test_every_artifact_names_configs_that_exist and every kind's figure, drawn from its committed CSV, by
#: tests/test_figure_defects.py; the yan2022 kinds (estimates, trace) run in test_whole_paper_runs_tiny
KIND_SMOKE = {"convergence": "ding2024_fig5", "field": "ding2024_fig2", "final": "benchmark_readings",
              "heatmap": "benchmark_objective", "parameters": "yuan2018_table4", "recording": "real_table7",
              "recording_spread": "real_benchmark", "speed": "benchmark_speed", "sphere": "yuan2018_fig4",
              "tuning": "ding2024_ext_pso_tuning"}  # tuning: the cheapest of its kind

#: the plot families (what a kind's table aggregates): the readings of one run, a quantity per step, final
#: values per case and estimator, the fits of a recording
FAMILIES = {"readings": ("field", "sphere", "parameters"), "steps": ("convergence",),
            "final values": ("final", "heatmap", "speed", "tuning"), "recordings": ("recording", "recording_spread")}
#: the kind whose smoke run stands for its family in ``make test`` (the cheapest run of the family)
IN_MAKE_TEST = {"readings": "field", "steps": "convergence", "final values": "final", "recordings": "recording"}

#: the cases a smoke run keeps, by artifact: ``benchmark_speed`` draws the 104 cells of ``benchmark_heatmap``
#: (a ``full`` case, every cell) coloured by paper: one scenario of each paper exercises all it does
SMOKE_CASES = {"benchmark_speed": ("scenario=ding2024_exp1", "scenario=yuan2018_table2", "scenario=yan2022_sim")}


def _consistent(row) -> bool:
    """An ``n/a`` row has no paper value; a ``reproduced`` row no failed majority."""
    if row.verdict == "n/a":
        return pd.isna(row.paper_value)
    return not (row.verdict == "reproduced" and failed_majority(row.success_rate))


def check_artifact(spec, out, summary, built, seeds=2):
    """The outputs of ``spec`` in ``out`` (its figure, built and not rendered: ``built`` is conftest.py's
    ``figures_not_rendered``; its table and runs) and its ``summary`` rows keep the contract."""
    assert built.get(spec.name, 0) >= 1 and (out / f"{spec.name}.png").exists()  # its figure, built
    assert len(pd.read_csv(out / f"{spec.name}.csv")) > 0
    runs = pd.read_csv(out / f"{spec.name}_runs.csv")
    assert "succeeded" in runs and len(runs) == seeds * runs.cell.nunique()
    # one success column (magexp.core.outcomes); the optimiser's own flag under its own name
    assert "success" not in runs and "optimizer_flag" in runs
    assert "field_rms" not in runs or runs.field_rms[runs.objective == "scalar"].isna().all()  # its `fun`
    assert list(summary.columns) == COLUMNS
    assert set(summary.verdict) <= set(VERDICTS)
    assert all(_consistent(r) for r in summary.itertuples())
    assert (summary.lo.dropna() <= summary.hi.dropna() + 1e-12).all()
    if spec.reported:
        assert (summary.verdict != "n/a").any()


def check_real_modes(out, summary):
    """Gyro and magnetometer agree to a few % of the field on every recording; the runs table names the
    combination each one-axis sequence leaves undetermined."""
    frac = summary[summary.quantity == "vector_residual_fraction"]
    assert len(frac) == 5 and (frac.value < 0.05).all()
    assert pd.read_csv(out / "real_modes_runs.csv").weakest_combination.notna().all()


#: what an artifact's own smoke run must also show, beyond the contract
OWN_CHECKS = {"real_modes": check_real_modes}


def _smoke(path):
    """``path`` as a parameter: a ``full`` case unless it stands for its family (:data:`IN_MAKE_TEST`)."""
    in_make_test = path.stem in {KIND_SMOKE[kind] for kind in IN_MAKE_TEST.values()}
    return pytest.param(path, id=path.stem, marks=[] if in_make_test else [pytest.mark.full])


def test_every_kind_has_a_smoke_run_and_every_family_one_in_make_test():
    """A new plot kind needs its representative in :data:`KIND_SMOKE`, each one of its kind, and its family in
    :data:`FAMILIES`; each family's kind in :data:`IN_MAKE_TEST` is one of the family."""
    kind_of = {p.stem: load(p).kind for p in ARTIFACTS}
    assert set(KIND_SMOKE) == set(kind_of.values())
    assert all(kind_of[name] == kind for kind, name in KIND_SMOKE.items())
    families = [kind for kinds in FAMILIES.values() for kind in kinds]
    assert sorted(families) == sorted(KIND_SMOKE)  # each kind in one family
    assert set(IN_MAKE_TEST) == set(FAMILIES) and all(IN_MAKE_TEST[f] in FAMILIES[f] for f in FAMILIES)


def test_every_artifact_names_configs_that_exist():
    """Each cell of every artifact chooses a scenario and an estimator that ``conf/`` has (the cheap half
    of a smoke run: a misspelt name in an experiment file fails here, not at ``make reproduce``)."""
    checked = 0
    for paper in papers():
        for path in artifact_paths(paper):
            spec = load(path)
            for cell in cells(spec):
                for override in overrides_of(spec, cell):
                    key, _, value = override.partition("=")
                    if key in GROUPS:
                        check_choice(key, value)
                        checked += 1
    assert checked > 500


def test_the_readings_figures_print_their_scenarios_unit():
    """A ``field``, ``sphere`` or ``parameters`` figure labels its axes with ``plot.unit``: the unit of the
    readings its scenarios generate (Yuan's mG, Ding's nT)."""
    from magexp.artifacts.plots.style import unit
    from magexp.core.seeding import run_generators, scenario_stream
    from magexp.run.compose import compose_config
    from magexp.run.runner import build as build_node

    units, checked = {}, set()  # scenario name -> the unit of its readings (one generation each)
    for spec in (load(p) for p in ARTIFACTS):
        if spec.kind not in ("field", "sphere", "parameters"):
            continue
        for cell in cells(spec):
            node = compose_config(overrides_of(spec, cell))["scenario"]
            if node.name not in units:
                rng = run_generators(0, stream=scenario_stream(node))[0]
                units[node.name] = build_node(node, "scenario").generate(rng=rng).unit
            assert units[node.name] == unit(spec), f"{spec.name}: readings in {units[node.name]}, figure says {unit(spec)}"
            checked.add(spec.name)
    assert {"ding2024_fig2", "yuan2018_fig2", "yuan2018_table2", "yuan2018_table7"} <= checked


@pytest.mark.slow
@pytest.mark.parametrize("path", [_smoke(p) for p in ARTIFACTS])
def test_artifact_runs_tiny(tmp_path, path, figures_not_rendered):
    """Two seeds (one where the artifact itself has one: a deterministic fit of a recording)."""
    spec = load(path)
    if spec.name in SMOKE_CASES:
        first = {case[0]: case for case in reversed(spec.cases)}  # each scenario's first case
        spec = dataclasses.replace(spec, cases=[first[scenario] for scenario in SMOKE_CASES[spec.name]])
    seeds = min(spec.seeds, 2)
    counts = reproduce({spec.paper: [spec]}, tmp_path, seeds=seeds, jobs=1, tiny=True, log=lambda *_: None)
    out, summary = tmp_path / spec.paper, counts["paper summaries"][spec.paper]
    check_artifact(spec, out, summary, figures_not_rendered, seeds=seeds)
    OWN_CHECKS.get(spec.name, lambda *_: None)(out, summary)


@pytest.mark.slow
@pytest.mark.full  # make test: each artifact kind's smoke run (test_artifact_runs_tiny) and test_report.py
def test_whole_paper_runs_tiny(tmp_path, figures_not_rendered):
    """Every artifact of one paper in one reproduction (one pass over all their runs, one seed: the
    intervals over seeds are the other artifacts' smoke runs'), each keeping the contract; the paper's
    summary, and its report with the LaTeX (booktabs) twin of every table."""
    from magexp.artifacts.reproduce import reproduce_paper

    summary = reproduce_paper(WHOLE_PAPER, root=tmp_path, seeds=1, jobs=1, tiny=True, log=lambda *_: None)
    specs = [load(p) for p in artifact_paths(WHOLE_PAPER)]
    assert {spec.name for spec in specs} >= {f"yan2022_{stem}" for stem in (
        "fig1", "fig3", "fig4", "fig_noise", "fig_tuning", "table_mockup", "table_sim")}
    assert set(summary.artifact) <= {spec.name for spec in specs}
    for spec in specs:
        check_artifact(spec, tmp_path / WHOLE_PAPER, summary[summary.artifact == spec.name], figures_not_rendered,
                       seeds=1)
    assert {"fit_rms", "be_rms", "k_error", "steps_to_ls"} <= set(summary.quantity)
    build(tmp_path)
    report, appendix = (tmp_path / "REPORT.md").read_text(), (tmp_path / "APPENDIX.md").read_text()
    assert "yan2022/yan2022_fig4.png" in appendix and "### Deviations from the paper's text" in report
    assert "### Headline claims" in report and "### Findings" in report and (tmp_path / "claims.csv").exists()
    versions = pd.read_csv(tmp_path / "versions.csv")
    assert {"python", "numpy", "scipy", "magexp_commit"} <= set(versions.package)
    written = pd.read_csv(tmp_path / "summary.csv", keep_default_na=False, na_values=[""])
    assert list(written.columns) == COLUMNS and np.isin(written.verdict, VERDICTS).all()
    assert len(written) == len(summary) > 0
    # every report table has its LaTeX (booktabs) twin with the same rows
    twins = [(f"{WHOLE_PAPER}/{name}_summary.tex", n) for name, n in written.groupby("artifact").size().items()]
    for twin, rows in [*twins, (f"{WHOLE_PAPER}/claims.tex", None), (f"{WHOLE_PAPER}/deviations.tex", None)]:
        tex = (tmp_path / twin).read_text()
        assert tex.startswith("\\begin{tabular}") and "\\toprule" in tex and "\\bottomrule" in tex
        if rows is not None:
            body = tex.split("\\midrule\n", 1)[1].split("\\bottomrule", 1)[0]
            assert body.count("\\\\\n") == rows, twin
