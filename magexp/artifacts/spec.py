"""The artifact language: typed, validated specs of ``experiments/<paper>/<stem>.yaml`` and ``paper.yaml``.

An artifact is a paper's figure or table as data::

    name: ding2024_fig5          # <firstauthor><year>_<fig|table><N> (default: the file stem)
    paper: ding2024              # the folder (default)
    title: ...
    kind: convergence            # a module of magexp.artifacts.kinds
    seeds: 30
    base: [scenario=ding2024_exp1, "?estimator.n_iterations=800"]   # overrides of every run ("?": if the key exists)
    cases: [[scenario=yuan2018_mode1], [scenario=yuan2018_mode3]]     # override lists, each crossed with the grid
    grid: {estimator: [pso, ipso], scenario.noise: [0, 2, 5, 10]}   # cartesian product
    skip_inapplicable: false     # drop cells whose estimator does not apply to the objective
    plot: {x: scenario.noise, hue: estimator, metric: fun, xscale: log}   # the keys of the kind's Plot
    summarise: [{quantity: final_rms, metric: fun}, {mode: parameters}]  # summary rows per cell
    ratios: [{quantity: improvement_ratio, metric: fun, numerator: {estimator: pso}, denominator: {estimator: ipso}}]
    success: {metric: fun, reference: truth_fun, factor: 1.1, floor: 1.0e-9}   # a run succeeds if metric <= factor reference + floor
    floor: 1.0e-9                # values below it (round-off) are compared and written as the floor
    reported:                    # the paper's numbers (printed precision: decimals, else inferred from the value)
      - {quantity: final_rms, match: {estimator: ipso, scenario.noise: 2}, value: 0.58}
      - {quantities: [S11, S12], match: {estimator: rdpso}, values: [-1.6013, 0.4010], decimals: 4}
      - {quantity: b1, match: {scenario: yuan2018_mode4}, value: -42.87, informative: false, reason: "..."}  # inside: uninformative
      - {quantity: F_g, match: {estimator: ekf}, value: 14.86, compared: false, reason: "..."}  # not compared
    tolerance: {rel: 0.15, reason: ...}   # only where the paper gives no run to compare with
    claims: [...]                # magexp.artifacts.claims.Claim: conditions on the results (by, section, role, figure, test)
    max_seeds: 400               # the most seeds a comparison's effect: may give a cell (magexp.artifacts.power)
    notes: ...                   # prose; {median:fun@estimator=ipso:.3g} interpolates a measured value
    caption: ...

The schema is the type hints of the dataclasses below, validated by pydantic
(:func:`magexp.artifacts.schema.build`; that module says why pydantic): a typo fails at load with
one line naming the key and the allowed ones, a wrong value with one naming the type it must have. The
papers are the folders of ``experiments/`` that hold an artifact (:func:`magexp.artifacts.paper_spec.papers`);
each has a ``paper.yaml`` (:class:`magexp.artifacts.paper_spec.Paper`: title, intro, order, deviations and its
``headline:`` claims, :class:`magexp.artifacts.paper_spec.Headline`).
"""

from __future__ import annotations

import copy
import decimal
import functools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from magexp.artifacts.claims import Claim
from magexp.artifacts import kinds, trends
from magexp.artifacts.monte_carlo import STATISTICS
from magexp.artifacts.schema import Bool, Float, Int, allowed, build, typed, unknown
from magexp.core.outcomes import ROUNDOFF_FLOOR, SUCCESS_FACTOR
from magexp.errors import MagexpError

#: the cap on a cell's seeds where an artifact gives no ``max_seeds`` (:mod:`magexp.artifacts.power`)
MAX_SEEDS = 400
#: minimum number of seeds of a cell whose interval is compared with a paper number
MIN_SEEDS_COMPARED = 30

#: sections of an artifact that an empty value (``success:``, ``reported: []``...) leaves at their default
_DEFAULTED_WHEN_EMPTY = ("success", "tolerance", "summarise", "ratios", "reported", "claims")


# -- the schema (validated by :func:`magexp.artifacts.schema.build`) -------------------------------------

