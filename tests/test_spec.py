"""The artifact schema: every artifact file loads; a typo fails with one line naming the key and the allowed ones."""

from pathlib import Path

import pytest
import yaml

from magexp.errors import MagexpError
from magexp.artifacts.spec import Reported, load
from magexp.artifacts.paper_spec import artifact_paths, load_paper, papers

ARTIFACTS = [p for paper in papers() for p in artifact_paths(paper)]


def test_papers_are_discovered_from_experiments():
    found = papers()
    assert {"ding2024", "yuan2018", "yan2022", "benchmark"} <= set(found)
    assert found.index("ding2024") < found.index("yuan2018") < found.index("yan2022") < found.index("benchmark")


@pytest.mark.parametrize("path", ARTIFACTS, ids=lambda p: p.stem)
def test_every_artifact_loads(path):
    spec = load(path)
    assert spec.name == path.stem and spec.paper == path.parent.name


def _write(tmp_path, data) -> Path:
    folder = tmp_path / "paperx"
    folder.mkdir(exist_ok=True)
    path = folder / "paperx_fig1.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


BASE = {"title": "t", "kind": "final", "grid": {"estimator": ["lm"]}, "plot": {"x": "scenario.noise"}}


@pytest.mark.parametrize("change, words", [
    ({"sedes": 3}, ["'sedes'", "allowed keys are", "seeds"]),
    ({"plot": {"x": "a", "hue_key": "b"}}, ["'hue_key'", "kind final", "hue"]),
    ({"plot": {"x": "a", "linthresh": "wide"}}, ["plot (kind final).linthresh='wide'", "float"]),  # a typed key
    ({"plot": {"x": "a", "xscale": "logarithmic"}}, ["plot.xscale='logarithmic'", "linear, log, symlog"]),
    ({"kind": "heatmap", "plot": {"x": "a"}}, ["kind heatmap", "'x'", "metric"]),  # a key of another kind
    ({"summarise": [{"quantity": "q", "metrik": "fun"}]}, ["summarise[0]", "'metrik'", "metric"]),
    ({"reported": [{"quantity": "q", "vaule": 1.0}]}, ["reported[0]", "'vaule'", "value"]),
    ({"claims": [{"id": "c", "text": "t", "kind": "ordering", "cells": [{}, {}], "bye": "paper"}]}, ["'bye'", "by"]),
    ({"kind": "finale"}, ["kind='finale'", "final"]),
    ({"seeds": "many"}, ["seeds='many'", "int"]),
    ({"grid": {"estimator": "lm"}}, ["grid.estimator", "list"]),
    ({"tolerance": {"rel": 0.1, "abs": 1.0}}, ["exactly one"]),
    ({"tolerance": {"rel": 0.1}, "reported": [{"quantity": "q", "value": 1.0}]}, ["needs a reason"]),
    ({"seeds": 10, "reported": [{"quantity": "q", "value": 1.0}]}, ["seeds=10", "at least 30 seeds"]),
    ({"seeds": True}, ["seeds=True", "int"]),  # a flag is no number
    ({"floor": True}, ["floor=True", "float"]),
    ({"skip_inapplicable": "yes"}, ["skip_inapplicable='yes'", "bool"]),
    ({"reported": [{"quantity": "q"}]}, ["reported[0]", "missing key 'value'"]),
    ({"tolerance": {"rell": 0.1}}, ["tolerance", "'rell'", "rel, abs, factor, below"]),
    ({"summarise": [{"quantity": "q", "metric": "fun", "interval": "bootstrap"}]}, ["interval='bootstrap'", "seeds, ls"]),
])
def test_a_typo_fails_with_one_line(tmp_path, change, words):
    with pytest.raises(MagexpError) as info:
        load(_write(tmp_path, {**BASE, **change}))
    message = str(info.value)
    assert "\n" not in message
    for w in words:
        assert w in message, (w, message)


def test_numbers_given_as_text_and_texts_given_as_numbers_are_converted(tmp_path):
    spec = load(_write(tmp_path, {**BASE, "floor": "1e-9", "title": 3}))  # YAML reads 1e-9 as text
    assert spec.floor == 1e-9 and isinstance(spec.floor, float) and spec.title == "3"


def test_old_plot_keys_still_load_as_the_canonical_ones(tmp_path):
    spec = load(_write(tmp_path, {**BASE, "plot": {"x": "a", "logx": True, "value": "fun"}}))
    assert spec.plot.xscale == "log" and spec.plot.metric == "fun" and not hasattr(spec.plot, "logx")


def test_vector_reported_entries_expand_and_printing_precision():
    spec = load(next(p for p in ARTIFACTS if p.stem == "yuan2018_table3"))
    s11 = [r for r in spec.reported if r.quantity == "S11"]
    assert len(s11) == 4 and s11[0].value == 0.9 and s11[0].half_unit() == pytest.approx(5e-5)
    assert Reported(quantity="q", value=0.58).half_unit() == pytest.approx(0.005)
    assert Reported(quantity="q", value=7.05e-12).half_unit() == pytest.approx(5e-15)
    assert Reported(quantity="q", value=266.0).half_unit() == pytest.approx(0.5)


def test_paper_yaml_deviations_are_typed():
    meta = load_paper("yuan2018")
    assert meta.deviations and all(d.text and d.reason for d in meta.deviations)
