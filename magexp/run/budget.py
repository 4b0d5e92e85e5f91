"""Bounded work: what a run, a sweep, a reproduction or a calibration will cost, checked before it starts.

Every command estimates, from its config and the size of its data, the memory and the work of
what it is asked to do, and refuses what exceeds a limit in one :class:`~magexp.errors.MagexpError`
line naming the value and the limit, before anything is computed or written.

Work is counted in *reading-evaluations*: one evaluation of the cost (or residuals) over one
reading. A run costs

.. math::

    W = E \\cdot N, \\qquad
    E = \\begin{cases} P (T + 1) & \\text{a swarm: } P \\text{ particles, } T \\text{ iterations} \\\\
                       E_{max} & \\text{a black-box budget (} \\texttt{max\\_evaluations} \\text{)} \\\\
                       p \\, T & \\text{an iterative solver (} \\texttt{max\\_nfev}, \\texttt{max\\_iter}\\text{: a
                       Jacobian of } p = 12 \\text{ columns per step)} \\\\
                       T & \\text{a filter (} \\texttt{n\\_steps} \\text{)} \\\\
                       p & \\text{a closed form}
           \\end{cases}

for ``N`` readings, and its memory, in float64 numbers,

.. math::

    M = 8 \\left[ f_N N + f_P \\, P + C(N, P) + (T + 1) (f_T + f_S) \\right] \\text{ bytes}

with ``f_N`` numbers kept per reading (readings, reference, attitude, calibrated, features, the
bound's Jacobians), ``f_P`` per particle of a swarm (positions, velocities, personal bests, draws;
``P``: its particles, a population's ``popsize * p``, else 1), ``C(N, P)`` the working memory of one
cost call on ``P`` particles, as the run's problem declares it
(:meth:`magexp.problems.base.CalibrationProblem.cost_floats`, e.g. ``O(P)`` for the fused scalar and
vector costs, one chunk of ``O(max(CHUNK, P))`` for their numpy fallback, ``48 N P`` for the
gyro-aided cost), ``f_T`` per iteration (the history) and ``f_S = p`` per step of a filter (its
state): :data:`FLOATS_PER_READING`, :data:`FLOATS_PER_PARTICLE`, :data:`FLOATS_PER_ITERATION`,
:data:`PARAMETERS`. These are upper estimates of the run's peak above the interpreter and its
imports, meant to stop a mistake (a typed ``1e12``), not to plan a cluster; ``make bench`` writes the
estimate beside the measured peak of a large run (``results/bench.csv``, within 1 to 2 times it).

A sweep costs its jobs' runs (its size is counted from the override grammar *before* it is
expanded), a reproduction its artifacts' cells times their seeds, a calibration ``folds + 1``
fits of the recording (whose readings are counted from the file's size before it is read).

The limits (:data:`LIMITS`) are documented defaults, each overridable by an environment
variable: ``MAGEXP_MAX_RUN_MEMORY=16GiB magexp ...``. They are generous: every canonical
reproduction stays two orders of magnitude below them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import psutil

from magexp.core.datafiles import data_files
from magexp.core.limits import refuse_over, show
from magexp.errors import MagexpError
from magexp.problems import problem_class
from magexp.problems.base import CalibrationProblem

#: float64 numbers a run keeps per reading (readings, reference field, attitude, calibrated
#: readings, problem features, the bound's Jacobians); per particle of a swarm (its state and
#: draws: ten vectors of :data:`PARAMETERS`); per iteration (the history: best cost, evaluations
#: spent) and per filter step (its state)
FLOATS_PER_READING = 96  # measured: 68 a reading above the interpreter (make bench, 2e5 and 1e6 readings)
FLOATS_PER_PARTICLE = 120
FLOATS_PER_ITERATION = 2
#: parameters of the largest problem (a Jacobian's columns per solver step)
PARAMETERS = 12
#: bytes of the shortest line of a plain recording (``1 2 3`` and its newline)
SHORTEST_LINE = 6


# ---------------------------------------------------------------------------------------------
# estimates

def _int(node: Mapping | None, key: str) -> int | None:
    """The non-negative finite number ``node[key]`` as an int, else None (a setting an estimate can use)."""
    value = node.get(key) if node is not None else None
    return int(value) if isinstance(value, (int, float)) and not isinstance(value, bool) and value >= 0 \
        and math.isfinite(value) else None


@dataclass(frozen=True)
class Estimate:
    """The cost of one fit: ``readings`` N, ``evaluations`` E, ``iterations`` T, ``particles`` P,
    ``memory`` (bytes), and the factors as ``(key, value)`` pairs for messages."""

    readings: int
    evaluations: int
    iterations: int
    particles: int
    memory: int
    factors: tuple

    @property
    def work(self) -> int:
        """Reading-evaluations: ``E N``."""
        return self.evaluations * self.readings

    def subject(self) -> str:
        """``key=value`` of the largest factor (the one a mistake most likely typed)."""
        key, value = max(self.factors, key=lambda kv: kv[1])
        return f"{key}={value}"


def estimate_fit(estimator: Mapping, n_readings: int, prefix: str = "estimator.",
                 readings_key: str = "scenario.n_readings", floats_per_reading: int = FLOATS_PER_READING,
                 problem=CalibrationProblem) -> Estimate:
    """The :class:`Estimate` of fitting ``estimator`` (its settings: a config node or an estimator's
    ``vars()``) to ``n_readings`` readings of ``problem`` (its class: what its cost holds; the
    module docstring's ``E`` and ``M``)."""
    particles, state = _int(estimator, "n_particles"), 0
    popsize = _int(estimator, "popsize")
    factors = [(readings_key, n_readings)]
    if particles:
        factors.append((prefix + "n_particles", particles))
    width = particles or (popsize * PARAMETERS if popsize else 1)
    if (t := _int(estimator, "n_iterations")) is not None:
        iterations, evaluations = t, (particles or 1) * (t + 1)
        factors.append((prefix + "n_iterations", t))
    elif (e := _int(estimator, "max_evaluations")) is not None:
        iterations, evaluations = e // max(width, 1), e
        factors.append((prefix + "max_evaluations", e))
    elif (t := next((v for k in ("max_nfev", "max_iter") if (v := _int(estimator, k)) is not None), None)) is not None:
        key = "max_nfev" if _int(estimator, "max_nfev") is not None else "max_iter"
        iterations, evaluations = t, PARAMETERS * t
        factors.append((prefix + key, t))
    elif (t := _int(estimator, "n_steps")) is not None:
        iterations, evaluations = t, t
        state = PARAMETERS  # a filter keeps its state at every step
        factors.append((prefix + "n_steps", t))
    else:  # a closed form
        iterations, evaluations = 1, PARAMETERS
    memory = 8 * (n_readings * floats_per_reading + FLOATS_PER_PARTICLE * width
                  + problem.cost_floats(n_readings, width) + (iterations + 1) * (FLOATS_PER_ITERATION + state))
    return Estimate(readings=n_readings, evaluations=evaluations, iterations=iterations, particles=width,
                    memory=memory, factors=tuple(factors))


def run_readings(scenario: Mapping) -> int:
    """Readings of a run's scenario: ``n_readings``, else (a recording read whole) the most its
    file can hold, else the scenario's default size (300)."""
    n = _int(scenario, "n_readings")
    if n is not None:
        return n
    sizes = [Path(p).stat().st_size for p in data_files({"scenario": dict(scenario)})]
    return max(sizes) // SHORTEST_LINE if sizes else 300


def run_problem(cfg: Mapping):
    """The problem class of a run: its ``objective``, else its scenario's; the generic
    :class:`~magexp.problems.base.CalibrationProblem` when neither names one (a scenario whose
    class fixes it)."""
    objective = cfg.get("objective") or (cfg.get("scenario") or {}).get("objective")
    try:
        return problem_class(objective) if isinstance(objective, str) else CalibrationProblem
    except MagexpError:  # an unknown objective is refused where the problem is built, naming it
        return CalibrationProblem


def estimate_run(cfg: Mapping) -> Estimate:
    """The :class:`Estimate` of a run of the (composed or resolved) config ``cfg``."""
    scenario, estimator = cfg.get("scenario") or {}, cfg.get("estimator") or {}
    return estimate_fit(estimator, run_readings(scenario), problem=run_problem(cfg))


def check_estimate(est: Estimate, what: str) -> None:
    """Refuse one fit over the memory or work limit, naming its largest factor."""
    detail = ", ".join(f"{k.rpartition('.')[2]} {v}" for k, v in est.factors)
    refuse_over(est.memory, "run_memory", est.subject(), f"{what} ({detail}) needs")
    refuse_over(est.work, "run_work", est.subject(), f"{what} ({detail}) needs")


def check_run(cfg: Mapping) -> Estimate:
    """Refuse a run over the memory or work limit (and over the memory available); returns its estimate."""
    est = estimate_run(cfg)
    check_estimate(est, "the run")
    check_available(est.memory, est.subject())
    return est


def check_available(need: int, subject: str) -> None:
    """Refuse ``need`` bytes beyond the memory this machine has available now."""
    if need < 2 ** 28:  # under 256 MB: never worth asking the system
        return
    have = psutil.virtual_memory().available
    if need > have:
        raise MagexpError(f"{subject} is not allowed here: it needs about {show(need, 'bytes')} of memory and "
                          f"{show(have, 'bytes')} are available")


class Tally:
    """The runs of one command, counted and summed as they are planned (:meth:`add`); :meth:`check`
    refuses the total. ``subject`` names what made them (``--seeds 5``, the sweep's axes).

    Parameters
    ----------
    subject : str
        What made the runs, for the refusal's message.
    """

    def __init__(self, subject: str = "the command"):
        self.subject, self.runs, self.work = subject, 0, 0

    def add(self, est: Estimate, count: int = 1) -> None:
        """Count ``count`` runs of estimate ``est`` and refuse the total (:meth:`check`)."""
        self.runs += count
        self.work += est.work * count
        self.check()

    def check(self) -> None:
        """Refuse the runs counted so far over the runs or work limit."""
        refuse_over(self.runs, "runs", self.subject, "it makes")
        refuse_over(self.work, "work", self.subject, f"its {self.runs} runs need")


def check_runs(configs, subject: str = "the command") -> None:
    """Refuse a list of run configs over the runs, per-run or total limits (before any computes)."""
    refuse_over(len(configs), "runs", subject, "it makes")
    tally, seen = Tally(subject), {}
    for cfg in configs:
        scenario, estimator = cfg.get("scenario") or {}, cfg.get("estimator") or {}
        key = (id(scenario), id(estimator))  # runs of a cell share their nodes: estimated once
        if key not in seen:
            seen[key] = (scenario, estimator, estimate_run(cfg))
            check_estimate(seen[key][2], "a run")
        tally.add(seen[key][2])


# ---------------------------------------------------------------------------------------------
# sweeps and reproductions, counted before they are expanded

def sweep_axis_size(ov, options) -> int:
    """How many values the parsed override ``ov`` takes (``options``: a group's choices), without
    listing them: ``range()`` is counted arithmetically."""
    # lazy, sweeps only: 115 ms CPU to import (min of 3, after this module's imports)
    from hydra.core.override_parser.types import ChoiceSweep, Glob, RangeSweep

    if not ov.is_sweep_override():
        return 1
    value = ov.value()
    if isinstance(value, RangeSweep):
        start, stop, step = value.start, value.stop, value.step if value.step is not None else 1
        if not step:
            return 0
        return max(0, math.ceil((stop - start) / step))
    if isinstance(value, ChoiceSweep):
        return len(value.list)
    if isinstance(value, Glob):
        return len(value.filter(options))
    return len(list(ov.sweep_string_iterator()))


def check_sweep(parsed, options_of) -> int:
    """Refuse a sweep of more jobs than the runs limit, counted before it is expanded; returns the
    number of jobs. ``parsed``: Hydra's parsed overrides; ``options_of(key)``: a group's choices."""
    sizes = [(ov, sweep_axis_size(ov, options_of(ov.get_key_element()))) for ov in parsed]
    total = math.prod(n for _, n in sizes)
    if sizes:
        ov = max(sizes, key=lambda s: s[1])[0]
        refuse_over(total, "runs", ov.input_line.strip(), "the sweep has")
    return total


# ---------------------------------------------------------------------------------------------
# calibrations

#: float64 numbers a calibration keeps per reading: the readings, calibrated readings, their
#: magnitudes, the reference, a fold's training copy, the estimator's design matrix and its
#: factors (measured: 8 M readings of a plain file calibrated by ``ellipsoid`` with 5 folds
#: peak at 3.35 GiB, 56 numbers a reading with the interpreter)
CALIBRATION_FLOATS_PER_READING = 56


def estimate_file_readings(path: Path) -> int:
    """Readings a text recording holds, from its size and the mean length of the lines its first
    64 KiB end (an upper estimate for a file of shorter lines later on is not needed: the limit is
    generous). A head that ends no line (a binary or sparse file) counts the shortest line a reading:
    a 2 GiB file of zeros holds up to 358 million readings, not one 64 KiB line's worth."""
    size = Path(path).stat().st_size
    with open(path, "rb") as fh:
        head = fh.read(1 << 16)
    ends = head.count(b"\n")
    mean = max(SHORTEST_LINE, head.rfind(b"\n") // ends) if ends else SHORTEST_LINE
    return size // mean


def check_calibration(n_readings: int, folds: int, estimator, problem=CalibrationProblem) -> Estimate:
    """Refuse a calibration of ``n_readings`` readings over the readings limit, more held-out
    ``folds`` than readings, one fit over the memory or work limit, or ``folds + 1`` fits over
    the command's work limit; ``estimator``: its config node or the object (``vars()`` are its
    settings); ``problem``: the class of the objective fitted (what its cost holds)."""
    refuse_over(n_readings, "readings", f"{n_readings} readings", "the recording holds")
    if isinstance(folds, int) and folds > n_readings:
        raise MagexpError(f"folds={folds} is not allowed: at most {n_readings}, one per reading of the recording "
                          "(each held-out block must hold a reading)")
    settings = estimator if isinstance(estimator, Mapping) else vars(estimator)
    est = estimate_fit(settings, n_readings, readings_key="readings",
                       floats_per_reading=CALIBRATION_FLOATS_PER_READING, problem=problem)
    check_estimate(est, "one fit")
    fits = folds + 1 if isinstance(folds, int) and folds >= 2 else 1
    refuse_over(est.work * fits, "work", f"folds={folds}" if fits > 1 else est.subject(),
                f"{fits} fits of {est.work:.3g} reading-evaluations each need")
    check_available(est.memory, est.subject())
    return est
