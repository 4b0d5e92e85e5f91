"""Defects a reader sees in a drawn figure, found from the figure's artists after a layout pass.

* :func:`empty_axes`: a visible axes with nothing drawn from data (no finite line, marker,
  collection, bar, image or table; reference lines such as ``axhline`` do not count).
* :func:`overlapping_text`: two texts printed over each other (suptitle, titles, axis labels,
  tick labels, legends as a whole, annotations, colour-bar labels, tables), measured by the
  renderer's window extents.
* :func:`overflowing_cells`: a table cell whose text runs out of the cell.
* :func:`raw_legends`: a legend entry made of raw override strings (``window=null``).
* :func:`legend_defects`: a legend entry whose series is not drawn, or two entries that look
  the same (one colour, marker and line style for two series).
* :func:`colorbar_mismatch`: a colour bar that does not say which column it shows, or whose
  label names another column than the one its image was drawn from (the plotting code records
  both with :func:`magexp.artifacts.plots.style.colorbar`).
* :func:`raw_names`: a config name (``yan2022_paper_mockup``) in a legend, a title or a table's
  header, where a reader wants words.
* :func:`clipped_markers`: a marker cut by the edge of its axes (its centre inside the view, its
  size over the edge): a paper's value drawn half.
* :func:`unlabelled_log_range`: a log axis labelled at fewer than two decades whose labelled ticks
  span less than half of its view (points at 1.8 on an axis labelled only at 0.9 and 1).
* :func:`small_text`: text smaller than :data:`MIN_POINTS` at the saved size.

:func:`defects` lists them all for one figure; ``tests/test_figure_defects.py`` runs it on the
figure of every artifact, drawn from its committed CSV.
"""

from __future__ import annotations

import re

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import Collection
from matplotlib.colors import to_hex
from matplotlib.image import AxesImage
from matplotlib.legend import Legend
from matplotlib.lines import Line2D
from matplotlib.patches import Rectangle
from matplotlib.table import Table
from matplotlib.text import Text

from magexp.artifacts.columns import column_label
from magexp.artifacts.plots.style import COLUMN_ATTR

#: two texts overlap when their window extents share more than this many pixels in each direction
OVERLAP_PX = 1.0
#: the smallest readable text (points at the saved size: figures are saved at their own size)
MIN_POINTS = 7.0
#: a log axis is labelled enough when its labelled ticks span at least this fraction of its view (in log)
LABELLED_SPAN = 0.5


def _finite(values) -> bool:
    """Whether ``values`` hold at least one finite number (something a panel can show)."""
    a = np.asarray(values, dtype=float)
    return a.size > 0 and bool(np.isfinite(a).any())


def _both_finite(x, y) -> bool:
    """Whether some point ``(x_i, y_i)`` has both coordinates finite."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    return x.shape == y.shape and x.size > 0 and bool((np.isfinite(x) & np.isfinite(y)).any())


def _draws_data(artist, ax: Axes) -> bool:
    """Whether ``artist`` shows data (not a reference line spanning the axes)."""
    if not artist.get_visible():
        return False
    if isinstance(artist, Line2D):
        return _line_draws_data(artist, ax)
    if isinstance(artist, Collection):
        return _collection_draws_data(artist)
    if isinstance(artist, AxesImage):
        return _finite(np.ma.filled(np.ma.asarray(artist.get_array(), dtype=float), np.nan))
    if isinstance(artist, Rectangle):
        return bool(np.isfinite([artist.get_height(), artist.get_width()]).all() and artist.get_height() != 0)
    return isinstance(artist, Table)


def _line_draws_data(line: Line2D, ax: Axes) -> bool:
    """A line with a finite point, unless it is an ``axhline`` / ``axvline`` (a reference across the axes)."""
    spans = (ax.get_xaxis_transform(which="grid"), ax.get_yaxis_transform(which="grid"))
    if any(line.get_transform() is t for t in spans):
        return False
    x, y = line.get_data()
    return _both_finite(x, y)


def _collection_draws_data(artist: Collection) -> bool:
    """A collection with several finite offsets (a scatter), finite 3-D offsets or a path with a
    finite vertex (a band, a bar set)."""
    offsets = artist.get_offsets()
    if len(offsets) and np.isfinite(np.asarray(offsets, float)).all(axis=-1).any() and len(offsets) > 1:
        return True
    if hasattr(artist, "_offsets3d"):
        return any(_finite(v) for v in artist._offsets3d)
    return any(len(p.vertices) and np.isfinite(p.vertices).all(axis=1).any() for p in artist.get_paths())


def _is_colorbar(ax: Axes) -> bool:
    """Whether ``ax`` is a colour bar's axes (not a panel to check)."""
    return getattr(ax, "_colorbar", None) is not None


