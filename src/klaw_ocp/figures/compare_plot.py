"""``compare.png``: several finished runs on one page (:func:`comparison_figure`).

Reads :class:`~klaw_ocp.result_files.run_data.RunData` only; never solves. The first run is the reference
(run 1). From top to bottom:

- the hip height of every run overlaid (one colour per run, :data:`RUN_COLOURS`, and one line
  style per run so identical curves stay visible);
- each other run's hip height minus run 1's, on its own axis, in the unit that suits its size
  (m, mm, µm or nm; the axis label says which): the two solver modes of one configuration agree
  to about 1e-9 m, different configurations by centimetres. Identical time grids are subtracted
  sample by sample, others interpolated onto run 1's times (:func:`klaw_ocp.compare.aligned_differences`);
- the force and torque profiles of the low level (section 3 of the paper: F_w, pa, F_θ1, F_θ2,
  F_θ3, F_θ4), one axis each, every run overlaid;
- the solve time and the iterations per subphase BVP (stance, swing1, swing2, swing3), summed
  over the steps, one bar per run (log scale when the bars span more than a decade and a half).

Every time axis carries thin grey lines at run 1's subphase boundaries (darker at heel strike).
Drawn on the Agg canvas (no pyplot).
"""
from __future__ import annotations

import textwrap

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ..compare import SUBPHASES, aligned_differences, unique_labels
from .plot_style import FONT_PT, FORCE_COLUMNS, RUN_COLOURS, SYMBOLS, new_figure, style_axes

LINE_STYLES = ("-", (0, (5, 2)), (0, (1, 1.5)), "-.", (0, (3, 1, 1, 1, 1, 1)))
#: (scale in metres, unit): the difference axis uses the largest unit the difference reaches 0.3 of
_LENGTH_UNITS = ((1.0, "m"), (1e-3, "mm"), (1e-6, "µm"), (1e-9, "nm"))
_LABELLED_BARS = 2   # runs up to which each bar carries its value
_BOUNDARY = {"subphase": dict(color="0.75", lw=0.4), "heel strike": dict(color="0.45", lw=0.6)}


def _style(i: int) -> dict:
    return {"color": RUN_COLOURS[i % len(RUN_COLOURS)], "ls": LINE_STYLES[i % len(LINE_STYLES)],
            "lw": 1.3 if i == 0 else 1.1}


def length_unit(largest: float) -> tuple[float, str]:
    """(scale, unit) for a length difference whose largest magnitude is ``largest`` metres."""
    if not np.isfinite(largest) or largest <= 0:
        return 1e-3, "mm"
    for scale, unit in _LENGTH_UNITS:
        if largest >= 0.3 * scale:
            return scale, unit
    return _LENGTH_UNITS[-1]


def _boundaries(run) -> tuple[np.ndarray, np.ndarray]:
    """(subphase boundary times, heel-strike times) of a run, from its sample table."""
    t, sub, step = (np.asarray(run.table[c]) for c in ("t", "subphase", "step"))
    if t.size < 2:
        return t[:0], t[:0]
    new_step = step[1:] != step[:-1]
    new_sub = (sub[1:] != sub[:-1]) & ~new_step
    return t[1:][new_sub], t[1:][new_step]


def _mark_boundaries(ax, marks) -> None:
    subphase, heel = marks
    for x in subphase:
        ax.axvline(x, zorder=0, **_BOUNDARY["subphase"])
    for x in heel:
        ax.axvline(x, zorder=0, **_BOUNDARY["heel strike"])


