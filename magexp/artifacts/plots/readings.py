"""The verdict of each headline claim of a paper under each reading of what the paper left unstated.

One figure per paper (``results/<paper>/readings.png``, drawn by :func:`magexp.artifacts.report.build`):
a grid of headlines (rows) by readings (columns), each cell coloured by the verdict under that reading
and naming the reading and the verdict in words. The first column is each headline's primary reading,
framed in black: it alone decides the headline's verdict; the others test its robustness. A headline
without readings has one cell, the paper's stated settings; an untestable one is left out (it has no
runs to judge).
"""

from __future__ import annotations

import textwrap

from matplotlib.patches import Patch, Rectangle

from magexp.artifacts.plots.style import plt

#: fill of a cell per verdict (the words in the cell say it too)
COLOURS = {"supported": "#a6d96a", "partly": "#fee08b", "contradicted": "#f46d43", "not shown": "#f7f7f7",
           "not testable here": "#dddddd", "by construction": "#abd9e9"}
#: characters per line of a cell's text
WRAP = 24


def cells_of(headline: dict) -> list[tuple[str, str, bool]]:
    """``(reading label, verdict, primary)`` of each cell of a headline row (``readings`` of
    :func:`magexp.artifacts.headlines.headlines`), the primary reading first; one cell of the paper's
    stated settings when it has none.
    """
    readings = sorted(headline.get("readings") or [], key=lambda r: not r["primary"])
    return ([(r["label"], r["verdict"], r["primary"]) for r in readings]
            or [("the paper's stated settings", headline["verdict"], True)])


def drawn(headlines: list[dict]) -> list[dict]:
    """The headlines the grid draws: every one but the untestable (no runs to judge)."""
    return [h for h in headlines if h["verdict"] != "not testable here"]


def cells(headlines: list[dict]) -> list[dict]:
    """The data the grid draws, a row per cell: ``headline`` (its id), ``reading``, ``verdict`` and
    ``primary`` (written beside the figure as ``readings.csv``, what ``magexp verify`` compares).
    """
    return [{"headline": h["id"], "reading": label, "verdict": verdict, "primary": primary}
            for h in drawn(headlines) for label, verdict, primary in cells_of(h)]


def draw(headlines: list[dict], title: str):
    """The grid of ``headlines`` (rows of :func:`magexp.artifacts.report.headlines`) as a figure."""
    rows = drawn(headlines)
    width = max((len(cells_of(h)) for h in rows), default=1)
    fig, ax = plt.subplots(figsize=(1.9 * width + 2.2, 0.8 * len(rows) + 0.9))
    for i, h in enumerate(rows):
        y = len(rows) - 1 - i
        for j, (label, verdict, primary) in enumerate(cells_of(h)):
            ax.add_patch(Rectangle((j, y), 0.96, 0.9, facecolor=COLOURS.get(verdict, "white"),
                                   edgecolor="black" if primary else "grey", linewidth=2.2 if primary else 0.8))
            ax.text(j + 0.48, y + 0.45, textwrap.fill(label, WRAP) + f"\n{verdict}" + ("\n(primary)" if primary else ""),
                    ha="center", va="center", fontsize=7, fontweight="bold" if primary else "normal")
    ax.set_xlim(0, width)
    ax.set_ylim(0, max(len(rows), 1))
    ax.set_yticks([len(rows) - 1 - i + 0.45 for i in range(len(rows))])
    ax.set_yticklabels([f"{h['id']}\n(verdict: {h['verdict']})" for h in rows], fontsize=7.5)
    ax.set_xticks([])
    ax.grid(False)
    for side in ("left", "bottom"):
        ax.spines[side].set_visible(False)
    ax.tick_params(length=0)
    ax.set_title(title, fontsize=9, loc="left")
    used = sorted({v for h in rows for _, v, _ in cells_of(h)}, key=list(COLOURS).index)
    ax.legend(handles=[Patch(facecolor=COLOURS[v], edgecolor="grey", label=v) for v in used],
              loc="upper center", bbox_to_anchor=(0.5, 0.0), ncols=len(used) or 1, fontsize=7.5)
    return fig
