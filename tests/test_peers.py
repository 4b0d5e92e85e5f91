"""magexp beside MAGYC (magexp.perf.peers): the neutral files, the time alignment, the measures, and the round
trip through the peer's environment (skipped without ``make peers``). The bench itself is not run here."""

import json
import subprocess
from argparse import Namespace

import numpy as np
import pytest

from magexp.errors import MagexpError
from magexp.core.geometry import preintegrate
from magexp.perf.peers import bench, data, exchange, magexp_side, measures, report
from magexp.perf.peers import claims as peer_claims
from magexp.perf.peers.exchange import Estimate


def dataset(n=400, *, soft=None, hard=(0.02, 0.12, 0.09)):
    """Readings on an exact ellipsoid ``D u + h`` (u on the unit sphere, radius 0.5 G) with a turning gyro."""
    rng = np.random.default_rng(3)
    u = rng.normal(size=(n, 3))
    u = 0.5 * u / np.linalg.norm(u, axis=1, keepdims=True)
    d = np.eye(3) if soft is None else np.asarray(soft)
    t = np.arange(n) * 0.1
    side = data.side("unit_test", "test", seed=0, mag_unit="G", mag_noise_std=1e-3, reference_total=0.5,
                     axes="one frame", alignment="none")
    return exchange.NeutralDataset(t, u @ d.T + np.asarray(hard), rng.normal(size=(n, 3)) * 0.1, side,
                                   {"truth_soft_iron": d, "truth_hard_iron": np.asarray(hard, float)})


def test_neutral_file_round_trip(tmp_path):
    ds = dataset()
    back = exchange.read(exchange.write(ds, tmp_path / "x"))
    for key in ("t", "mag", "gyro"):
        np.testing.assert_array_equal(getattr(back, key), getattr(ds, key))
    np.testing.assert_array_equal(back.truth["truth_hard_iron"], ds.truth["truth_hard_iron"])
    assert back.side == json.loads(json.dumps(ds.side))


def test_bad_dataset_is_refused_in_one_line(tmp_path):
    ds = dataset()
    ds.gyro = ds.gyro[:-1]
    with pytest.raises(MagexpError, match="gyro of shape"):
        exchange.write(ds, tmp_path / "bad")
    assert not (tmp_path / "bad.npz").exists()


def test_rates_at_averages_the_held_gyro_over_each_interval():
    gyro_t = np.array([0.0, 1.0, 2.0, 3.0])
    rates = np.array([[1.0, 0, 0], [3.0, 0, 0], [5.0, 0, 0], [7.0, 0, 0]])
    out = data.rates_at(gyro_t, rates, np.array([0.5, 1.5, 3.0]))
    # [0.5, 1.5]: half at 1, half at 3 -> 2; [1.5, 3]: 0.5 s at 3 and 1 s at 5 -> 13/3; the first row repeats
    np.testing.assert_allclose(out[:, 0], [2.0, 2.0, 13 / 3])
    bias = np.array([0.1, -0.2, 0.3])  # a constant bias passes through unchanged
    np.testing.assert_allclose(data.rates_at(gyro_t, rates + bias, np.array([0.5, 1.5, 3.0])) - out,
                               np.tile(bias, (3, 1)))


def test_soft_iron_error_ignores_scale_and_rotation_not_shape():
    truth = np.array([[1.10, 0.10, 0.04], [0.10, 0.88, 0.02], [0.04, 0.02, 1.22]])
    angle = 0.7
    rot = np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]])
    assert measures.soft_iron_error(2.5 * truth @ rot, truth) < 1e-12
    assert measures.soft_iron_error(-truth, truth) < 1e-12  # the gyro objective's (S, h) -> (-S, -h) member
    assert measures.soft_iron_error(None, truth) == pytest.approx(measures.soft_iron_error(np.eye(3), truth))
    stretched = truth @ np.diag([1.05, 1.0, 1.0])
    assert 0.02 < measures.soft_iron_error(stretched, truth) < 0.05