def overflowing_cells(fig) -> list[str]:
    """Table cells whose text is wider or taller than the cell (it runs into its neighbours);
    call after a layout pass (:func:`overlapping_text` makes one).
    """
    renderer = fig.canvas.get_renderer()
    found = []
    for ax in fig.axes:
        for table in ax.tables:
            for (row, col), cell in table.get_celld().items():
                text = cell.get_text()
                if not text.get_text().strip():
                    continue
                inner, box = text.get_window_extent(renderer), cell.get_window_extent(renderer)
                if inner.width > box.width + OVERLAP_PX or inner.height > box.height + OVERLAP_PX:
                    found.append(f"table cell ({row}, {col}) {text.get_text()[:20]!r} does not fit its cell")
    return found


def empty_axes(fig) -> list[str]:
    """Visible data axes (not colour bars) on which nothing is drawn from data."""
    found = []
    for k, ax in enumerate(fig.axes):
        if not ax.get_visible() or _is_colorbar(ax):
            continue
        artists = [*ax.lines, *ax.collections, *ax.images, *ax.patches, *ax.tables]
        if not any(_draws_data(a, ax) for a in artists):
            found.append(f"axes {k} ({ax.get_title() or 'untitled'!r}) has nothing drawn")
    return found


def _texts(fig, renderer) -> list[tuple[str, object, object]]:
    """``(name, owner, bbox)`` of every visible text of ``fig``; texts of one owner (one legend,
    one table) are one item."""
    items = []

    def add(name, owner, artist):
        if artist is None or not artist.get_visible():
            return
        if isinstance(artist, Text) and not artist.get_text().strip():
            return
        box = artist.get_window_extent(renderer)
        if box.width > 0 and box.height > 0 and np.isfinite(box.get_points()).all():
            items.append((name, owner, _corners(artist, box, renderer)))

    if fig._suptitle is not None:
        add("suptitle", "suptitle", fig._suptitle)
    for legend in fig.legends:
        add("figure legend", legend, legend)
    for k, ax in enumerate(fig.axes):
        if not ax.get_visible():
            continue
        where = f"axes {k}"
        for loc, title in (("left", ax._left_title), ("center", ax.title), ("right", ax._right_title)):
            add(f"{where} {loc} title", (ax, "title", loc), title)
        if ax.axison and not hasattr(ax, "get_zlim"):  # 3-D axes place labels and ticks by projection
            for name, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
                add(f"{where} {name}label", (ax, name, "label"), axis.label)
                for j, tick in enumerate(axis._update_ticks()):  # the ticks drawn (inside the view)
                    for side, text in ((1, tick.label1), (2, tick.label2)):
                        if getattr(tick, f"label{side}").get_visible():
                            add(f"{where} {name} tick {text.get_text()!r}", (ax, name, "tick", j, side), text)
        legend = ax.get_legend()
        if legend is not None:
            add(f"{where} legend", legend, legend)
        for j, text in enumerate(ax.texts):
            add(f"{where} text {text.get_text()[:20]!r}", (ax, "text", j), text)
        for table in ax.tables:
            add(f"{where} table", table, table)
    return items


def _corners(artist, box, renderer) -> np.ndarray:
    """The four corners (display pixels) of what ``artist`` covers: its window extent, or for a
    rotated text the rotated rectangle of its glyphs (its extent's centre is the rectangle's)."""
    angle = artist.get_rotation() % 90 if isinstance(artist, Text) else 0.0
    if not angle:
        return np.array([[box.x0, box.y0], [box.x1, box.y0], [box.x1, box.y1], [box.x0, box.y1]])
    rotation = artist.get_rotation()
    artist.set_rotation(0)
    flat = artist.get_window_extent(renderer)
    artist.set_rotation(rotation)
    t = np.deg2rad(rotation)
    half = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * [flat.width / 2, flat.height / 2]
    turn = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
    return half @ turn.T + [(box.x0 + box.x1) / 2, (box.y0 + box.y1) / 2]


