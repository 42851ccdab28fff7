"""The plots of every run (``<results>/plots/``; :mod:`.registry` lists them), drawn from a
:class:`~klaw_ocp.result_files.run_data.RunData`, and three of their figure functions.

- ``hip_height.png`` (§4.2): the hip height over time against the vertical sinusoid the stance is
  guided towards (one bump per step, lowest at the heel strikes) and the heel-strike floor the hip
  should not drop below; a second axis shows the difference in mm.
- ``gait_diagram.png`` (§3 state-phase timings, figure 3): :mod:`klaw_ocp.figures.gait_diagram`.
- ``torques.png`` (§4.2, §4.3): every applied force and torque, F_w, pa, F_θ1, F_θ2 of the
  stance and F_θ3, F_θ4 of the swing, one axis each, coloured by subphase, with a swing2
  recovery (§4.3 "recovery algorithm") shaded.
- ``states.png`` (§4, figure 2): w, θ1, θ2 of the stance model and θ3, θ4 of the swing model.
- ``legs.png`` (§5, figure 8): a strobe of the dynamic model, :mod:`klaw_ocp.figures.strobe`.
- ``joint_angles.png`` and ``body.png`` (§4, the body of 56 angles): hip, knee and ankle over the
  gait cycle, and the skeleton at heel strikes beside the dynamic model, :mod:`klaw_ocp.figures.body_plots`.

A walk of more than 60 steps (:data:`~klaw_ocp.figures.plot_style.MAX_DRAWN_STEPS`) is drawn in two
parts, its first 40 steps and its last 10, side by side on a broken time axis, and the title says
which steps (:func:`~klaw_ocp.figures.plot_style.drawn_steps`): a whole long walk was a solid band.

Every time plot follows bioptim: a dark thin vertical line at each step boundary (heel strike),
light ones at the subphase boundaries (toe-off, end of swing1, end of swing2), and one colour per
subphase (:data:`~klaw_ocp.figures.plot_style.SUBPHASE_COLOURS`). A line is drawn per subphase with
NaN breaks (one artist per subphase, not one per sample) and never joins two steps: at a heel
strike the stance and swing coordinates change legs.

The axes are placed in inches (:func:`~klaw_ocp.figures.plot_style.axes_column`), with margins sized
for their labels, instead of a constrained layout: that alone would cost about a third of the
time of the plots. The functions read results only: they never solve and never import a
solver or pyplot.
"""
from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import MaxNLocator

from ..errors import ConfigError, out_of_range
from .gait_diagram import walk_end
from .plot_style import (ACCENT, FONT_PT, SUBPHASE_COLOURS, SUBPHASE_LABELS, SYMBOLS, axes_rows, drawn_note,
                         mark_breaks, new_figure, part_spans, png_bytes, style_axes)
from .registry import PLOTS

TABLE_SUBPHASES = ("double_support", "swing1", "swing2", "swing3")
_RECOVERY_SHADE = {"facecolor": "#D55E00", "alpha": 0.12, "hatch": "///", "edgecolor": "#D55E00", "lw": 0}
_ROLE = {"w": "stance leg", "theta1": "stance leg", "theta2": "upper body", "theta3": "swing hip",
         "theta4": "swing knee", "F_w": "stance leg", "pa": "stance leg", "F_theta1": "stance hip",
         "F_theta2": "stance hip", "F_theta3": "swing hip", "F_theta4": "swing knee"}


# -- what the time plots share ---------------------------------------------------------------
def boundaries(run) -> tuple[list[float], list[float]]:
    """(step boundaries, subphase boundaries) in walk time (s): the heel strikes including the
    last one, and every toe-off, end of swing1 and end of swing2."""
    steps = [s["t_start_s"] for s in run.steps] + ([walk_end(run)] if run.steps else [])
    subs = []
    for s in run.steps:
        toe_off = s["t_start_s"] + s["t_ds_s"]
        subs += [toe_off, toe_off + s["t_swing1_end_s"], toe_off + s["t_swing2_end_s"]]
    return steps, subs


