"""The whole spec checked before any run: a mistake in an artifact or a ``paper.yaml`` is one line, never a
verdict.

A spec is read and typed at load (:mod:`magexp.artifacts.schema`); what only its plan can tell is checked
here, once its cells are planned (:func:`check_plan`, called by
:func:`magexp.artifacts.sample_sizes.plan_with_effects`: every artifact of a reproduction is planned before any
run) and once more on the stored runs a redraw judges (:func:`check_claims`):

* every claim's ``metric`` is a pandas expression (``pandas.eval``) of the columns its runs will have:
  the cell's settings (its grid, cases and base keys, dotted names written as they are,
  :func:`magexp.artifacts.selection.expression`) and every column its planned runs may write, the union of the
  declarations of their writers (:func:`magexp.artifacts.run_columns.planned_columns`: the runner's, the core
  metrics', the problem's, the scenario's, the estimator's and an analysis step's, and the columns the runs table
  adds), so a metric a new estimator declares is known before any run, with or without ``results/``; the check
  evaluates it on one row per planned cell with the same function the claim is judged with
  (:func:`magexp.artifacts.selection.column`), so the two agree;
* every claim's ``where`` (a threshold's, a success rate's, a trend's) and each of a comparison's ``cells``
  selects at least one planned cell (a key that is no
  setting must be a runs column, a row filter such as ``succeeded``, or ``seeds``);
* every ``reported`` entry's ``match`` selects at least one planned cell (the cells' overrides, what
  :func:`magexp.artifacts.tables.reported_entry` matches);
* every part of a headline and of its readings names a claim of the paper
  (:func:`magexp.artifacts.paper_spec.check_headlines`, when the paper's artifacts are read).

Each failure raises :class:`~magexp.errors.MagexpError` naming the artifact, the entry, the bad value and
what exists: the command prints it as one line and exits 2, with nothing run. A claim that still cannot be
evaluated when it is judged is a bug of this check (:func:`magexp.artifacts.claims.evaluate` says so).
"""

from __future__ import annotations

import difflib
import re

import pandas as pd

from magexp.artifacts.plan import objective_of, setting_of
from magexp.artifacts.run_columns import cell_configs, planned_columns
from magexp.artifacts.selection import cell_settings, column, expression, restrict
from magexp.artifacts.tables import matches
from magexp.errors import MagexpError

#: names an expression may use that are no column (``pandas.eval``'s words)
_WORDS = {"and", "or", "not", "in", "True", "False"}
_NAME = re.compile(r"(?<![\w.])[A-Za-z_]\w*(?:\.\w+)*(?!\w*\s*\()")


def _numeric(values: list):
    """``values`` as numbers where each is one (a setting as a runs CSV reads it back), else as given."""
    try:
        return [float(v) for v in values]
    except (TypeError, ValueError):
        return values


def planned_table(plan) -> pd.DataFrame:
    """One row per planned cell of ``plan`` (:class:`magexp.artifacts.plan.ArtifactPlan`), as its runs
    table will hold it: settings, names, and every column a run may write (1.0).

    Parameters
    ----------
    plan : ArtifactPlan
        The artifact's planned cells and configs.

    Returns
    -------
    pandas.DataFrame
        The skeleton runs table the claims are checked on.
    """
    first = cell_configs(plan)
    rows = []
    for ci, cell in enumerate(plan.cells):
        cfg = first.get(ci, {})
        rows.append({"cell": ci, "seed": 0, **cell, "setting": setting_of(plan.overrides[ci]),
                     "scenario": (cfg.get("scenario") or {}).get("name", ""),
                     "estimator": (cfg.get("estimator") or {}).get("name", ""), "objective": objective_of(cfg)})
    table = pd.DataFrame(rows)
    for key in {k for cell in plan.cells for k in cell}:
        table[key] = _numeric(table[key].tolist())
    metrics = sorted(planned_columns(plan) - set(table.columns))
    return pd.concat([table, pd.DataFrame(1.0, index=table.index, columns=metrics)], axis=1)


def check_plan(plan) -> None:
    """Raise :class:`~magexp.errors.MagexpError` unless every claim and reported entry of ``plan.spec``
    can be judged on the planned cells (module docstring).

    Parameters
    ----------
    plan : ArtifactPlan
        The artifact's plan (:func:`magexp.artifacts.plan.plan_artifact`).
    """
    table = planned_table(plan)
    check_claims(plan.spec, table)
    check_reported(plan.spec, [dict(o.split("=", 1) for o in overrides) for overrides in plan.overrides])


