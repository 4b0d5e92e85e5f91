"""``python -m magexp.calibration.simulate``: a recording with attitudes and the field that ``objective=vector``
calibrates back to the distortion it was drawn with (issue 40, item 7: the docs' vector example)."""

from __future__ import annotations

import numpy as np
import pytest

import magexp
from magexp.calibration.simulate import main, simulate


@pytest.mark.full  # 1.7 s in a fresh worker (composing the estimator's config and its imports), 0.2 s after
def test_the_vector_objective_recovers_the_simulated_distortion(tmp_path):
    text, w, offset = simulate(400, 3)
    path = tmp_path / "attitudes.csv"
    path.write_text(text)
    cal = magexp.calibrate(str(path), objective="vector", estimator="lm", folds=0, compiled=False)
    np.testing.assert_allclose(cal.w, w, atol=2e-3)  # the whole W, its rotation included
    np.testing.assert_allclose(cal.offset, offset, atol=10.0)  # nT, noise 20 nT per axis on 400 readings
    assert cal.metrics["spread_after"] < 0.1 * cal.metrics["spread_before"]
    assert simulate(400, 3)[0] == text and simulate(400, 4)[0] != text  # the seed decides every draw


def test_the_command_writes_once_and_refuses_in_one_line(tmp_path, capsys):
    path = tmp_path / "a.csv"
    assert main([str(path), "--readings", "50"]) == 0 and path.read_text().count("\n") == 56
    before = path.read_text()
    for argv, says in (([str(path)], "exists already"), ([str(tmp_path / "b.csv"), "--readings", "5"], "--readings"),
                       ([str(tmp_path / "no" / "c.csv")], "does not exist")):
        capsys.readouterr()
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert says in err and err.count("\n") == 1, err
    assert path.read_text() == before and not (tmp_path / "b.csv").exists()
