"""Shared matplotlib style (Agg backend) and helpers used by every kind.

The Agg backend is chosen for magexp's own processes; inside a Jupyter kernel (``Calibration.plot()`` in
a notebook) the kernel's inline backend is left as it is, so that the figure shows."""

from __future__ import annotations

import functools
import math
import sys
from pathlib import Path

import matplotlib
import numpy as np

from magexp.artifacts.plots import VECTOR
from magexp.artifacts.tables import scenario_label  # noqa: F401  (the kinds' legends and ticks use it from here)
from magexp.core.atomic import atomic_path
from magexp.errors import MagexpError

if "ipykernel" not in sys.modules:  # a notebook keeps its inline backend
    matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402
from matplotlib import mathtext  # noqa: E402

STYLE = {
    "figure.dpi": 110,
    "savefig.dpi": 110,
    "font.size": 9,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "legend.fontsize": 8,
    "legend.frameon": False,
}
plt.rcParams.update(STYLE)


def share_mathtext_parses() -> bool:
    """Let every renderer share one cache of parsed math text (e.g. a log axis' ``$10^{-2}$`` labels).

    Matplotlib caches :meth:`matplotlib.mathtext.MathTextParser.parse` per parser, and every renderer
    owns a parser: each figure, and each of its two formats (PNG, PDF), parses the same labels again.
    A parse depends only on the parser's output type and the arguments of the cached call, so one
    cache per output type gives the same glyphs, hence the same bytes, with fewer parses (a test
    compares the bytes of figures drawn with and without it).
    """
    cached = getattr(mathtext.MathTextParser, "_parse_cached", None)
    if getattr(cached, "shared", False):
        return True
    original = getattr(cached, "__wrapped__", None)
    if original is None:
        return False
    parsers = {"vector": mathtext.MathTextParser("path"), "raster": mathtext.MathTextParser("agg")}

    @functools.lru_cache(maxsize=4096)
    def parse(output_type, s, dpi, prop, antialiased, load_glyph_flags):
        return original(parsers[output_type], s, dpi, prop, antialiased, load_glyph_flags)

    def shared(self, s, dpi, prop, antialiased, load_glyph_flags):
        return parse(self._output_type, s, dpi, prop, antialiased, load_glyph_flags)

    shared.shared, shared.original, shared.cache_info = True, cached, parse.cache_info
    mathtext.MathTextParser._parse_cached = shared
    return True


share_mathtext_parses()


def label(spec, key: str, value=None) -> str:
    """Readable label of a grid key (``plot.labels`` in the artifact may rename keys)."""
    names = dict(spec.plot.get("labels", {}) or {})
    name = names.get(key, key.split(".")[-1].replace("_", " "))
    return name if value is None else f"{name} = {value}"


def unit(spec) -> str:
    """The unit of the readings an artifact's scenarios generate (``plot.unit``, default ``nT``; Yuan's
    scenarios: ``mG``), printed wherever a figure draws a field, an offset or an objective in it.
    """
    return str(spec.plot.get("unit", "nT"))


