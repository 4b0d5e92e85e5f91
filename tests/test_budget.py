"""Bounded work (:mod:`magexp.run.budget`): every command refuses work over a limit in one line naming the
value and the limit, exit 2, before anything runs or is written.

"Before anything runs" is asserted by counting: the fit, the run and the planning functions are
wrapped, and a refused command must not have called them (never by timing)."""

from __future__ import annotations

import numpy as np
import pytest

from magexp.core import limits
from magexp.run import budget
from magexp.run.compose import compose_config, options, parse_overrides, resolved
from magexp.errors import MagexpError

CALIB = "# magexp-recording v1\n# unit: nT\nbx,by,bz\n"


@pytest.fixture
def started(monkeypatch):
    """Counts of what a command started: runs (``executor.run_batch``), fits of a calibration
    (``calibration.fit.fit_model`` and ``fold_fit``), reproduction plans (``artifacts.plan_artifact``), recordings read."""
    import magexp.artifacts.plan
    import magexp.calibration.fit
    import magexp.core.recordings
    import magexp.run.executor

    counts = {"runs": 0, "fits": 0, "plans": 0, "reads": 0}

    def counted(module, name, key):
        original = getattr(module, name)

        def wrapper(*args, **kwargs):
            counts[key] += 1
            return original(*args, **kwargs)

        monkeypatch.setattr(module, name, wrapper)

    counted(magexp.run.executor, "run_batch", "runs")
    counted(magexp.calibration.fit, "fit_model", "fits")  # the whole recording's fit
    counted(magexp.calibration.fit, "fold_fit", "fits")  # a held-out fold's
    counted(magexp.artifacts.plan, "plan_artifact", "plans")
    counted(magexp.core.recordings, "load_recording", "reads")
    return counts


def tree(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


@pytest.fixture
def work(tmp_path):
    """An empty working folder (``tmp_path`` also holds the test's caches)."""
    folder = tmp_path / "work"
    folder.mkdir()
    return folder


def one_line(err: str, *words: str) -> None:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    for word in words:
        assert word in lines[0], (word, lines[0])


def recording(path, n: int, seed: int = 0):
    """An ``n``-reading recording of a distorted sphere (a calibration succeeds on it)."""
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(n, 3))
    u = 48000 * u / np.linalg.norm(u, axis=1, keepdims=True) * [1.1, 0.95, 1.02] + [120, -75, 32]
    path.write_text(CALIB + "".join(f"{a:.3f},{b:.3f},{c:.3f}\n" for a, b, c in u))
    return path


RUN_CASES = [  # one run over a limit: the words its line must name
    (["estimator.n_iterations=1000000000000"], ["estimator.n_iterations=1000000000000", "TiB", "8 GiB",
                                                 "MAGEXP_MAX_RUN_MEMORY"]),
    (["estimator.n_particles=100000000"], ["estimator.n_particles=100000000", "MAGEXP_MAX_RUN_MEMORY"]),
    (["scenario.n_readings=2000000000"], ["scenario.n_readings=2000000000", "MAGEXP_MAX_RUN_MEMORY"]),
    (["estimator.n_iterations=10000000"], ["estimator.n_iterations=10000000", "reading-evaluations",
                                           "MAGEXP_MAX_RUN_WORK"]),
    (["estimator=lm", "estimator.max_nfev=100000000"], ["estimator.max_nfev=100000000", "MAGEXP_MAX_RUN_WORK"]),
    (["estimator=de", "estimator.max_evaluations=1000000000"], ["estimator.max_evaluations=1000000000",
                                                                 "MAGEXP_MAX_RUN_WORK"]),
]


@pytest.mark.parametrize("args, words", RUN_CASES, ids=[" ".join(a) for a, _ in RUN_CASES])
def test_a_run_over_a_limit_is_refused_before_it_starts(cli, work, started, args, words):
    result = cli(*args, cwd=work)
    assert result.returncode == 2
    one_line(result.stderr, *words)
    assert started["runs"] == 0 and tree(work) == []


def test_a_sweep_is_counted_before_it_is_expanded(cli, work, started, monkeypatch):
    import magexp.run.preflight

    def no_expansion(*overrides):  # expanding 10^8 jobs is itself the work to refuse
        raise AssertionError("the sweep was expanded before its size was checked")

    monkeypatch.setattr(magexp.run.preflight, "sweep_jobs", no_expansion)
    result = cli("-m", "seed=range(0,100000000)", "estimator=pso,ipso", cwd=work)
    assert result.returncode == 2
    one_line(result.stderr, "seed=range(0,100000000)", "200000000 runs", "200000 runs", "MAGEXP_MAX_RUNS")
    assert started["runs"] == 0 and tree(work) == []


def test_a_sweep_over_the_total_work_is_refused(cli, work, started, monkeypatch):
    monkeypatch.setenv("MAGEXP_MAX_WORK", "1e9")  # each ipso run: 50 x 801 x 300 = 1.2e7
    result = cli("-m", "seed=range(0,100)", cwd=work)
    assert result.returncode == 2
    one_line(result.stderr, "the sweep", "reading-evaluations", "MAGEXP_MAX_WORK")
    assert started["runs"] == 0 and tree(work) == []