@typed
@dataclass(frozen=True)
class Summarise:
    """One summary row per cell of ``metric`` (``mode: parameters``: one row per estimated parameter,
    ``only`` restricting it to some estimators; ``mode: ftest``: per axis the p-value of the F-test of
    the cell's estimate against the least-squares fit, :func:`magexp.artifacts.least_squares.f_test`).
    ``aggregate: mean`` for 0/1 outcomes; ``interval`` (see :mod:`magexp.artifacts.summary`)."""

    quantity: str = ""
    metric: str = ""
    mode: str = "value"
    aggregate: str = "median"
    truth_metric: str | None = None
    only: list[str] | None = None
    interval: str = "seeds"  # seeds: 2.5-97.5 % over seeds; ls: least-squares t-interval (one run on recorded data)

    def __post_init__(self):
        if self.interval not in ("seeds", "ls"):
            raise MagexpError(f"summarise.interval={self.interval!r} is not allowed: choose one of seeds, ls")
        if self.mode not in ("value", "parameters", "ftest"):
            raise MagexpError(f"summarise.mode={self.mode!r} is not allowed: choose one of value, parameters, ftest")
        if self.aggregate not in ("median", "mean"):
            raise MagexpError(f"summarise.aggregate={self.aggregate!r} is not allowed: choose one of median, mean")
        if self.mode != "parameters" and not self.quantity or self.mode == "value" and not self.metric:
            raise MagexpError("summarise: an entry needs quantity and metric (or mode: parameters)")


@typed
@dataclass(frozen=True)
class Ratio:
    """Per seed ``metric`` of the ``numerator`` cell over that of the ``denominator`` cell."""

    quantity: str
    metric: str
    numerator: dict[str, Any]
    denominator: dict[str, Any]


@typed
@dataclass(frozen=True)
class Tolerance:
    """A fixed tolerance: only where the paper gives no run to compare with (``reason`` says why).

    ``rel`` (``|v - p| <= rel |p|``), ``abs`` (``|v - p| <= abs``), ``factor`` (``p/f <= v <= p f``)
    or ``below`` (both below it); exactly one."""

    rel: Float | None = None
    abs: Float | None = None
    factor: Float | None = None
    below: Float | None = None
    reason: str = ""

    def __post_init__(self):
        given = [k for k in ("rel", "abs", "factor", "below") if getattr(self, k) is not None]
        if len(given) != 1:
            raise MagexpError(f"tolerance {given or 'empty'} is not allowed: give exactly one of rel, abs, factor, below")

    @property
    def kind(self) -> str:
        """Which of the tolerance's fields is set: ``below``, ``abs``, ``factor`` or ``rel``."""
        return next(k for k in ("below", "abs", "factor", "rel") if getattr(self, k) is not None)

    def text(self) -> str:
        """The tolerance as ``<kind> <value>`` (e.g. ``rel 0.15``)."""
        return f"{self.kind} {getattr(self, self.kind):g}"

    def holds(self, value: float, paper: float) -> bool:
        """Whether ``value`` is within this tolerance of the paper's ``paper``."""
        t = getattr(self, self.kind)
        return {"abs": lambda: abs(value - paper) <= t, "below": lambda: value < t and paper < t,
                "factor": lambda: paper / t <= value <= paper * t,
                "rel": lambda: abs(value - paper) <= t * abs(paper)}[self.kind]()


@typed
@dataclass(frozen=True)
class Reported:
    """One number the paper prints. ``decimals``: its printed decimal places (trailing zeros are lost
    in YAML floats); without it the precision is that of the shortest text of ``value``."""

    quantity: str
    value: Float
    match: dict[str, Any] = field(default_factory=dict)
    decimals: Int | None = None
    tolerance: Tolerance | None = None
    informative: Bool = True  # false: a row inside its interval is ``uninformative`` (``reason`` says why)
    compared: Bool = True  # false: the row is ``not compared`` (``reason`` says why: not comparable, a repeat)
    reason: str = ""
    statistic: str | None = None  # the paper's value is this statistic over its own ``trials`` (magexp.artifacts.monte_carlo)
    trials: Int | None = None

    def __post_init__(self):
        if not self.informative and not str(self.reason).strip():
            raise MagexpError(f"reported {self.quantity}: informative: false needs a reason (why the runs cannot pin it down)")
        if not self.compared and not str(self.reason).strip():
            raise MagexpError(f"reported {self.quantity}: compared: false needs a reason (why the number is not compared)")

    def half_unit(self) -> float:
        """Half a unit of the last printed digit: the paper's printing precision."""
        if self.decimals is not None:
            return 0.5 * 10.0 ** (-self.decimals)
        exponent = decimal.Decimal(repr(float(self.value))).normalize().as_tuple().exponent
        return 0.5 * 10.0 ** int(exponent)