def panels(n: int, *, width: float = 3.4, height: float = 2.8, rows: int = 1, axes=None):
    """A row (or grid) of ``n`` axes; ``axes`` (``n`` Axes of the caller's figure, or one Axes for
    ``n == 1``) draws into the caller's own layout instead of a new figure.
    """
    if axes is not None:
        axes = [axes] if hasattr(axes, "plot") else list(axes)
        if len(axes) != n:
            raise MagexpError(f"axes: {len(axes)} given, this figure draws {n} panels")
        return axes[0].figure, axes
    cols = -(-n // rows)
    if n == 1:  # a single panel gets the room of a figure
        width, height = 6.0, 4.2
    fig, axes = plt.subplots(rows, cols, figsize=(width * cols, height * rows), squeeze=False, sharex=False,
                             layout="constrained")
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    return fig, list(axes.ravel()[:n])



def quantities_of(spec, metric: str) -> set[str]:
    """The summary quantities computed from the runs column ``metric`` (a ratio's quantity is its
    own): the ``reported:`` entries of these are the paper's values of what a figure draws.
    """
    names = {s.quantity for s in spec.get("summarise", []) if getattr(s, "metric", None) == metric and s.quantity}
    return names | {r.quantity for r in spec.get("ratios", []) if r.quantity == metric}


def paper_values(spec, metric: str) -> list:
    """The artifact's ``reported:`` entries of ``metric`` (by name, or by a quantity summarised from it)."""
    names = quantities_of(spec, metric) | {metric}
    return [e for e in spec.get("reported", []) if e.quantity in names]


def legend_entries(axes) -> dict:
    """``{label: handle}`` of every labelled artist of ``axes``, each label once (first seen)."""
    unique = {}
    for ax in axes:
        for handle, name in zip(*ax.get_legend_handles_labels()):
            unique.setdefault(name, handle)
    return unique


def shared_legend(fig, axes, entries: dict | None = None, *, ncols: int = 4, inside: bool = False, **kwargs):
    """One legend for the panels ``axes``: below them, outside, where the figure has constrained
    layout (its own figures) and not ``inside``; else in the first panel (a caller's axes).
    ``entries``: ``{label: handle}`` (default: :func:`legend_entries`); nothing is drawn without any.
    """
    entries = legend_entries(axes) if entries is None else entries
    if not entries:
        return None
    if not inside and type(fig.get_layout_engine()).__name__ == "ConstrainedLayoutEngine":
        return _fitting_legend(fig, entries, min(ncols, len(entries)), **kwargs)
    return axes[0].legend(entries.values(), entries.keys(), **kwargs)


def _fitting_legend(fig, entries: dict, ncols: int, **kwargs):
    """The figure's legend below its panels in the most columns, up to ``ncols``, that keep it within
    the figure's width (long entries: fewer columns, never a legend that widens the figure)."""
    renderer = fig.canvas.get_renderer()
    for n in range(ncols, 0, -1):
        legend = fig.legend(entries.values(), entries.keys(), loc="outside lower center", ncols=n, **kwargs)
        if n == 1 or legend.get_window_extent(renderer).width <= fig.bbox.width:
            return legend
        legend.remove()


#: attribute naming the data column a colour bar (and the image it belongs to) shows
COLUMN_ATTR = "magexp_column"


def drawn_from(image, column: str):
    """Record on ``image`` the data column its cells were filled from; returns ``image``."""
    setattr(image, COLUMN_ATTR, column)
    return image


def colorbar(image, ax, *, column: str, label: str, **kwargs):
    """A colour bar of ``image`` labelled ``label``, recording the column it says it shows
    (:data:`COLUMN_ATTR`): a check compares it with the label and with the column the image was
    filled from (:func:`drawn_from`; :func:`magexp.artifacts.plots.check.colorbar_mismatch`).
    """
    bar = ax.figure.colorbar(image, ax=ax, **kwargs)
    setattr(bar, COLUMN_ATTR, column)
    bar.set_label(label)
    return bar


def save(fig, path: Path) -> list[Path]:
    """Write the figure as a PNG and its vector twin (PDF), both without time stamps or
    producer strings, so the same figure gives the same bytes; return both paths.
    """
    path = Path(path)
    twin = path.with_suffix(VECTOR)
    try:  # each file atomically (magexp.core.atomic): a killed drawing leaves no truncated figure
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format=path.suffix[1:], metadata={"Software": None}, bbox_inches="tight")
        with atomic_path(twin) as tmp:
            fig.savefig(tmp, format=VECTOR[1:], bbox_inches="tight",
                        metadata={"CreationDate": None, "ModDate": None, "Producer": None, "Creator": None})
    finally:
        plt.close(fig)
    return [path, twin]


