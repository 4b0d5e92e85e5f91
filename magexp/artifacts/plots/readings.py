"""The verdict of each headline claim of a paper under each reading of what the paper left unstated.

One figure per paper (``results/<paper>/readings.png``, drawn by :func:`magexp.artifacts.report.build`):
a grid of headlines (rows) by readings (columns), each cell coloured by the verdict under that reading
and naming the reading and the verdict in words; a headline without readings has one cell, magexp's
own settings; an untestable one is left out (it has no runs to judge).
"""

from __future__ import annotations

import textwrap

from matplotlib.patches import Patch, Rectangle

from magexp.artifacts.plots.style import plt

#: fill of a cell per verdict (the words in the cell say it too)
COLOURS = {"supported": "#a6d96a", "partly": "#fee08b", "contradicted": "#f46d43", "depends": "#c2a5cf",
           "not testable here": "#dddddd", "by construction": "#abd9e9"}
#: characters per line of a cell's text
WRAP = 24


def cells_of(headline: dict) -> list[tuple[str, str]]:
    """``(reading label, verdict)`` of each cell of a headline row (``readings`` of
    :func:`magexp.artifacts.report.headlines`); one cell of magexp's settings when it has none.

    Parameters
    ----------
    headline : dict
        A headline row.

    Returns
    -------
    list of tuple of str
        ``(reading label, verdict)`` per cell.
    """
    readings = headline.get("readings") or []
    return [(r["label"], r["verdict"]) for r in readings] or [("magexp's settings", headline["verdict"])]


def drawn(headlines: list[dict]) -> list[dict]:
    """The headlines the grid draws: every one but the untestable (no runs to judge).

    Parameters
    ----------
    headlines : list of dict
        A paper's headline rows (their ``verdict`` is read).

    Returns
    -------
    list of dict
        Those with runs to judge.
    """
    return [h for h in headlines if h["verdict"] != "not testable here"]


def cells(headlines: list[dict]) -> list[dict]:
    """The data the grid draws, a row per cell: ``headline`` (its id), ``reading`` and ``verdict``
    (written beside the figure as ``readings.csv``, what ``magexp verify`` compares).

    Parameters
    ----------
    headlines : list of dict
        A paper's headline rows, with their readings.

    Returns
    -------
    list of dict
        A ``{headline, reading, verdict}`` row per cell.
    """
    return [{"headline": h["id"], "reading": label, "verdict": verdict}
            for h in drawn(headlines) for label, verdict in cells_of(h)]


def draw(headlines: list[dict], title: str):
    """The grid of ``headlines`` (rows of :func:`magexp.artifacts.report.headlines`) as a figure.

    Parameters
    ----------
    headlines : list of dict
        The headline rows of a paper.
    title : str
        The figure's title.

    Returns
    -------
    matplotlib.figure.Figure
        The grid drawn.
    """
    rows = drawn(headlines)
    width = max((len(cells_of(h)) for h in rows), default=1)
    fig, ax = plt.subplots(figsize=(1.9 * width + 2.2, 0.62 * len(rows) + 0.9))
    for i, h in enumerate(rows):
        y = len(rows) - 1 - i
        for j, (label, verdict) in enumerate(cells_of(h)):
            ax.add_patch(Rectangle((j, y), 0.96, 0.9, facecolor=COLOURS.get(verdict, "white"), edgecolor="grey"))
            ax.text(j + 0.48, y + 0.45, textwrap.fill(label, WRAP) + f"\n{verdict}", ha="center", va="center",
                    fontsize=7)
    ax.set_xlim(0, width)
    ax.set_ylim(0, max(len(rows), 1))
    ax.set_yticks([len(rows) - 1 - i + 0.45 for i in range(len(rows))])
    ax.set_yticklabels([f"{h['id']}\n(overall: {h['verdict']})" for h in rows], fontsize=7.5)
    ax.set_xticks([])
    ax.grid(False)
    for side in ("left", "bottom"):
        ax.spines[side].set_visible(False)
    ax.tick_params(length=0)
    ax.set_title(title, fontsize=9, loc="left")
    used = sorted({v for h in rows for _, v in cells_of(h)}, key=list(COLOURS).index)
    ax.legend(handles=[Patch(facecolor=COLOURS[v], edgecolor="grey", label=v) for v in used],
              loc="upper center", bbox_to_anchor=(0.5, 0.0), ncols=len(used) or 1, fontsize=7.5)
    return fig