@pytest.mark.parametrize("env, value, allowed", [("MAGEXP_MAX_RUNS", "6", True), ("MAGEXP_MAX_RUNS", "5", False),
                                                 ("MAGEXP_MAX_RUNS", "1e1", True)])
def test_the_limits_are_configured_by_the_environment(monkeypatch, env, value, allowed):
    monkeypatch.setenv(env, value)
    parsed = parse_overrides(["seed=range(3)", "estimator=ipso,pso"])  # 6 jobs
    if allowed:
        assert budget.check_sweep(parsed, options) == 6
    else:
        with pytest.raises(MagexpError, match="seed=range.*6 runs.*5 runs.*MAGEXP_MAX_RUNS"):
            budget.check_sweep(parsed, options)


@pytest.mark.parametrize("value", ["abc", "-3", "0", "nan", "4 parsecs"])
def test_a_bad_limit_is_one_line(cli, work, monkeypatch, value):
    monkeypatch.setenv("MAGEXP_MAX_RUN_MEMORY", value)
    result = cli("seed=1", cwd=work)
    assert result.returncode == 2
    one_line(result.stderr, "MAGEXP_MAX_RUN_MEMORY", repr(value), "GiB")


def test_amounts_read_with_units():
    assert limits.parse_amount("4GiB") == 4 * 2 ** 30
    assert limits.parse_amount("2e5") == 200000
    assert limits.parse_amount("10M") == 1e7
    assert limits.parse_amount("1.5 TiB") == 1.5 * 2 ** 40
    assert limits.parse_amount("twelve") is None


def test_the_sweep_size_is_counted_without_listing_it():
    sizes = [budget.sweep_axis_size(ov, options("estimator")) for ov in parse_overrides(
        ["seed=range(0,100000000)", "a=1,2,3", "b=choice(1,2)", "c=range(0,1,0.25)", "d=5", "e=range(10,0,-3)",
         "estimator=glob(*)"])]
    assert sizes == [100000000, 3, 2, 4, 1, 4, len(options("estimator"))]


def test_the_estimate_follows_the_equations():
    """E = P (T + 1) for a swarm; M = 8 [96 N + 120 P + C(N, P) + 2 (T + 1)] bytes, C the cost's own
    working memory: 14 P for the fused scalar cost (never N x P), 48 N P for the gyro-aided one."""
    from magexp.problems import kernels

    plain = resolved(compose_config(["estimator=ipso", "scenario=ding2024_exp1"]))
    est = budget.estimate_run(plain)
    assert est.evaluations == 50 * 801 and est.work == 50 * 801 * 300
    cost = 14 * 50 if kernels.fused_enabled() else kernels.working_floats(50, fused=False)
    assert est.memory == 8 * (300 * 96 + 120 * 50 + cost + 801 * 2)
    lm = budget.estimate_run(resolved(compose_config(["estimator=lm"])))
    assert lm.evaluations == 12 * 2000 and lm.particles == 1
    kf = budget.estimate_run(resolved(compose_config(["estimator=kf", "scenario=yan2022_sim"])))
    assert kf.memory == 8 * (12 * 96 + 120 + 3 * 12 + 601 * (2 + 12))  # yan2022_sim names no objective: generic
    gyro = budget.estimate_run({**plain, "objective": "gyro"})
    assert gyro.memory == 8 * (300 * 96 + 120 * 50 + 48 * 300 * 50 + 801 * 2)


@pytest.mark.parametrize("fused", [True, False])
def test_a_fused_cost_needs_memory_of_order_n_plus_p(fused, monkeypatch):
    """make bench's run (1e6 readings, 500 particles) is within the 8 GiB default on both paths
    of the fused cost, and doubling the particles adds O(P), not O(N P)."""
    from magexp.problems import kernels

    monkeypatch.setenv("MAGEXP_NUMBA", "1" if fused else "0")
    if fused and not kernels.fused_enabled():
        pytest.skip("numba is not installed")
    run = ["scenario=ding2024_exp1", "estimator=ipso", "scenario.n_readings=1000000", "estimator.n_iterations=3"]
    small, large = (budget.check_run(resolved(compose_config([*run, f"estimator.n_particles={p}"])))
                    for p in (500, 1000))
    assert small.memory < 2 ** 30 and large.memory - small.memory < 8 * 500 * 1000


@pytest.mark.full  # two child processes of 200 000 readings; make test: the estimate's arithmetic above
def test_the_memory_estimate_of_a_fused_run_bounds_its_measured_peak():
    """The guard's estimate of a command-line ipso run (200 000 readings, 500 particles) is at
    least its peak resident memory above the baseline and at most twice it, both measured in
    child processes (:func:`magexp.perf.footprint.memory_check`; make bench does it at 1e6)."""
    from magexp.perf.footprint import memory_check

    m = memory_check(200_000, 500, 3)
    assert 1.0 <= m["ratio"] <= 2.0, m