@pytest.mark.slow  # a subprocess in the peer's environment: about 4 s, most of it importing magyc (jax, gtsam)
@pytest.mark.skipif(exchange.available() is not None, reason="the peer's environment is absent (make peers)")
def test_peer_round_trip_recovers_an_exact_ellipsoid(tmp_path):
    soft = np.array([[1.10, 0.10, 0.04], [0.10, 0.88, 0.02], [0.04, 0.02, 1.22]])
    soft = soft / np.cbrt(np.linalg.det(soft))  # the peer's scale: det 1
    ds = dataset(soft=soft)
    ds.side["methods"] = ["ellipsoid_fit", "sphere_fit"]
    (answer,) = exchange.run_peer([(exchange.write(ds, tmp_path / "in"), tmp_path / "out.json")])
    ellipsoid, sphere = (Estimate.from_peer(r) for r in answer["results"])
    assert answer["peer"] == "magyc" and ellipsoid.error is None
    # the ellipsoid fit returns the correction SI^-1, read back as the distortion D: its eigenvalues are exact
    # (its axes are not: magyc 1.0.0 transposes the eigenvector matrix, magyc_side's docstring)
    np.testing.assert_allclose(np.linalg.eigvalsh(ellipsoid.soft_iron), np.linalg.eigvalsh(soft), atol=1e-8)
    np.testing.assert_allclose(ellipsoid.hard_iron, ds.truth["truth_hard_iron"], atol=1e-8)
    assert sphere.soft_iron is None and sphere.gyro_bias is None
    assert np.linalg.norm(sphere.hard_iron - ds.truth["truth_hard_iron"]) > 1e-3  # a sphere cannot fit the ellipsoid


def test_compare_and_winner_use_the_report_vocabulary():
    import pandas as pd

    from magexp.artifacts.comparisons import CONTRADICTED, HOLDS, NO_DIFFERENCE, UNDECIDED
    from magexp.perf.peers import claims

    idx = pd.MultiIndex.from_arrays([[str(s) for s in range(5)], ["all"] * 5])
    low, high = pd.Series([1.0, 1.1, 0.9, 1.2, 1.0], idx), pd.Series([2.0, 2.2, 1.9, 2.4, 2.1], idx)
    assert claims.compare(low, high)[0] == HOLDS
    assert claims.compare(high, low)[0] == CONTRADICTED
    assert claims.compare(low, low + pd.Series([0.1, -0.1, 0.05, -0.05, 0.02], idx))[0] == NO_DIFFERENCE
    # one equal pair leaves 4 differences: the smallest p is 1/16, above alpha, whatever they are
    assert claims.compare(low, low + pd.Series([0.1, 0.1, 0.05, 0.05, 0.0], idx))[0] == UNDECIDED
    halves = pd.MultiIndex.from_arrays([["0", "0"], ["first_half", "second_half"]])
    a, b = pd.Series([0.8, 1.0], halves), pd.Series([10.0, 14.0], halves)
    assert claims.compare(a, b)[0] == UNDECIDED  # two halves of a recording decide nothing
    assert claims.said(b) == "12 (halves 10 and 14)"  # two values, never an interval in brackets
    family = claims.adjust([{"test": claims.tested(low, high), "evidence": "e"} for _ in range(3)])
    assert all(c["result"] == NO_DIFFERENCE for c in family)  # 1/32 each, x 3 by Holm: above alpha
    assert "Holm p = 0.094 of 3" in family[0]["evidence"]
    rows = [{"kind": "magyc_synthetic", "dataset": "magyc_high", "seed": s, "fit_on": "all", "axis_map": "",
             "side": "x", "method": m, "metric": metric, "value": v.iloc[s] * (1.0 if metric == "soft_iron_error" else 0.5)}
            for m, v in (("a", low), ("b", high), ("c", low + pd.Series([0.1, -0.1, 0.05, -0.05, 0.02], idx))) for s in range(5)
            for metric in ("soft_iron_error", "hard_iron_error")]
    frame = claims.frame_of(rows)
    np.testing.assert_allclose(claims.values(frame, claims.ERROR, method="b"), high.to_numpy())  # the worse error
    assert claims.winner(frame, claims.ERROR, ["a", "b"]) == ("a", HOLDS, [])
    assert claims.winner(frame, claims.ERROR, ["a", "b", "c"]) == ("a", NO_DIFFERENCE, ["c"])


def test_report_includes_the_peers_section_and_never_writes_it(tmp_path):
    from magexp.artifacts import report

    report.build(tmp_path)  # no results/peers: the section is one skip line
    assert "Skipped" in (tmp_path / "REPORT.md").read_text() and not (tmp_path / "peers").exists()
    peers = tmp_path / "peers"
    peers.mkdir()
    text = f"## magexp beside MAGYC\n\n### Headline claims\n\n**Headline.** shown\n\n{report.PEERS_MARK}\n\nnot shown\n"
    (peers / "peers.md").write_text(text)
    (peers / "peers.png").write_bytes(b"png")
    report.build(tmp_path)
    out = (tmp_path / "REPORT.md").read_text()
    assert "**Headline.** shown" in out and "not shown" not in out and "(peers/peers.png)" in out
    assert (peers / "peers.md").read_text() == text and sorted(p.name for p in peers.iterdir()) == ["peers.md", "peers.png"]