@typed
@dataclass(frozen=True)
class Success:
    """A run succeeds when ``metric <= factor * reference + floor`` (``reference``: the metric of the
    true calibration on the same readings). Runs without the reference column are not judged. The
    rule and its defaults: :mod:`magexp.core.outcomes` (:func:`~magexp.core.outcomes.succeeded`)."""

    metric: str = "fun"
    reference: str = "truth_fun"
    factor: Float = SUCCESS_FACTOR
    floor: Float = ROUNDOFF_FLOOR


@typed
@dataclass
class Artifact:
    """A validated artifact spec (see the module docstring). ``plot`` is the ``Plot`` dataclass of
    its kind's module (:func:`magexp.artifacts.kinds.plot_of`)."""

    name: str
    paper: str
    title: str
    kind: str
    seeds: Int = 10
    base: list[str] = field(default_factory=list)
    grid: dict[str, list[Any]] = field(default_factory=dict)
    cases: list[list[str]] = field(default_factory=list)
    skip_inapplicable: Bool = False
    plot: Any = None
    summarise: list[Summarise] = field(default_factory=list)
    ratios: list[Ratio] = field(default_factory=list)
    reported: list[Reported] = field(default_factory=list)
    tolerance: Tolerance | None = None
    success: Success = field(default_factory=Success)
    floor: Float = ROUNDOFF_FLOOR
    claims: list[Claim] = field(default_factory=list)
    max_seeds: Int = MAX_SEEDS  # the cap on a cell's seeds from a comparison's effect (magexp.artifacts.power)
    notes: str = ""
    caption: str = ""
    report_table: list[str] = field(default_factory=list)
    requires_data: list[str] = field(default_factory=list)  # recordings read from magexp.paths.SHARED_DATA
    path: Any = field(default=None, metadata={"yaml": False})  # the file it was read from (set by the loader)

    def get(self, key: str, default=None):
        """Mapping-style access (``spec.get("caption")``), for code written against the old node."""
        value = getattr(self, key, default)
        return default if value is None else value


# -- reading an artifact ---------------------------------------------------------------------------------

def _expand_reported(entry, where: str) -> list:
    """A vector entry ``{quantities: [...], values: [...]}`` as one entry per quantity."""
    if not isinstance(entry, dict) or "quantities" not in entry and "values" not in entry:
        return [entry]
    qs, vs = entry.get("quantities"), entry.get("values")
    if not isinstance(qs, list) or not isinstance(vs, list) or len(qs) != len(vs):
        raise MagexpError(f"{where}: quantities and values must be lists of the same length")
    rest = {k: v for k, v in entry.items() if k not in ("quantities", "values")}
    return [{**rest, "quantity": q, "value": v} for q, v in zip(qs, vs)]


def _normalised(data: dict, path: Path) -> dict:
    """The artifact mapping as :class:`Artifact` reads it: ``name`` and ``paper`` default to the file
    stem and folder, an empty section is left at its default, vector ``reported`` entries are expanded
    (an error in one names its index among the expanded entries)."""
    data = {"name": path.stem, "paper": path.parent.name, **data}
    for key in _DEFAULTED_WHEN_EMPTY:
        if not data.get(key, True):
            del data[key]
    if isinstance(data.get("reported"), list):
        data["reported"] = [e for i, entry in enumerate(data["reported"])
                            for e in _expand_reported(entry, f"{path.stem}.reported[{i}]")]
    return data


def _check_fixed_tolerances(art: Artifact, where: str) -> None:
    """Every fixed tolerance says why; every reported number without one is compared over
    :data:`MIN_SEEDS_COMPARED` seeds at least (a least-squares interval, ``interval: ls``, needs no seeds)."""
    for tol in [art.tolerance] + [r.tolerance for r in art.reported]:
        if tol is not None and not tol.reason.strip():
            raise MagexpError(f"{where}: a fixed tolerance needs a reason (why the paper gives no run to compare with)")
    ls_items = {s.quantity for s in art.summarise if s.interval == "ls"}
    loose = [r.quantity for r in art.reported if r.quantity not in ls_items and (r.tolerance or art.tolerance) is None]
    if loose and art.seeds < MIN_SEEDS_COMPARED:
        raise MagexpError(f"{where}.seeds={art.seeds} is not allowed: a cell compared with a paper number "
                          f"({loose[0]}) needs at least {MIN_SEEDS_COMPARED} seeds")