def _overlap(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two convex quadrilaterals share more than :data:`OVERLAP_PX` along every separating
    direction (the separating axis theorem over both shapes' edge normals)."""
    for quad in (a, b):
        edges = np.roll(quad, -1, axis=0) - quad
        for nx, ny in np.column_stack([-edges[:, 1], edges[:, 0]]):
            norm = np.hypot(nx, ny)
            if norm == 0:
                continue
            pa, pb = a @ [nx, ny] / norm, b @ [nx, ny] / norm
            if min(pa.max(), pb.max()) - max(pa.min(), pb.min()) <= OVERLAP_PX:
                return False
    return True


def overlapping_text(fig) -> list[str]:
    """Pairs of texts whose window extents overlap (after a layout pass without rendering)."""
    fig.draw_without_rendering()
    renderer = fig.canvas.get_renderer()
    items = _texts(fig, renderer)
    if len(items) < 2:
        return []
    corners = np.stack([c for _, _, c in items])  # (n, 4, 2)
    lo, hi = corners.min(axis=1), corners.max(axis=1)
    near = ((np.minimum(hi[:, None], hi[None]) - np.maximum(lo[:, None], lo[None])) > OVERLAP_PX).all(axis=2)
    found = []
    for i, j in zip(*np.nonzero(np.triu(near, 1))):  # the extents meet: test the (rotated) shapes
        (na, oa, a), (nb, ob, b) = items[i], items[j]
        if oa is not ob and _overlap(a, b):
            found.append(f"{na} overlaps {nb}")
    return found


def colorbar_mismatch(fig) -> list[str]:
    """Colour bars without a recorded column, or whose label is not that column's label, or whose
    image was drawn from another column than the bar records.
    """
    found = []
    for ax in fig.axes:
        bar = getattr(ax, "_colorbar", None)
        if bar is None:
            continue
        label = ax.get_ylabel() or ax.get_xlabel()
        column = getattr(bar, COLUMN_ATTR, None)
        drawn = getattr(bar.mappable, COLUMN_ATTR, None)
        if column is None:
            found.append(f"colour bar {label!r} does not record the column it shows")
            continue
        if drawn != column:
            found.append(f"colour bar {label!r} says {column!r}, its cells are drawn from {drawn!r}")
        if column_label(column) not in label:
            found.append(f"colour bar {label!r} does not name its column {column!r} ({column_label(column)!r})")
    return found


#: a raw override string: ``key=value`` with no space (readable labels read ``A = 2 nT``)
RAW_OVERRIDE = re.compile(r"[A-Za-z_][\w.]*=\S")


def raw_legends(fig) -> list[str]:
    """Legend entries made of raw override strings (``lm, scenario=real_x, window=null``)."""
    legends = [*fig.legends, *(ax.get_legend() for ax in fig.axes)]
    texts = [t.get_text() for lg in legends if isinstance(lg, Legend) for t in lg.get_texts()]
    return [f"legend entry {t!r} is a raw override string" for t in texts if RAW_OVERRIDE.search(t)]


def _has_data(artist) -> bool:
    """Whether a legend's artist (a line, a collection, a patch, an errorbar) shows a finite value."""
    if hasattr(artist, "lines") and isinstance(getattr(artist, "lines"), tuple):  # a container (errorbar)
        return any(_has_data(a) for a in artist if a is not None and not isinstance(a, tuple))
    if isinstance(artist, Line2D):
        x, y = artist.get_data()
        return _both_finite(x, y)
    if isinstance(artist, Collection):
        return len(artist.get_offsets()) > 0 or any(len(p.vertices) for p in artist.get_paths())
    return True


def _look(handle) -> tuple:
    """What a reader tells a legend entry by: colours, marker, line and hatch of its handle."""
    if isinstance(handle, Line2D):
        return ("line", to_hex(handle.get_color()), handle.get_marker(), handle.get_linestyle(),
                to_hex(handle.get_markerfacecolor(), keep_alpha=True), to_hex(handle.get_markeredgecolor()))
    if isinstance(handle, Collection):
        face = handle.get_facecolor()
        edge = handle.get_edgecolor()
        paths = handle.get_paths()
        shape = tuple(np.round(paths[0].vertices, 3).ravel()) if len(paths) else ()
        return ("collection", to_hex(face[0], keep_alpha=True) if len(face) else None,
                to_hex(edge[0]) if len(edge) else None, handle.get_hatch(), shape)
    if hasattr(handle, "get_facecolor"):
        return ("patch", to_hex(handle.get_facecolor(), keep_alpha=True), to_hex(handle.get_edgecolor()),
                handle.get_hatch())
    return ("other", id(handle))


def legend_defects(fig) -> list[str]:
    """Legend entries whose series has nothing drawn (all of its values missing), and entries of
    one legend a reader cannot tell apart (same colour, marker, line style).
    """
    drawn: dict[str, list] = {}
    for ax in fig.axes:
        for handle, text in zip(*ax.get_legend_handles_labels()):
            drawn.setdefault(text, []).append(handle)
    found = []
    for legend in [*fig.legends, *(ax.get_legend() for ax in fig.axes)]:
        if legend is None:
            continue
        seen: dict[tuple, str] = {}
        for handle, text in zip(legend.legend_handles, (t.get_text() for t in legend.get_texts())):
            if text in drawn and not any(_has_data(a) for a in drawn[text]):
                found.append(f"legend entry {text!r}: nothing of it is drawn")
            look = _look(handle)
            if look in seen:
                found.append(f"legend entries {seen[look]!r} and {text!r} look the same")
            seen[look] = text
    return found


#: a config name: a paper's prefix and an underscore (``yan2022_paper_mockup``, ``ding2024_exp1``)
CONFIG_NAME = re.compile(r"\b[a-z]+\d{4}_\w+")


def _worded_texts(fig) -> list[tuple[str, str]]:
    """``(where, text)`` of the texts a reader reads as words: titles, legend entries, colour-bar
    labels and table headers (tick labels name cases and are left to the kinds)."""
    found = [("suptitle", fig._suptitle.get_text())] if fig._suptitle is not None else []
    for legend in [*fig.legends, *(ax.get_legend() for ax in fig.axes)]:
        if isinstance(legend, Legend):
            found += [("legend entry", t.get_text()) for t in legend.get_texts()]
    for k, ax in enumerate(fig.axes):
        found += [(f"axes {k} title", t.get_text()) for t in (ax._left_title, ax.title, ax._right_title)]
        if _is_colorbar(ax):
            found.append((f"axes {k} colour-bar label", ax.get_ylabel() or ax.get_xlabel()))
        for table in ax.tables:
            found += [(f"axes {k} table header", cell.get_text().get_text())
                      for (row, col), cell in table.get_celld().items() if row == 0 or col < 0]
    return found


def raw_names(fig) -> list[str]:
    """Config names (:data:`CONFIG_NAME`) printed where a reader wants words: a legend entry, a
    title, a colour-bar label or a table header (``plot.names`` gives them words).
    """
    return [f"{where} {text!r} prints the config name {m.group(0)!r}"
            for where, text in _worded_texts(fig) for m in [CONFIG_NAME.search(text)] if m]


def _marker_points(line: Line2D) -> np.ndarray:
    """Display coordinates of the finite points of ``line`` that carry a marker."""
    marker = line.get_marker()
    if marker in (None, "", " ", "None", "none") or not line.get_visible() or not line.get_clip_on():
        return np.empty((0, 2))
    xy = np.asarray(line.get_xydata(), float)
    xy = xy[np.isfinite(xy).all(axis=1)] if xy.ndim == 2 else np.empty((0, 2))
    return line.get_transform().transform(xy) if len(xy) else np.empty((0, 2))


def clipped_markers(fig) -> list[str]:
    """Markers cut by the edge of their axes: the centre inside the view (edge included), the marker
    (half its size plus half its edge) reaching more than :data:`OVERLAP_PX` over the edge. Call
    after a layout pass (:func:`overlapping_text` makes one).
    """
    found = []
    for k, ax in enumerate(fig.axes):
        if not ax.get_visible() or _is_colorbar(ax) or hasattr(ax, "get_zlim"):
            continue
        box, cut, names = ax.bbox, 0, []
        for line in ax.lines:
            points = _marker_points(line)
            if not len(points):
                continue
            r = (line.get_markersize() + line.get_markeredgewidth()) / 2 * fig.dpi / 72
            x, y = points[:, 0], points[:, 1]
            inside = (x >= box.x0 - 0.5) & (x <= box.x1 + 0.5) & (y >= box.y0 - 0.5) & (y <= box.y1 + 0.5)
            over = ((x - r < box.x0 - OVERLAP_PX) | (x + r > box.x1 + OVERLAP_PX)
                    | (y - r < box.y0 - OVERLAP_PX) | (y + r > box.y1 + OVERLAP_PX))
            if (n := int((inside & over).sum())):
                cut += n
                names.append(line.get_label() if not line.get_label().startswith("_") else f"marker {line.get_marker()!r}")
        if cut:
            found.append(f"axes {k} ({ax.get_title() or 'untitled'!r}): {cut} marker(s) cut by the axes edge "
                         f"({', '.join(dict.fromkeys(names))})")
    return found


def _log_axes(fig):
    """``(k, ax, name, axis)`` of every visible log-scaled axis of a 2-D data axes of ``fig``."""
    for k, ax in enumerate(fig.axes):
        if ax.get_visible() and ax.axison and not hasattr(ax, "get_zlim"):
            for name, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
                if axis.get_scale() == "log" and axis.get_visible():
                    yield k, ax, name, axis


def _labelled_ticks(axis) -> list[float]:
    """Where ``axis`` prints a tick label (major or minor, either side, inside the view)."""
    return [t.get_loc() for t in axis._update_ticks()
            if any(lb.get_visible() and lb.get_text().strip() for lb in (t.label1, t.label2))]


def unlabelled_log_range(fig) -> list[str]:
    """Log axes labelled at fewer than two powers of ten whose labelled ticks (major and minor,
    inside the view) span less than :data:`LABELLED_SPAN` of the view in log: a reader cannot read
    the values beyond them (two labelled decades give the scale). Call after a layout pass.
    """
    found = []
    for k, ax, name, axis in _log_axes(fig):
        lo, hi = sorted(axis.get_view_interval())
        if lo <= 0 or hi <= lo:
            continue
        labelled = _labelled_ticks(axis)
        span = (np.log10(max(labelled)) - np.log10(min(labelled))) if len(labelled) > 1 else 0.0
        decades = sum(1 for v in labelled if v > 0 and abs(np.log10(v) - round(np.log10(v))) < 1e-9)
        if decades < 2 and span < LABELLED_SPAN * np.log10(hi / lo):
            found.append(f"axes {k} ({ax.get_title() or 'untitled'!r}): log {name} axis from {lo:.3g} to {hi:.3g} "
                         f"labelled only at {', '.join(f'{v:g}' for v in labelled) or 'no tick'}")
    return found


def small_text(fig) -> list[str]:
    """Visible texts of ``fig`` smaller than :data:`MIN_POINTS` (a figure is saved at its own size, so
    points are what a reader gets); texts of one legend, one table are reported once.
    """
    found, seen = [], set()
    for text in fig.findobj(Text):
        if not text.get_visible() or not text.get_text().strip() or text.get_fontsize() >= MIN_POINTS - 1e-9:
            continue
        if text.axes is not None and not text.axes.get_visible():
            continue
        owner = text.axes if text.axes is not None else text.figure
        key = (id(owner), text.get_fontsize())
        if key not in seen:
            seen.add(key)
            found.append(f"text {text.get_text()[:20]!r} is {text.get_fontsize():g} pt (readable: {MIN_POINTS:g} pt or more)")
    return found


def defects(fig) -> list[str]:
    """Every defect of ``fig`` found by the checks of this module (also of a figure already saved
    and closed: it gets an Agg canvas to lay it out again).
    """
    if not hasattr(fig.canvas, "get_renderer"):
        FigureCanvasAgg(fig)
    return (overlapping_text(fig) + overflowing_cells(fig) + empty_axes(fig) + colorbar_mismatch(fig)
            + raw_legends(fig) + raw_names(fig) + legend_defects(fig) + clipped_markers(fig)
            + unlabelled_log_range(fig) + small_text(fig))