def swing2_recoveries(run) -> list[tuple[int, float, float, str]]:
    """(step, t0, t1, note) of every swing2 that needed a recovery (§4.3): a nonzero
    ``hip_actuator`` or a "recovery-loop" / "ipopt-repair" fallback."""
    found = []
    for s in run.steps:
        for sub in s.get("subphases", []):
            if sub.get("name") != "swing2":
                continue
            actuator = float(sub.get("parameters", {}).get("hip_actuator", 0.0) or 0.0)
            how = [f for f in sub.get("fallbacks", []) if f in ("recovery-loop", "ipopt-repair")]
            if actuator != 0.0 or how:
                toe_off = s["t_start_s"] + s["t_ds_s"]
                note = ", ".join(how + ([f"hip_actuator {actuator:+.3f} rad"] if actuator else []))
                found.append((s["index"], toe_off + s["t_swing1_end_s"], toe_off + s["t_swing2_end_s"], note))
    return found


def subphase_lines(table: dict, column: str) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """subphase -> (t, y) with NaN breaks: the samples of that subphase, each run of them joined
    to the previous sample of the same step (the table drops a subphase's first node, which is
    the previous one's last), never across a step boundary."""
    t, y = np.asarray(table["t"], float), np.asarray(table[column], float)
    sub, step = table["subphase"], np.asarray(table["step"])
    out = {}
    if len(t) < 2:
        return out
    same_step = step[1:] == step[:-1]
    for name in TABLE_SUBPHASES:
        seg = np.flatnonzero(same_step & (sub[1:] == name))      # segment j joins rows j and j + 1
        if seg.size == 0:
            continue
        groups = np.split(seg, np.flatnonzero(np.diff(seg) != 1) + 1)
        rows = np.concatenate([np.r_[g, g[-1] + 1, -1] for g in groups])
        nan = rows < 0
        tt, yy = t[rows], y[rows]
        tt[nan], yy[nan] = np.nan, np.nan
        out[name] = (tt, yy)
    return out


def draw_boundaries(ax, run, subphases: bool = True) -> None:
    """Thin vertical lines at the step boundaries (dark) and the subphase boundaries (light)."""
    steps, subs = boundaries(run)
    trans = ax.get_xaxis_transform()
    if subphases and subs:
        ax.vlines(subs, 0, 1, transform=trans, colors="#c8c8c8", lw=0.5, zorder=1)
    if steps:
        ax.vlines(steps, 0, 1, transform=trans, colors="#444444", lw=0.6, zorder=1)


def draw_recoveries(ax, recoveries) -> None:
    """A hatched span over every swing2 that needed a recovery (:func:`swing2_recoveries`)."""
    for _, t0, t1, _ in recoveries:
        ax.axvspan(t0, t1, zorder=0, **_RECOVERY_SHADE)


def _subphase_handles(recoveries) -> list:
    handles = [Line2D([], [], color=SUBPHASE_COLOURS[s], lw=2, label=SUBPHASE_LABELS[s]) for s in TABLE_SUBPHASES]
    handles += [Line2D([], [], color="#444444", lw=0.8, label="step boundary (heel strike)"),
                Line2D([], [], color="#c8c8c8", lw=1.0, label="subphase boundary")]
    if recoveries:
        what = "; ".join(f"step {k}: {note}" for k, _, _, note in recoveries[:3])
        more = f"; +{len(recoveries) - 3} more" if len(recoveries) > 3 else ""
        handles.append(Patch(label=f"swing2 recovery ({what}{more})", **_RECOVERY_SHADE))
    return handles


def _empty(run, what: str):
    fig = new_figure(8.0, 3.0)
    ax = fig.add_subplot()
    ax.text(0.5, 0.5, f"{run.name}: no completed step, no {what}", ha="center", va="center", fontsize=FONT_PT + 2)
    ax.set_axis_off()
    return fig