#: mantissas of the ticks of a log axis that holds fewer than two decade ticks, coarsest first: the
#: first set giving :data:`MIN_LOG_TICKS` ticks in the view is used
NARROW_LOG_SUBS = ((1.0, 2.0, 5.0), (1.0, 1.5, 2.0, 3.0, 5.0, 7.0), (1.0, 1.2, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0))
MIN_LOG_TICKS = 3


def _decade_ticks(lo: float, hi: float) -> int:
    """How many powers of ten lie in ``[lo, hi]`` (both positive)."""
    return math.floor(math.log10(hi) + 1e-12) - math.ceil(math.log10(lo) - 1e-12) + 1


def narrow_log_ticks(lo: float, hi: float, at_least: int = MIN_LOG_TICKS) -> list[float]:
    """Ticks of a log view ``[lo, hi]`` that holds fewer than two decade ticks: the coarsest mantissa
    set of :data:`NARROW_LOG_SUBS` that puts ``at_least`` ticks inside it (a view of 0.85 to
    1.8 gets 0.9, 1, 1.2, 1.5); a view too narrow for any of them, evenly spaced round values.
    Used by :func:`tidy_log_axes` and for colour bars of ratios.
    """
    lo, hi = sorted((lo, hi))
    for subs in NARROW_LOG_SUBS:
        ticks = [float(f"{m * 10.0 ** e:.12g}") for e in range(math.floor(math.log10(lo)), math.ceil(math.log10(hi)) + 1)
                 for m in subs if lo <= m * 10.0 ** e <= hi]
        if len(ticks) >= at_least:
            return ticks
    return [float(f"{t:.12g}") for t in matplotlib.ticker.MaxNLocator(4).tick_values(lo, hi) if lo <= t <= hi]


class _ReadableLogLocator(matplotlib.ticker.LogLocator):
    """Major ticks of a log axis: matplotlib's decades, or where the view holds fewer than two of
    them, :func:`narrow_log_ticks` (labelled plainly, so the values beyond one decade can be read).
    Decided when the figure is drawn, after every limit is set."""

    def tick_values(self, vmin, vmax):
        """Plain ticks on a log axis spanning less than two decades, else matplotlib's."""
        lo, hi = sorted((vmin, vmax))
        if lo > 0 and np.isfinite(hi) and _decade_ticks(lo, hi) < 2:
            return np.array(narrow_log_ticks(lo, hi))
        return super().tick_values(vmin, vmax)


class _ReadableLogLabels(matplotlib.ticker.LogFormatterSciNotation):
    """Labels of :class:`_ReadableLogLocator`'s ticks: powers of ten as ``10^k``; the ticks of a
    narrow view (fewer than two decade ticks) as plain numbers (``1.5``, ``0.02``)."""

    def __call__(self, x, pos=None):
        """A tick's label: plain ``%g`` on a log axis spanning less than two decades, else matplotlib's."""
        lo, hi = sorted(self.axis.get_view_interval())
        if lo > 0 and _decade_ticks(lo, hi) < 2:
            return f"{x:g}"
        return super().__call__(x, pos)


def _unlabelled(x, pos=None) -> str:
    """No label: the formatter of ticks left unlabelled."""
    return ""


def tidy_log_axes(fig):
    """Give every log-scaled axis of ``fig`` readable ticks: decades where its view holds two or more
    (minor ticks unlabelled), else the plain ticks of :func:`narrow_log_ticks` (a reader can read a
    point at 1.8 on an axis from 0.85); returns ``fig`` (call it last in a kind's ``draw``).
    """
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            if axis.get_scale() == "log":
                axis.set_major_locator(_ReadableLogLocator())
                axis.set_major_formatter(_ReadableLogLabels(labelOnlyBase=False))
                axis.set_minor_formatter(matplotlib.ticker.FuncFormatter(_unlabelled))
    return fig


def group_values(frame, key):
    """Distinct values of ``key`` in ``frame`` in first-seen order (None: one group)."""
    if not key:
        return [None]
    return list(dict.fromkeys(frame[key].tolist()))
