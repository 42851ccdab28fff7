"""``sweep.png``: the convergence and cost map of a sweep (:mod:`klaw_ocp.sweep`).

One panel per solver method, the first varied path on x and the second on y (a single row when
only one path is varied). A cell that converged is a square coloured by the wall time of its walk
(one colour bar, seconds, shared by the panels); a failed, errored or lost walk is a red 'x'. With more
than two varied paths the others are aggregated: a cell is ok only if all its walks are, and its
colour is their largest wall time (the title says so). Numeric values sit at their value on the
axis; anything else (true/false, null, strings) gets categorical ticks in grid order.

Drawn with the Agg canvas directly (no pyplot, no global backend switch) and written atomically.
"""
from __future__ import annotations

import io
import math
from pathlib import Path

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ..config_paths import format_value as _label
from ..result_files.atomic import atomic_write_bytes

_PANEL_IN = 4.6      # panel width, inches
_DPI = 130
_MAX_TICKS = 16      # numeric axes with more distinct values get automatic ticks
_FAIL_COLOUR = "#d62728"
_WALL_NOTE = "(wall time: the first walk in each process includes loading the solver kernels)"
_LEGEND_MARGIN_IN = 0.1      # the legend's room from each edge of the figure


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


class _Axis:
    """Positions and ticks of one varied path (numeric, or categorical in grid order)."""

    def __init__(self, path: str | None, values: list):
        self.path = path
        self.labels = list(dict.fromkeys(_label(v) for v in values))
        self.numeric = path is not None and all(_is_number(v) for v in values)
        self.position = ({_label(v): float(v) for v in values} if self.numeric
                         else {label: float(i) for i, label in enumerate(self.labels)})

    def apply(self, ax, which: str) -> None:
        set_ticks, set_labels, set_label = ((ax.set_xticks, ax.set_xticklabels, ax.set_xlabel) if which == "x"
                                            else (ax.set_yticks, ax.set_yticklabels, ax.set_ylabel))
        if self.path is None:
            set_ticks([])
            (ax.set_ylim if which == "y" else ax.set_xlim)(-1, 1)
            return
        set_label(self.path)
        if not self.numeric or len(self.labels) <= _MAX_TICKS:
            set_ticks([self.position[k] for k in self.labels])
            set_labels(self.labels, rotation=45 if which == "x" and len(self.labels) > 8 else 0)
        if not self.numeric:
            (ax.set_xlim if which == "x" else ax.set_ylim)(-0.6, len(self.labels) - 0.4)


def _cells(rows: list[dict], xpath: str, ypath: str | None) -> dict:
    """(x label, y label) -> {"ok": all ok, "wall": max wall_s, "n": walks, "row": first bad row}."""
    cells: dict = {}
    for row in rows:
        key = (_label(row[xpath]), _label(row[ypath]) if ypath else "")
        cell = cells.setdefault(key, {"ok": True, "wall": None, "n": 0, "row": None})
        cell["n"] += 1
        wall = row.get("wall_s")
        if wall is not None and math.isfinite(wall):
            cell["wall"] = wall if cell["wall"] is None else max(cell["wall"], wall)
        if row["status"] != "ok":
            cell["ok"] = False
            cell["row"] = cell["row"] or row
    return cells


def _fail_text(row: dict) -> str:
    if row["status"] == "failed":
        return f"step {row['failed_step']}\n{row['failed_subphase']}"
    return "lost" if row["status"] == "lost" else "error"