def check_claims(spec, table: pd.DataFrame) -> None:
    """Raise :class:`~magexp.errors.MagexpError` unless each claim's metric is an expression of ``table``'s
    columns and its ``where`` and each of its ``cells`` select a cell of ``table``.

    Parameters
    ----------
    spec : Artifact
        The artifact.
    table : pandas.DataFrame
        Its runs table: the planned one (:func:`planned_table`) or the stored one.
    """
    if not spec.claims or not len(table):
        return
    settings = cell_settings(table)
    for claim in spec.claims:
        where = f"{spec.name}.claims[{claim.id}]"
        check_metric(f"{where}.metric", claim.metric, table, settings)
        selections = ([(f"cells[{i}]", c) for i, c in enumerate(claim.cells)] if claim.kind in ("ordering", "winner")
                      else [("where", claim.where)])
        for key, selection in selections:
            _check_selection(f"{where}.{key}", selection, table, settings)


def _setting_keys(settings: dict) -> list[str]:
    """The setting names of the cells (``{cell: {key: value}}``), sorted."""
    return sorted({k for s in settings.values() for k in s})


def check_metric(where: str, metric: str, table: pd.DataFrame, settings: dict) -> None:
    """Raise :class:`~magexp.errors.MagexpError` (naming ``where``) unless ``metric`` is a column of
    ``table`` or a pandas expression of its columns that evaluates on it.

    Parameters
    ----------
    where : str
        The entry, as the error names it (``artifact.claims[id].metric``).
    metric : str
        The claim's metric.
    table : pandas.DataFrame
        The runs table it is judged on.
    settings : dict
        ``{cell: {key: value}}`` of ``table`` (:func:`magexp.artifacts.selection.cell_settings`).
    """
    text = re.sub(r"`[^`]*`", " ", expression(metric, table.columns))
    unknown = [n for n in _NAME.findall(text) if n not in table.columns and n not in _WORDS]
    bad = [n.strip("`") for n in re.findall(r"`[^`]*`", metric) if n.strip("`") not in table.columns] + unknown
    if bad:
        near = difflib.get_close_matches(bad[0], [str(c) for c in table.columns], n=3, cutoff=0.6)
        raise MagexpError(f"{where}={metric!r} is not allowed: {bad[0]!r} is no column of its runs "
                          f"(nearest: {', '.join(near) or 'none'}; its settings: {', '.join(_setting_keys(settings))}); "
                          "a metric is a pandas expression of the runs' columns, dotted config keys written as they are")
    try:
        column(table, metric)
    except MagexpError as exc:
        raise MagexpError(f"{where}={metric!r} is not allowed: {str(exc).splitlines()[0]}") from None


def _check_selection(where: str, selection: dict, table: pd.DataFrame, settings: dict) -> None:
    """Raise unless every key of ``selection`` is a setting, a runs column (a row filter) or ``seeds``,
    and its settings select at least one cell of ``table``."""
    keys = _setting_keys(settings)
    stray = [k for k in selection if k != "seeds" and k not in keys and k not in table.columns]
    if stray:
        raise MagexpError(f"{where}={selection} is not allowed: {stray[0]!r} is no setting of its cells "
                          f"(settings: {', '.join(keys)}) nor a runs column")
    _, rest, _ = restrict(table, selection)
    if not any(matches(rest, s) for s in settings.values()):
        raise MagexpError(f"{where}={selection} selects no planned cell: its cells have "
                          f"{_values_of(rest, list(settings.values()))}")


def _values_of(selection: dict, cells: list[dict]) -> str:
    """What the ``cells`` hold for each key of ``selection`` (``key in [v1, v2]``), for an error line."""
    parts = []
    for key in selection:
        seen = sorted({str(c[key]) for c in cells if key in c})
        parts.append(f"{key} in [{', '.join(seen)}]" if seen else f"no {key}")
    return "; ".join(parts) or "no cell"


def check_reported(spec, cells: list[dict]) -> None:
    """Raise :class:`~magexp.errors.MagexpError` unless every ``reported`` entry of ``spec`` matches one
    of ``cells`` (each planned cell's ``{key: value}`` overrides).

    Parameters
    ----------
    spec : Artifact
        The artifact.
    cells : list of dict
        The planned cells' overrides (:func:`magexp.artifacts.tables.cell_overrides`).
    """
    for i, entry in enumerate(spec.reported):
        if not any(matches(entry.match, c) for c in cells):
            raise MagexpError(f"{spec.name}.reported[{i}] ({entry.quantity}) match={dict(entry.match)} selects no "
                              f"planned cell: its cells have {_values_of(entry.match, cells)}")