def test_subset_gives_both_sides_the_same_readings_and_rotations():
    ds = dataset(n=1000)
    sub = magexp_side.subset(ds, 300)
    fit = magexp_side.fit_indices(len(ds.t), 300)
    assert len(sub.t) == len(fit) == 300 and fit[0] == 0 and fit[-1] == 999
    np.testing.assert_array_equal(sub.mag, ds.mag[fit])
    # the mean rate held over each interval rotates exactly as the full gyro stream between the two readings
    full, _ = preintegrate(ds.t[:-1], ds.gyro[1:], ds.t[fit])
    held, _ = preintegrate(sub.t[:-1], sub.gyro[1:], sub.t)
    np.testing.assert_allclose(held, full, atol=1e-12)
    assert not np.allclose(sub.gyro[1:], ds.gyro[fit[1:]])  # not the sampled rates: the mean over each interval
    # every reading: the dataset itself
    np.testing.assert_allclose(magexp_side.subset(ds, 5000).gyro, ds.gyro, atol=1e-12)


def test_jobs_run_both_sides_on_every_reading_and_on_the_same_subset(monkeypatch, tmp_path):
    ds = dataset(n=1000)
    ds.side["kind"] = "magyc_synthetic"
    monkeypatch.setattr(bench, "simulated_sets", lambda args, work: [ds])
    args = bench.parse(["--out", str(tmp_path), "--no-real"])
    jobs = bench.jobs_of(args, tmp_path)
    assert [(label, len(d.t)) for d, _, label, _ in jobs] == [("all", 1000), (magexp_side.SUBSET, magexp_side.N_FIT)]
    # both sides read the same neutral dataset of each job: the subset's readings are those of magexp's fit
    np.testing.assert_array_equal(jobs[1][0].mag, ds.mag[magexp_side.fit_indices(1000, magexp_side.N_FIT)])
    assert all(d.side["methods"] == args.peer.split(",") for d, *_ in jobs)


@pytest.mark.skipif(exchange.available() is not None, reason="the peer's environment is absent (make peers)")
def test_magexp_lm_budget_is_the_peers():
    code = ("import inspect, re, magyc; print([inspect.signature(magyc.magyc_bfg).parameters['max_iter'].default] + "
            "[int(v) for f in (magyc.magyc_ls, magyc.magyc_nls) for v in re.findall(r'max_nfev=(\\d+)', "
            "inspect.getsource(f))] + ['max_iter' in inspect.signature(magyc.magyc_ifg).parameters])")
    out = subprocess.run([str(exchange.PEER_VENV / "bin" / "python"), "-c", code], capture_output=True, text=True,
                         check=True).stdout
    *budgets, ifg_capped = json.loads(out.replace("False", "false").replace("True", "true"))
    assert budgets == [magexp_side.LM_NFEV] * 3  # MAGYC-BFG (gtsam iterations), -LS and -NLS (scipy evaluations)
    assert not ifg_capped  # MAGYC-IFG: incremental updates, no iteration budget (the section says so)


def test_claims_on_each_basis_use_only_its_runs():
    rows = []
    for basis, (lm, nls) in (("all", (0.01, 0.2)), ("subset", (0.3, 0.02))):
        for s in range(5):
            for method, v in (("magexp_lm_gyro", lm), ("magyc_nls", nls)):
                rows += [{"kind": "magyc_synthetic", "dataset": "magyc_mid", "seed": str(s), "fit_on": basis,
                          "axis_map": "", "side": "x", "method": method, "metric": metric, "value": v * (1 + 0.1 * s)}
                         for metric in ("soft_iron_error", "hard_iron_error")]
    args = Namespace(nsamples=6000, n_fit=300, seeds=5)
    frame, summary = peer_claims.frame_of(rows), bench.summarise(rows)
    claims = report.simulated_claims(frame, summary, args)
    said = {(c["basis"], c.get("peer", "best")): c for c in claims}
    assert said[("all", "magyc_nls")]["text"].startswith("MAM (mid), the same 6,000 readings: magexp lm")
    assert said[("subset", "magyc_nls")]["text"].startswith("MAM (mid), the same 300 readings: magexp lm")
    assert said[("all", "magyc_nls")]["test"].p_hold == pytest.approx(1 / 32)  # lower on every seed of "all"
    assert said[("subset", "magyc_nls")]["test"].p_contra == pytest.approx(1 / 32)  # higher on every seed of "subset"
    assert said[("all", "best")]["best"] == "magexp_lm_gyro" and said[("subset", "best")]["best"] == "magyc_nls"
    text = report.headline(peer_claims.adjust(claims), frame, summary, args)
    assert "On the same 6,000 readings (every reading)" in text and "On the same 300 readings, evenly spaced" in text
    assert f"at most {magexp_side.LM_NFEV} evaluations" in text