def _has_samples(run) -> bool:
    return bool(run.steps) and len(run.table["t"]) > 0


# fixed layout of the time plots, inches (see plot_style.add_axes_in)
_WIDTH, _LEFT, _RIGHT, _TOP, _GAP, _XLABEL, _LEGEND_ROW = 10.5, 1.15, 0.25, 0.42, 0.1, 0.5, 0.24
_NOTE_ROW = 0.2              # a title's second line: which steps a long walk's plot draws


def _series_figure(run, columns, title: str, axis_height: float):
    """One axis per column over time, shared x, each line coloured by subphase; a long walk in
    two parts side by side (plot_style.drawn_steps), the title saying which steps."""
    if not _has_samples(run):
        return _empty(run, title.lower())
    recoveries = swing2_recoveries(run)
    handles = _subphase_handles(recoveries)
    # the subphases and boundaries in one row; a recovery's long label in its own row below
    shade = [h for h in handles if isinstance(h, Patch)]
    handles = [h for h in handles if not isinstance(h, Patch)]
    ncols = len(handles)
    legend_rows = 1 + len(shade)
    note, spans = drawn_note(len(run.steps)), part_spans(run)
    top = _TOP + (_NOTE_ROW if note else 0.0)
    bottom = _XLABEL + legend_rows * _LEGEND_ROW + 0.12
    height = top + len(columns) * axis_height + (len(columns) - 1) * _GAP + bottom
    fig = new_figure(_WIDTH, height, layout=None)
    rows = axes_rows(fig, [axis_height] * len(columns), _LEFT, _RIGHT, top, _GAP, spans)
    for row, column in zip(rows, columns):
        for ax in row:
            style_axes(ax)
            draw_boundaries(ax, run)
            draw_recoveries(ax, recoveries)
            for name, (t, y) in subphase_lines(run.table, column).items():
                ax.plot(t, y, color=SUBPHASE_COLOURS[name], lw=1.2, zorder=3)
            ax.yaxis.set_major_locator(MaxNLocator(nbins=4))     # few ticks: each costs a few artists
            ax.margins(x=0.0, y=0.08)
        row[0].set_ylabel(f"{SYMBOLS[column]}\n{_ROLE[column]}")
        mark_breaks(row)
    rows[-1][0].set_xlabel("t (s), walk time from the first heel strike")
    for ax, span in zip(rows[-1], spans):
        ax.set_xlim(*span)
    fig.suptitle(f"{title}: {run.label}" + (f"\n{note}" if note else ""), fontsize=FONT_PT + 2,
                 y=1 - 0.1 / height, va="top")
    fig.legend(handles=handles, loc="lower center", bbox_to_anchor=(0.5, (0.06 + len(shade) * _LEGEND_ROW) / height),
               ncols=ncols, fontsize=FONT_PT, frameon=False, borderaxespad=0.0)
    if shade:
        fig.legend(handles=shade, loc="lower center", bbox_to_anchor=(0.5, 0.06 / height), ncols=1,
                   fontsize=FONT_PT, frameon=False, borderaxespad=0.0)
    return fig


# -- the plots -------------------------------------------------------------------------------
def torques_figure(run):
    """``torques.png``: F_w, pa, F_θ1, F_θ2 (stance) and F_θ3, F_θ4 (swing; none in double
    support, where the hind leg is kinematic) over time, coloured by subphase."""
    return _series_figure(run, ("F_w", "pa", "F_theta1", "F_theta2", "F_theta3", "F_theta4"),
                          "Applied forces and torques", 1.05)


def states_figure(run):
    """``states.png``: w, θ1, θ2 of the stance model and θ3, θ4 of the swing (hind) leg over
    time, coloured by subphase (in double support θ3, θ4 are the hind leg's kinematic angles)."""
    return _series_figure(run, ("w", "theta1", "theta2", "theta3", "theta4"), "States", 1.15)