def _check_trends(art: Artifact, where: str) -> None:
    """Every trend claim names a numeric grid axis and one range; no other claim has a trend's keys
    (:func:`magexp.artifacts.trends.spec_error`)."""
    for i, c in enumerate(art.claims):
        why = trends.spec_error(c, art.grid)
        if why:
            raise MagexpError(f"{where}.claims[{i}] ({c.id}): {why}")


def _check_monte_carlo(art: Artifact, where: str) -> None:
    """A reported statistic over the paper's trials names both ``statistic`` (one of
    :data:`~magexp.artifacts.monte_carlo.STATISTICS`) and ``trials`` (at least 1), and no fixed tolerance."""
    for i, r in enumerate(art.reported):
        at = f"{where}.reported[{i}] ({r.quantity})"
        if r.statistic is None and r.trials is None:
            continue
        if r.statistic not in STATISTICS:
            raise MagexpError(f"{at}: statistic={r.statistic!r} is not allowed: choose one of {', '.join(STATISTICS)}"
                              " (the paper's value is that statistic over its trials)")
        if r.trials is None or r.trials < 1:
            raise MagexpError(f"{at}: trials={r.trials!r} is not allowed: give the paper's number of trials, at least 1")
        if r.tolerance is not None or art.tolerance is not None:
            raise MagexpError(f"{at}: statistic={r.statistic!r} with a fixed tolerance is not allowed: "
                              "a statistic over trials is judged against our statistic's interval, not a tolerance")


def check_unique_ids(items: list, where: str) -> None:
    """Raise unless the ``id`` of every item of ``items`` differs from the others."""
    ids = [item.id for item in items]
    if len(set(ids)) != len(ids):
        raise MagexpError(f"{where}: ids must be unique, got {ids}")


def parse(data: dict, path: Path) -> Artifact:
    """Validate a loaded artifact mapping (``path`` names it in errors and gives the defaults)."""
    where = path.stem
    if not isinstance(data, dict):
        raise MagexpError(f"artifact {str(path)!r} is not a mapping of keys {', '.join(allowed(Artifact))}")
    data = _normalised(data, path)
    if "path" in data:
        raise MagexpError(unknown(where, "path", Artifact))
    if data.get("kind") not in kinds.names():
        raise MagexpError(f"{where}.kind={data.get('kind')!r} is not allowed: choose one of {', '.join(kinds.names())}")
    plot = data.pop("plot", None)
    art = build(Artifact, data, where)
    art.path = path
    art.plot = kinds.plot_of(art.kind, plot, where)
    _check_fixed_tolerances(art, where)
    _check_trends(art, where)
    _check_monte_carlo(art, where)
    check_unique_ids(art.claims, f"{where}.claims")
    if art.max_seeds < art.seeds:
        raise MagexpError(f"{where}.max_seeds={art.max_seeds} is not allowed: at least seeds ({art.seeds})")
    return art


#: libyaml's parser where PyYAML has it (the same safe constructor and resolver as ``yaml.safe_load``,
#: measured 10x faster on the 44 files of experiments/, the same objects: every command lists the papers and reads their specs)
_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


@functools.lru_cache(maxsize=256)
def _parsed(text: str):
    """The YAML ``text`` parsed with the safe loader, cached (specs are read again and again)."""
    return yaml.load(text, Loader=_LOADER)  # noqa: S506 (a safe loader)


def read_yaml(path: Path):
    """``yaml.safe_load`` of the file ``path``, parsed once per distinct content (a process lists the
    papers and reads every spec many times: planning, summary, claims, report); a fresh copy each call.
    """
    return copy.deepcopy(_parsed(Path(path).read_text()))


def load(path: Path | str) -> Artifact:
    """Read and validate an artifact YAML."""
    path = Path(path)
    if not path.exists():
        raise MagexpError(f"artifact {str(path)!r} does not exist")
    try:
        data = read_yaml(path)
    except yaml.YAMLError as exc:
        raise MagexpError(f"artifact {str(path)!r} is not valid YAML: {str(exc).splitlines()[0]}") from None
    return parse(data or {}, path)