def sweep_figure(rows: list[dict], varied_paths: list[str], title: str | None = None) -> Figure:
    """The map as a matplotlib Figure (see the module docstring)."""
    methods = list(dict.fromkeys(row["method"] for row in rows)) or ["(no walks)"]
    xpath = varied_paths[0]
    ypath = varied_paths[1] if len(varied_paths) > 1 else None
    rest = varied_paths[2:]
    xaxis = _Axis(xpath, [row[xpath] for row in rows])
    yaxis = _Axis(ypath, [row[ypath] for row in rows] if ypath else [None])
    n_side = max(len(xaxis.labels), len(yaxis.labels) if ypath else 1)
    side_pt = min(26.0, 0.6 * _PANEL_IN * 72 / (n_side + 1))
    height = 4.4 if ypath else 2.9

    fig = Figure(figsize=(_PANEL_IN * len(methods) + 1.4, height), dpi=_DPI, layout="constrained")
    axes = fig.subplots(1, len(methods), sharey=True, squeeze=False)[0]
    per_method = {m: _cells([r for r in rows if r["method"] == m], xpath, ypath) for m in methods}
    walls = [c["wall"] for cells in per_method.values() for c in cells.values() if c["ok"] and c["wall"] is not None]
    lo, hi = (min(walls), max(walls)) if walls else (0.0, 1.0)
    norm = Normalize(vmin=lo, vmax=hi if hi > lo else lo + max(1e-3, 0.05 * lo))
    mappable = None
    annotate = side_pt >= 20 and sum(len(c) for c in per_method.values()) <= 40  # room for a label
    for ax, method in zip(axes, methods):
        cells = per_method[method]
        good = [(k, c) for k, c in cells.items() if c["ok"]]
        bad = [(k, c) for k, c in cells.items() if not c["ok"]]
        xy = lambda items: ([xaxis.position[k[0]] for k, _ in items],  # noqa: E731
                            [yaxis.position[k[1]] if ypath else 0.0 for k, _ in items])
        if good:
            xs, ys = xy(good)
            colours = [c["wall"] if c["wall"] is not None else lo for _, c in good]
            mappable = ax.scatter(xs, ys, c=colours, cmap="viridis", norm=norm, marker="s",
                                  s=side_pt ** 2, edgecolors="0.2", linewidths=0.5, zorder=2)
        if bad:
            xs, ys = xy(bad)
            ax.scatter(xs, ys, marker="x", color=_FAIL_COLOUR, s=(0.8 * side_pt) ** 2,
                       linewidths=2.2, zorder=3)
            if annotate:
                for (x, y), (_, c) in zip(zip(xs, ys), bad):
                    ax.annotate(_fail_text(c["row"]), (x, y), xytext=(0, -0.55 * side_pt - 2),
                                textcoords="offset points", ha="center", va="top", fontsize=7,
                                color=_FAIL_COLOUR, zorder=4)
        n_ok = sum(c["n"] for _, c in good)
        ax.set_title(f"{method}: {n_ok}/{sum(c['n'] for c in cells.values())} ok", fontsize=10)
        ax.grid(True, color="0.9", zorder=0)
        ax.set_axisbelow(True)
        if xaxis.numeric:
            ax.margins(x=0.12)
        if ypath and yaxis.numeric:
            ax.margins(y=0.15 if annotate else 0.12)
        xaxis.apply(ax, "x")
        if ax is axes[0]:
            yaxis.apply(ax, "y")
    if mappable is not None:
        bar = fig.colorbar(mappable, ax=list(axes), pad=0.02, fraction=0.05 if ypath else 0.04)
        bar.set_label("max wall time per cell [s]" if rest else "wall time per walk [s]")
    _legend(fig)
    n = {status: sum(r["status"] == status for r in rows) for status in ("ok", "failed", "error", "lost")}
    head = (title or "klaw-ocp sweep") + f": {len(rows)} walks, {n['ok']} ok, {n['failed']} failed, {n['error']} error"
    head += f", {n['lost']} lost" if n["lost"] else ""     # a worker process died (docs/sweep.md)
    if rest:
        head += (f"\naggregated over {', '.join(rest)}: a cell is ok only if all its walks are; "
                 f"colour = max wall time")
    fig.suptitle(head, fontsize=10)
    return fig


def _legend(fig) -> None:
    """The legend under the panels, in one row if it fits in the figure's width, else with the
    note on two lines, else in one column: a single panel's figure (6 in) is narrower than the
    one-row legend, which was cut at both edges."""
    renderer = FigureCanvasAgg(fig).get_renderer()
    wrapped = _WALL_NOTE.replace(" includes", "\nincludes")
    for ncol, text in ((3, _WALL_NOTE), (3, wrapped), (1, wrapped)):
        handles = [Line2D([], [], marker="s", ls="", color="#3b8f88", markeredgecolor="0.2", label="converged"),
                   Line2D([], [], marker="x", ls="", color=_FAIL_COLOUR, markeredgewidth=2.2, label="failed / error / lost"),
                   Line2D([], [], ls="", label=text)]
        legend = fig.legend(handles=handles, loc="outside lower center", ncol=ncol, fontsize=8, frameon=False,
                            handletextpad=0.3, columnspacing=1.5)
        if legend.get_window_extent(renderer).width <= fig.bbox.width - 2 * _DPI * _LEGEND_MARGIN_IN or ncol == 1:
            return
        legend.remove()


def sweep_png(rows: list[dict], varied_paths: list[str], title: str | None = None) -> bytes:
    fig = sweep_figure(rows, varied_paths, title)
    FigureCanvasAgg(fig)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return buffer.getvalue()


def write_sweep_png(rows: list[dict], varied_paths: list[str], path, title: str | None = None) -> Path:
    """Render the map of ``rows`` and write it to ``path`` atomically."""
    atomic_write_bytes(path, sweep_png(rows, varied_paths, title))
    return Path(path)