def hip_height_figure(run):
    """``hip_height.png``: hip height, the §4.2 reference sinusoid (dashed), the heel-strike floor
    per step and the step boundaries; below, hip height minus reference in mm. A long walk in two
    parts side by side (plot_style.drawn_steps), the title saying which steps."""
    if not _has_samples(run):
        return _empty(run, "hip height")
    note, spans = drawn_note(len(run.steps)), part_spans(run)
    top_in = 0.35 + (_NOTE_ROW if note else 0.0)
    height = 4.65 + top_in
    fig = new_figure(_WIDTH, height, layout=None)
    rows = axes_rows(fig, [2.75, 1.15], 1.0, _RIGHT, top_in, 0.12, spans)
    t, y, ref = run.table["t"], run.table["hip_y"], run.table["hip_y_ref"]
    has_ref = bool(np.isfinite(ref).any())
    # the floor: a step function over each step (a gap where a step recorded no reference)
    ft, fy = [], []
    for s in run.steps:
        floor = (s.get("hip_reference") or {}).get("floor_m")
        if floor is not None:
            ft += [s["t_start_s"], s["t_start_s"] + s["t_step_s"], np.nan]
            fy += [floor, floor, np.nan]
    values = np.concatenate([y, np.asarray(fy, float), ref if has_ref else y])
    lo, hi = float(np.nanmin(values)), float(np.nanmax(values))
    span = max(hi - lo, 1e-3)
    legend = None
    for k, (top, bottom) in enumerate(zip(*rows)):
        for ax in (top, bottom):
            style_axes(ax)
            draw_boundaries(ax, run, subphases=False)
        handles = [Line2D([], [], color="#444444", lw=0.8, label="step boundary (heel strike)")]
        if ft:
            handles += top.plot(ft, fy, color="#0072B2", lw=1.1, ls="-.", zorder=2,
                                label="heel-strike floor (lower of the step's two heel-strike heights)")
        if has_ref:
            handles += top.plot(t, ref, color="#D55E00", lw=1.3, ls=(0, (4, 2.5)), zorder=3,
                                label="reference sinusoid y_ref (§4.2)")
        handles += top.plot(t, y, color=ACCENT, lw=1.1, zorder=4, label="hip height y_hip")
        top.set_ylim(lo - 0.08 * span, hi + 0.55 * span)      # headroom for the legend
        bottom.axhline(0.0, color="#777777", lw=0.8)
        if has_ref:
            bottom.plot(t, 1000.0 * (y - ref), color=ACCENT, lw=1.0)
        bottom.set_xlim(*spans[k])
        legend = legend or handles
    top, bottom = rows[0][0], rows[1][0]
    top.set_ylabel(SYMBOLS["hip_y"])
    top.legend(handles=legend, loc="upper center", ncols=2, fontsize=FONT_PT, frameon=True, framealpha=0.9)
    top.set_title(f"Hip height: {run.label}, {len(run.steps)} steps (§4.2 asks for one bump per step)"
                  + (f"\n{note}" if note else ""), loc="left")
    bottom.set_ylabel("y_hip − y_ref\n(mm)")
    bottom.set_xlabel("t (s), walk time from the first heel strike")
    for row in rows:
        mark_breaks(row)
    return fig


def render_plots(run, names=None) -> dict[str, tuple[str, bytes]]:
    """Every plot of ``run`` (or those in ``names``) as name -> (file name, PNG bytes), ready for
    :func:`klaw_ocp.result_files.atomic.write_rendered` into ``<results>/plots/``."""
    from ..result_files.registry import load
    names = list(PLOTS) if names is None else list(names)
    unknown = sorted(set(names) - set(PLOTS))
    if unknown:
        raise ConfigError(out_of_range("plot names", unknown, f"any of {sorted(PLOTS)}"))
    return {name: (PLOTS[name].file, png_bytes(load(PLOTS[name].figure)(run))) for name in names}
