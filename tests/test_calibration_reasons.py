"""Refuse only for the right reason (issue 33 item 4): the gate's anisotropy limit set from real sensors, the
residual RMS less the readings' own noise, an estimator short of the closed-form optimum named as such, a fit
that collapsed not blamed on the recording, and the gyro-aided model refused for a saturated gyroscope; and
model=auto (item 7) reporting every candidate, a gyro-aided one that cannot succeed dropped before its fit."""

import re

import numpy as np
import pytest

import magexp
from magexp.calibration.checks import GATE, check_fit
from magexp.calibration import fit as fit_module
from magexp.calibration.command import main
from magexp.calibration.quality import noise_of
from magexp.calibration.models import clipped, gyro_unusable, select
from magexp.errors import MagexpError
from magexp.paths import SHARED_DATA

QMC = SHARED_DATA / "qmc5883l_noisy_raw_data.csv"
SPHERE = SHARED_DATA / "hmc5883l_full-sphere"


def _present(path):
    return pytest.mark.skipif(not (path.is_file() or path.with_name(path.name + "_mag.csv").is_file()),
                              reason=f"{path} is not present")


def _refused(tmp_path, capsys, *args):
    code = main([*args, f"out={tmp_path / 'out'}"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert not (tmp_path / "out").exists()
    return err[0]


@_present(QMC)
def test_qmc5883l_log_is_accepted_its_anisotropy_and_noise_its_sensors():
    """Was: refused for W's ratio 2.25 > 2.0 (blaming the coverage) and a residual RMS of 6.27 % > 3.2 %, while
    its held-out spread beats raw and the data's authors publish a matrix of ratio 2.18 for this sensor."""
    cal = magexp.calibrate(QMC)
    sigma = np.linalg.svd(cal.w, compute_uv=False)
    assert cal.report["gate"]["passed"] and 2.0 < sigma[0] / sigma[-1] < GATE["max_anisotropy"]
    m = cal.metrics
    assert m["heldout_spread"] < 0.75 * m["spread_before"]
    assert 0.9 * m["rms_after"] < m["noise_after"] < m["rms_after"]  # the residual is mostly the sensor's noise


def test_anisotropy_refusal_names_check_number_and_limit_not_coverage():
    rng = np.random.default_rng(3)
    d = rng.standard_normal((400, 3))
    readings = 50 * d / np.linalg.norm(d, axis=1, keepdims=True) * [4.0, 1.0, 1.0]
    with pytest.raises(MagexpError) as err:
        magexp.calibrate(readings, unit="uT", model="full")
    line = str(err.value)
    assert "check 'anisotropy' failed" in line and "= 4 exceed the limit 3" in line and "gate.max_anisotropy" in line
    assert "cover" not in line


def test_noise_is_discounted_from_the_residual_only_for_a_time_series():
    """White noise on a perfectly calibrated sphere: the noise estimate recovers it from neighbouring readings
    (a slow turn), and a shuffled set, whose neighbours are far apart, discounts nothing."""
    rng = np.random.default_rng(5)
    t = np.linspace(0, 1, 4000)
    az, el = 80 * np.pi * t, np.arcsin(2 * t - 1)
    d = np.stack([np.cos(az) * np.cos(el), np.sin(az) * np.cos(el), np.sin(el)], axis=1)
    noisy = 50 * d + rng.normal(0, 2.0, d.shape)
    assert noise_of(noisy, noisy) == pytest.approx(2.0, rel=0.1)
    assert noise_of(noisy[rng.permutation(len(noisy))], noisy) == 0.0
    raw = noisy * [1.3, 0.9, 1.0] + [30, -20, 10]
    cal = magexp.calibrate(raw, unit="counts", model="full")  # 4 % noise: over the 3.2 % limit, but noise
    assert cal.report["gate"]["passed"] and cal.metrics["rms_after"] > GATE["max_rms_fraction"] * 50


@_present(SPHERE)
def test_an_unconverged_swarm_is_named_with_the_closed_form_fit(tmp_path, capsys):
    """Was: "every calibrated direction lies within 17.4 deg of one (a single attitude)" for a swarm that failed."""
    line = _refused(tmp_path, capsys, f"data.path={SPHERE}", "estimator=ipso", "estimator.n_iterations=3",
                    "model=full")
    assert "estimator='ipso' did not converge" in line and "closed-form ellipsoid fit's 0.46 %" in line
    assert "limit 1.1" in line and "estimator.n_iterations=..., now 3" in line and "single attitude" not in line


@_present(SPHERE)
def test_an_unconverged_swarm_under_auto_is_named_by_its_held_out_spread(tmp_path, capsys):
    """model=auto (the default): the swarm's full model failed on the folds (13.5 % held out in the box centred on
    the closed form, 26 % in the readings' range box); auto would otherwise have fallen back to the diagonal model
    (2.83 %) without a word."""
    line = _refused(tmp_path, capsys, f"data.path={SPHERE}", "estimator=ipso", "estimator.n_iterations=3")
    held = re.search(r"its held-out spread ([0-9.]+) %", line)
    assert "estimator='ipso' did not converge" in line and held and float(held.group(1)) > 1.1 * 0.707
    assert "closed-form ellipsoid fit's 0.707 % (limit 1.1 times)" in line


@_present(SPHERE)
def test_a_converged_swarm_reaches_the_closed_form_optimum():
    swarm = magexp.calibrate(SPHERE, estimator="ipso", model="full", folds=0)
    closed = magexp.calibrate(SPHERE, model="full", folds=0)
    assert swarm.metrics["spread_after"] <= 1.1 * closed.metrics["spread_after"]


def test_a_collapsed_fit_is_blamed_on_the_fit():
    full = {"coverage_cells": 1.0, "direction_max_angle_deg": 90.0}
    with pytest.raises(MagexpError, match="did not converge.*collapsed, not the recording"):
        check_fit("r", "ipso", True, "", {"coverage_cells": 0.03, "direction_max_angle_deg": 12.0}, full)
    with pytest.raises(MagexpError, match="single attitude"):
        check_fit("r", "ipso", True, "", {"coverage_cells": 0.03, "direction_max_angle_deg": 12.0},
                  {"coverage_cells": 0.03, "direction_max_angle_deg": 12.0})
    partial = {"coverage_cells": 11 / 32, "direction_max_angle_deg": 80.0}  # x-io: z stays negative
    with pytest.raises(MagexpError, match=r"into 11 \(34 % of the sphere, under 75 %\).*model=sphere"):
        check_fit("r", "lm", True, "", {"coverage_cells": 6 / 32, "direction_max_angle_deg": 38.8}, partial)


def test_clipped_gyroscope_axes():
    rates = np.radians(np.array([[250.13, 10, 10], [250.13, 20, -30], [-250.13, 5, 0], [100, 300, 0]]))
    assert [(a, round(lim, 2), n) for a, lim, n in clipped(rates)] == [("x", 250.13, 3)]
    assert clipped(rates[1:]) == [] and gyro_unusable((None, rates[1:])) is None
    assert gyro_unusable(None) == "the recording has no gyroscope"


@_present(SPHERE)
def test_gyro_model_on_a_saturated_gyroscope_is_refused_for_it(tmp_path, capsys):
    """Was: "every calibrated direction lies within 0.0 deg of one (a single attitude)"."""
    line = _refused(tmp_path, capsys, f"data.path={SPHERE}", "model=gyro")
    assert "gyroscope saturates (gx at ±250.1 deg/s on 22 readings)" in line and "model=full" in line


# -- model=auto reports every candidate, and drops one that cannot succeed before fitting it (item 7) ----------
def test_auto_reports_every_candidate_fitted_failed_or_dropped():
    spreads = {"sphere": 0.05, "diagonal": float("nan"), "full": 0.01}
    chosen, record = select(spreads.get, "scalar", 0.1, dropped={"gyro": "the gyroscope saturates (gx ...)"})
    assert chosen == "full" and record["dropped"] == {"gyro": "the gyroscope saturates (gx ...)"}
    assert "held out: full 1 %, sphere 5 %, diagonal: its fit failed with a region of directions held out" in record["why"]
    assert record["why"].endswith("; gyro not fitted: the gyroscope saturates (gx ...))")


@_present(SPHERE)
def test_auto_never_fits_the_gyro_model_of_a_saturated_gyroscope(monkeypatch):
    """Was: 2.3 of auto's 3.2 CPU-seconds on the gyro-aided candidate, whose fit failed and was dropped without a
    word. Now it is dropped before any fit (the default run: 0.57 s of CPU against model=full's 0.48 s)."""
    fitted = []
    real = fit_module.heldout
    monkeypatch.setattr(fit_module, "heldout", lambda *a, **k: fitted.append(a[-1] if len(a) > 6 else k.get("model"))
                        or real(*a, **k))
    cal = magexp.calibrate(SPHERE)
    assert "gyro" not in fitted and set(fitted) == {"sphere", "diagonal", "full"}
    selection = cal.report["model_selection"]
    assert "gyroscope saturates" in selection["dropped"]["gyro"] and "gyro not fitted" in selection["why"]
