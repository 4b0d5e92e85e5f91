"""Figures a paper can take as they are: a vector twin beside every PNG, and drawing into the
caller's own axes."""

import hashlib

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from omegaconf import OmegaConf

from magexp.artifacts.kinds import kind
from magexp.artifacts.plots.style import panels, save


def frame():
    it = np.arange(20)
    return pd.concat([pd.DataFrame({"estimator": est, "iteration": it, "nfev": it * 50.0,
                                    "median": 10.0 / (1 + it) + k, "q25": 9.0 / (1 + it) + k, "q75": 11.0 / (1 + it) + k,
                                    "noise_floor": 0.5, "rms_bound": 0.4, "n_seeds": 3, "converged": 2})
                      for k, est in enumerate(["pso", "ipso"])], ignore_index=True)


SPEC = OmegaConf.create({"title": "test", "plot": {"hue": "estimator"}})


def digest(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_save_writes_a_deterministic_pdf_twin(tmp_path):
    draw = kind("convergence").draw
    first = save(draw(frame(), SPEC), tmp_path / "a.png")
    second = save(draw(frame(), SPEC), tmp_path / "b.png")
    assert [p.name for p in first] == ["a.png", "a.pdf"]
    assert (tmp_path / "a.pdf").read_bytes().startswith(b"%PDF")
    assert digest(tmp_path / "a.pdf") == digest(tmp_path / "b.pdf")  # same figure, same bytes
    assert digest(tmp_path / "a.png") == digest(tmp_path / "b.png")
    assert b"CreationDate" not in (tmp_path / "a.pdf").read_bytes()


def test_a_kind_draws_into_the_callers_axes():
    fig, (left, right) = plt.subplots(1, 2)
    right.plot([0, 1], [0, 1])
    out = kind("convergence").draw(frame(), SPEC, axes=[left])
    assert out is fig
    assert len(left.get_lines()) >= 2 and len(right.get_lines()) == 1  # only the given axes were drawn in
    assert left.get_yscale() == "log"
    plt.close(fig)


def test_panels_refuses_the_wrong_number_of_axes():
    import pytest

    from magexp.errors import MagexpError

    fig, axes = plt.subplots(1, 3)
    with pytest.raises(MagexpError, match="3 given"):
        panels(2, axes=axes)
    assert panels(3, axes=axes) == (fig, list(axes))
    plt.close(fig)


def test_math_text_parsed_once_for_every_figure_gives_the_same_bytes(tmp_path, monkeypatch):
    from matplotlib import mathtext

    shared = mathtext.MathTextParser._parse_cached
    assert shared.shared  # in place once magexp.artifacts.plots.style is imported
    draw = kind("convergence").draw  # log axes: math text tick labels
    hits = shared.cache_info().hits
    save(draw(frame(), SPEC), tmp_path / "shared.png")
    save(draw(frame(), SPEC), tmp_path / "again.png")
    assert shared.cache_info().hits > hits  # the second figure reused the first one's parses
    monkeypatch.setattr(mathtext.MathTextParser, "_parse_cached", shared.original)  # matplotlib's own
    save(draw(frame(), SPEC), tmp_path / "own.png")
    for ext in ("png", "pdf"):
        assert digest(tmp_path / f"shared.{ext}") == digest(tmp_path / f"own.{ext}")
        assert digest(tmp_path / f"again.{ext}") == digest(tmp_path / f"own.{ext}")