def _time_axes(fig, grid):
    hip = fig.add_subplot(grid[0, :])
    diff = fig.add_subplot(grid[1, :], sharex=hip)
    forces = [fig.add_subplot(grid[2 + k // 2, k % 2], sharex=hip) for k in range(len(FORCE_COLUMNS))]
    return hip, diff, forces


def _plot_hip(ax, runs) -> None:
    for i, run in enumerate(runs):
        ax.plot(run.table["t"], run.table["hip_y"], **_style(i))
    ax.set_ylabel(SYMBOLS["hip_y"])
    ax.set_title("hip height")


def _plot_difference(ax, runs) -> None:
    if len(runs) < 2:
        ax.text(0.5, 0.5, "one run only: nothing to compare", transform=ax.transAxes, ha="center",
                va="center", fontsize=FONT_PT + 1)
        ax.set_ylabel("Δ hip height")
        ax.set_yticks([])
        return
    diffs = [aligned_differences(runs[0], run, ["hip_y"]) for run in runs[1:]]
    largest = max((v for v in (_largest_abs(d["hip_y"]) for d in diffs) if np.isfinite(v)), default=0.0)
    scale, unit = length_unit(largest)
    for i, d in enumerate(diffs, start=1):
        ax.plot(d["t"], d["hip_y"] / scale, **_style(i))
    ax.axhline(0.0, color="0.3", lw=0.6)
    how = {"identical": "same time grid, sample by sample",
           "interpolated": "interpolated onto run 1's times over the common range",
           "no overlap": "time ranges do not overlap"}
    parts = [f"run {i}: max |Δ| {_largest_abs(d['hip_y']) / scale:.3g} {unit} ({how[d['grid']]})"
             for i, d in enumerate(diffs, start=2)]
    ax.set_ylabel(f"Δ hip height ({unit})")
    ax.set_title(f"hip height minus run 1's, in {unit}\n" + textwrap.fill("; ".join(parts), 150))


def _largest_abs(values: np.ndarray) -> float:
    finite = np.abs(values[np.isfinite(values)])
    return float(finite.max()) if finite.size else float("nan")


def _plot_forces(axes, runs) -> None:
    for ax, column in zip(axes, FORCE_COLUMNS):
        for i, run in enumerate(runs):
            ax.plot(run.table["t"], run.table[column], **_style(i))
        ax.set_ylabel(SYMBOLS[column])
        ax.set_title(SYMBOLS[column].split(" (")[0] + {"pa": ": hip actuator position"}.get(column, ""))
    for ax in axes[-2:]:
        ax.set_xlabel("time (s)")
    for ax in axes[:-2]:
        ax.tick_params(labelbottom=False)


def _per_subphase(run, key: str) -> dict:
    totals = {name: 0.0 for name in SUBPHASES}
    for step in run.steps:
        for sub in step["subphases"]:
            totals[sub["name"]] = totals.get(sub["name"], 0.0) + float(sub.get(key) or 0.0)
    return totals


def _bars(ax, runs, key: str, scale: float, ylabel: str, title: str) -> None:
    totals = [_per_subphase(run, key) for run in runs]
    names = list(dict.fromkeys(n for t in totals for n in t))
    width = 0.8 / len(runs)
    x = np.arange(len(names))
    values = []
    for i, t in enumerate(totals):
        heights = [t.get(n, 0.0) * scale for n in names]
        values += [h for h in heights if h > 0]
        bars = ax.bar(x + (i - (len(runs) - 1) / 2) * width, heights, width * 0.92,
                      color=RUN_COLOURS[i % len(RUN_COLOURS)], label=f"run {i + 1}")
        if len(runs) <= _LABELLED_BARS:
            ax.bar_label(bars, labels=[f"{h:.3g}" if h > 0 else "" for h in heights], fontsize=FONT_PT,
                         padding=1.5)
    ax.set_xticks(x, names)
    if values and max(values) / min(values) > 30:
        ax.set_yscale("log")
        ax.set_ylim(min(values) / 2, max(values) * 3)   # room for the bar labels
    elif values:
        ax.set_ylim(0, max(values) * 1.15)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.set_xlabel("subphase (summed over each run's steps: " + " / ".join(str(len(r.steps)) for r in runs) + ")")


def comparison_figure(runs) -> Figure:
    """The comparison page of ``runs`` (RunData; the first is the reference): see the module docstring."""
    if not runs:
        raise ValueError("comparison_figure: got no runs, allowed one or more RunData")
    fig = new_figure(11.0, 15.0)
    grid = fig.add_gridspec(6, 2, height_ratios=[1.25, 0.9, 1, 1, 1, 1.05])
    hip, diff, forces = _time_axes(fig, grid)
    _plot_hip(hip, runs)
    _plot_difference(diff, runs)
    _plot_forces(forces, runs)
    marks = _boundaries(runs[0])
    for ax in (hip, diff, *forces):
        _mark_boundaries(ax, marks)
        style_axes(ax)
    hip.tick_params(labelbottom=False)
    diff.set_xlabel("time (s)")
    times, iterations = fig.add_subplot(grid[5, 0]), fig.add_subplot(grid[5, 1])
    _bars(times, runs, "wall_s", 1e3, "solve time (ms)", "solve time per subphase BVP")
    _bars(iterations, runs, "iterations", 1.0, "iterations", "solver iterations per subphase BVP")
    for ax in (times, iterations):
        style_axes(ax)
        ax.grid(False, axis="x")

    labels = unique_labels(runs)
    handles = [Line2D([], [], **_style(i), label=f"run {i + 1}: {label}") for i, label in enumerate(labels)]
    handles += [Line2D([], [], **_BOUNDARY["subphase"], label="run 1 subphase boundary"),
                Line2D([], [], **_BOUNDARY["heel strike"], label="run 1 heel strike")]
    title = f"Comparison of {len(runs)} runs (differences against run 1)" if len(runs) > 1 else "One run"
    legend = fig.legend(handles=handles, loc="outside upper center", ncol=2, fontsize=FONT_PT, frameon=False,
                        title=title)
    legend.get_title().set_fontsize(FONT_PT + 3)
    return fig
