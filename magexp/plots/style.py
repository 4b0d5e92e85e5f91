"""Shared matplotlib style (Agg backend) and helpers used by every kind."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

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


def label(spec, key: str, value=None) -> str:
    """Readable label of a grid key (``plot.labels`` in the artifact may rename keys)."""
    names = dict(spec.plot.get("labels", {}) or {})
    name = names.get(key, key.split(".")[-1].replace("_", " "))
    return name if value is None else f"{name} = {value}"


def panels(n: int, *, width: float = 3.4, height: float = 2.8, rows: int = 1, axes=None):
    """A row (or grid) of ``n`` axes; ``axes`` (``n`` Axes of the caller's figure, or one Axes for
    ``n == 1``) draws into the caller's own layout instead of a new figure."""
    if axes is not None:
        axes = [axes] if hasattr(axes, "plot") else list(axes)
        if len(axes) != n:
            from magexp.errors import MagexpError

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


#: the vector twin written beside every PNG (for a paper: LaTeX's includegraphics takes it as is)
VECTOR = ".pdf"


def save(fig, path: Path) -> list[Path]:
    """Write the figure as a PNG and its vector twin (PDF), both without time stamps or
    producer strings, so the same figure gives the same bytes; return both paths."""
    path = Path(path)
    fig.savefig(path, metadata={"Software": None}, bbox_inches="tight")
    twin = path.with_suffix(VECTOR)
    fig.savefig(twin, metadata={"CreationDate": None, "ModDate": None, "Producer": None, "Creator": None},
                bbox_inches="tight")
    plt.close(fig)
    return [path, twin]


def group_values(frame, key):
    """Distinct values of ``key`` in ``frame`` in first-seen order (None: one group)."""
    if not key:
        return [None]
    return list(dict.fromkeys(frame[key].tolist()))
