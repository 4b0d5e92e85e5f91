"""Artifact kinds: one module per kind in this package, found by listing it (as benchopt finds its solvers).

A kind module ``<kind>.py`` holds all of its kind:

* its first docstring line: what the kind draws (the table of kinds in ``docs/extending.md`` is
  generated from it, :func:`docs_section`);
* ``Plot``: a frozen dataclass of its ``plot:`` keys with their defaults (the keys of every kind come
  from :class:`magexp.artifacts.plot_keys.CommonPlot`); a spec's ``plot:`` is validated against
  it when the spec is loaded (:func:`plot_of`), so a wrong key or type fails there;
* ``table(runs, plot)``: the table behind its figure from the runs, the only aggregation (medians,
  quartiles and intervals through :mod:`magexp.artifacts.tables`);
* ``draw(table, spec, axes=None)``: the figure from that table alone (the drawing code lives in
  :mod:`magexp.artifacts.plots`, imported only when a figure is drawn).

Adding a kind is adding one module here; modules whose name starts with ``_`` are not kinds.

``table`` and ``draw`` are documented here, once: a kind's own docstrings say in a line or two what
its table holds and what its figure draws (``tests/test_docstrings.py`` checks these sections and that
every kind's ``table`` and ``draw`` take the parameters they name).

Parameters of ``table``
-----------------------
runs : ArtifactRuns
    The artifact's runs (:func:`magexp.artifacts.plan.collect`): ``runs.spec`` the artifact,
    ``runs.cells`` its cells, ``runs.table`` one row per (cell, seed) with its metrics and
    ``runs.outputs`` each run's output, read from the run cache on access.
plot : Plot
    The artifact's ``plot:`` keys, an instance of the kind's ``Plot`` (:func:`plot_of`).

Returns of ``table``
--------------------
pandas.DataFrame
    The table behind the figure, written as the artifact's CSV: every number the figure shows.

Parameters of ``draw``
----------------------
table : pandas.DataFrame
    The table ``table`` wrote (the artifact's CSV, read back): the figure aggregates nothing.
spec : Artifact
    The artifact (:class:`magexp.artifacts.spec.Artifact`): its title, its typed ``plot`` and
    what it compares.
axes : matplotlib Axes or list of them, optional
    The caller's panels (default: a new figure).

Returns of ``draw``
-------------------
matplotlib.figure.Figure
    The figure (matplotlib is imported only by ``draw``).
"""

from __future__ import annotations

import dataclasses
import functools
import importlib
import pkgutil

from magexp.artifacts.schema import build
from magexp.core.generated import with_section
from magexp.errors import MagexpError

#: old plot keys, still read: each becomes its canonical key at load
ALIASES = {"value": "metric", "metrics": "metric"}


@functools.cache
def names() -> tuple[str, ...]:
    """The kinds: the modules of this package not starting with ``_``."""
    return tuple(sorted(m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_")))


def kind(name: str):
    """The module of the artifact kind ``name``."""
    if name not in names():
        raise MagexpError(f"artifact kind={name!r} is not allowed: choose one of {', '.join(names())}")
    return importlib.import_module(f"{__name__}.{name}")


def plot_of(name: str, data, where: str):
    """The typed ``plot:`` of an artifact of kind ``name``: its old keys renamed (:data:`ALIASES`,
    ``logx: true`` as ``xscale: log``), validated against the kind's ``Plot``; an unknown key or a
    value of the wrong type fails in one line naming ``where``, the kind, the key and the keys it has.
    """
    if data is not None and not isinstance(data, dict):
        raise MagexpError(f"{where}.plot={data!r} is not allowed: it must be a mapping")
    data = dict(data or {})
    for old, new in ALIASES.items():
        if old in data:
            data[new] = data.pop(old)
    if data.pop("logx", False):
        data["xscale"] = "log"
    return build(kind(name).Plot, data, f"{where}.plot (kind {name})")


def tabulate(runs):
    """The table behind the figure of ``runs.spec``: its kind's ``table(runs, plot)``."""
    return kind(runs.spec.kind).table(runs, runs.spec.plot)


# -- the table of kinds in docs/extending.md, written from the modules ---------------------------------

#: the lines around the generated table of kinds in docs/extending.md
BEGIN, END = "<!-- kinds: written by python -m magexp.artifacts.kinds; do not edit -->", "<!-- /kinds -->"


def _key(f) -> str:
    """A ``plot:`` key as the docs name it: its name, and its default where it has one."""
    if f.default is not dataclasses.MISSING:
        return f"`{f.name}`" if f.default is None else f"`{f.name}` (`{f.default}`)"
    return f"`{f.name}` (required)" if f.default_factory is dataclasses.MISSING else f"`{f.name}`"


def common_keys() -> set[str]:
    """The ``plot:`` keys every kind takes (those of :class:`magexp.artifacts.plot_keys.CommonPlot`)."""
    return set.intersection(*({f.name for f in dataclasses.fields(kind(n).Plot)} for n in names()))


def docs_section() -> str:
    """The generated part of docs/extending.md: the keys every kind takes, then one row per kind (what it
    draws, from its module's first docstring line, and its own ``plot:`` keys with their defaults).
    """
    common = common_keys()
    first = dataclasses.fields(kind(names()[0]).Plot)
    lines = [BEGIN, "Every kind takes " + ", ".join(_key(f) for f in first if f.name in common) + ".", "",
             "| kind | what it draws | its own keys (default) |", "|---|---|---|"]
    for name in names():
        module = kind(name)
        own = [_key(f) for f in dataclasses.fields(module.Plot) if f.name not in common]
        lines.append(f"| `{name}` | {module.__doc__.splitlines()[0].rstrip('.')} | {', '.join(own) or 'none'} |")
    return "\n".join(lines + [END])


def with_docs_section(text: str) -> str:
    """``text`` (docs/extending.md) with its generated section replaced by :func:`docs_section`."""
    return with_section(text, BEGIN, END, docs_section())