def test_every_papers_reproduction_is_within_the_runs_limit():
    from magexp.artifacts.reproduce import available_papers, check_reproduction, select

    selected = select(available_papers(), None)
    runs = check_reproduction(selected, None)
    assert 10000 < runs < limits.limit("runs") / 8  # make reproduce: about 20600 runs, far from the limit


def test_reproduce_seeds_is_refused_before_planning(work, started, capsys):
    from magexp.artifacts.reproduce import main

    assert main(["yan2022", "--seeds", "100000000", "--out", str(work / "out")]) == 2
    one_line(capsys.readouterr().err, "--seeds 100000000", "MAGEXP_MAX_RUNS")
    assert started["plans"] == 0 and started["runs"] == 0 and tree(work) == []


def test_run_many_refuses_before_any_run(started):
    from magexp.run.executor import run_many

    plain = resolved(compose_config(["estimator.n_iterations=100000000"]))
    with pytest.raises(MagexpError, match="estimator.n_iterations=100000000.*MAGEXP_MAX_RUN_WORK"):
        run_many([plain, {**plain, "seed": 1}], jobs=1)
    assert started["runs"] == 0


CALIBRATE_CASES = [  # (overrides, words)
    (["folds=1000000000"], ["folds=1000000000", "at most 40"]),
    (["estimator=ipso", "estimator.n_particles=10000000000"], ["estimator.n_particles=10000000000", "TiB",
                                                                "MAGEXP_MAX_RUN_MEMORY"]),
    (["estimator=ipso", "estimator.n_iterations=100000000"], ["estimator.n_iterations=100000000",
                                                               "MAGEXP_MAX_RUN_WORK"]),
]


@pytest.mark.parametrize("args, words", CALIBRATE_CASES, ids=[" ".join(a) for a, _ in CALIBRATE_CASES])
def test_a_calibration_over_a_limit_is_refused_before_a_fit(cli, work, started, args, words):
    data = recording(work / "rec.csv", 40)
    before = tree(work)
    result = cli("calibrate", f"data.path={data}", f"out={work / 'cal'}", *args, cwd=work)
    assert result.returncode == 2
    one_line(result.stderr, *words)
    assert started["fits"] == 0 and tree(work) == before


def test_folds_times_fits_over_the_work_limit_is_refused(work, started, monkeypatch):
    from magexp import calibrate

    monkeypatch.setenv("MAGEXP_MAX_WORK", "1e9")
    data = recording(work / "rec.csv", 2000)
    with pytest.raises(MagexpError, match=r"folds=1000 is not allowed: 1001 fits .*MAGEXP_MAX_WORK"):
        calibrate(data, estimator="ipso", folds=1000)
    with pytest.raises(MagexpError, match="folds=10000000 is not allowed: at most 2000"):
        calibrate(data, folds=10 ** 7)  # the Python API: refused, not 15 minutes of fits
    assert started["fits"] == 0


def test_a_recording_too_big_is_refused_before_it_is_read(cli, work, started, monkeypatch):
    monkeypatch.setenv("MAGEXP_MAX_READINGS", "1000")
    data = work / "big.txt"
    data.write_text("".join(f"{i}.5 {i % 7}.25 {i % 11}.125\n" for i in range(5000)))
    before = tree(work)
    result = cli("calibrate", f"data.path={data}", "data.unit=uT", f"out={work / 'cal'}", cwd=work)
    assert result.returncode == 2
    one_line(result.stderr, f"data.path='{data}'", "hold about 5", "1000 readings", "MAGEXP_MAX_READINGS")
    assert started["reads"] == 0 and started["fits"] == 0 and tree(work) == before


def test_a_recording_whose_calibration_would_not_fit_in_memory_is_refused_unread(cli, work, started, monkeypatch):
    monkeypatch.setenv("MAGEXP_MAX_RUN_MEMORY", "100KiB")
    data = work / "big.txt"
    data.write_text("".join(f"{i}.5 {i % 7}.25 {i % 11}.125\n" for i in range(5000)))
    result = cli("calibrate", f"data.path={data}", "data.unit=uT", f"out={work / 'cal'}", cwd=work)
    assert result.returncode == 2
    one_line(result.stderr, f"data.path='{data}'", "100 KiB", "MAGEXP_MAX_RUN_MEMORY")  # reading it, or calibrating
    assert started["reads"] == 0 and started["fits"] == 0


def test_a_sparse_recording_is_refused_by_its_size_unread(tmp_path):
    """A 2 GiB file of zeros (sparse: no line ends in its head) counts as its size in shortest lines and is
    refused before it is read (issue 34: it took 140 s to reach its one-line refusal)."""
    import time

    from magexp.errors import MagexpError
    from magexp.run.files import check_recording_file

    big = tmp_path / "big.csv"
    with open(big, "wb") as fh:
        fh.truncate(2 * 2 ** 30)
    start = time.perf_counter()
    with pytest.raises(MagexpError, match="big.csv.*over the limit.*MAGEXP_MAX_"):  # its reading's memory, first
        check_recording_file(big)
    assert time.perf_counter() - start < 1
