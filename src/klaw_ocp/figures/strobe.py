"""``legs.png``: a strobe of the dynamic model over the walk, as the paper's figure 8 ("Motion of
one leg for two complete walking sequences", §5), and the model at one instant for figure 10
("Heel-strike for 3 walking sequences").

The dynamic model (§2.3, figure 2) in world coordinates (x forward, y up, m), from a row of
``dynamics.csv`` and its step in ``summary.json``:

- stance leg, a telescope from its ankle (``origin_x_m``, l9) to the hip (``hip_x``, ``hip_y``),
  = ankle + w·(sin θ1, cos θ1);
- swing (in double support: hind) leg, from the stance hip across the pelvis to its own hip
  (``swing_hip_x``, ``swing_hip_y``), then two segments: knee = swing hip − l3·(sin θ3, cos θ3), ankle =
  knee − l4·(sin(θ3 + θ4), cos(θ3 + θ4));
- upper body, from the hip along (sin θ2, cos θ2), length l2.

Which leg is which alternates: the stance leg of step k is ``steps[k]["stance_leg"]``. With
``legs=("right",)`` one leg is drawn as in figure 8: as the stance telescope in its stance steps
and as the swing leg in the others. The feet are kinematic cosmetics (§4.3) and not drawn.

Axis-level functions (:func:`draw_strobe`, :func:`draw_posture`) draw onto a given axis so that a
composite figure can reuse them; :func:`legs_figure` lays a long walk out in several panels of
the same scale. Each leg is one ``LineCollection`` per line width, not one artist per pose.
"""
from __future__ import annotations

import math

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.lines import Line2D
from matplotlib.ticker import MultipleLocator

from ..errors import ConfigError, out_of_range
from .plot_style import FONT_PT, LEG_COLOURS, axes_column, drawn_note, drawn_steps, new_figure, style_axes

TRUNK_COLOUR = "#555555"
GROUND_COLOUR = "#8c6d46"
POSE_SPACING_M = 0.1     # automatic ``every``: the hip travels about this far between two poses
M_PER_INCH = 0.7         # drawing scale of legs.png
MAX_PANEL_M = 8.4        # longest x span of one panel (12 in at M_PER_INCH)
_THIN = {"lw": 0.7, "alpha": 0.55}
_BOLD = {"lw": 1.8, "alpha": 1.0}


def pose_points(run, rows) -> dict:
    """The model's points at table rows ``rows`` (index array): ``hip`` (the stance leg's),
    ``swing_hip`` (the pelvis's other hip, the swing leg's), ``stance_ankle``,
    ``knee``, ``swing_ankle``, ``head`` (end of the upper body), each (n, 2) in m, and
    ``stance_leg`` / ``swing_leg`` (n,) leg names and ``step`` (n,)."""
    rows = np.asarray(rows, dtype=int)
    table, body, steps = run.table, run.body, run.steps
    step = np.asarray(table["step"])[rows].astype(int)
    origin = np.array([s["origin_x_m"] for s in steps])[step]
    stance_leg = np.array([s["stance_leg"] for s in steps])[step]
    hip = np.column_stack([table["hip_x"][rows], table["hip_y"][rows]])
    # the swing leg hangs from the pelvis's other hip (a run folder from before the pelvis has none)
    swing_hip = (np.column_stack([table["swing_hip_x"][rows], table["swing_hip_y"][rows]])
                 if "swing_hip_x" in table else hip)
    th2, th3 = table["theta2"][rows], table["theta3"][rows]
    phi = th3 + table["theta4"][rows]
    knee = swing_hip - body["l3"] * np.column_stack([np.sin(th3), np.cos(th3)])
    return {"hip": hip, "swing_hip": swing_hip, "stance_ankle": np.column_stack([origin, np.full(len(rows), body["l9"])]),
            "knee": knee, "swing_ankle": knee - body["l4"] * np.column_stack([np.sin(phi), np.cos(phi)]),
            "head": hip + body["l2"] * np.column_stack([np.sin(th2), np.cos(th2)]),
            "stance_leg": stance_leg, "swing_leg": np.where(stance_leg == "right", "left", "right"), "step": step}


def auto_every(run, spacing_m: float = POSE_SPACING_M) -> int:
    """Every how many samples a pose is drawn so that the hip travels about ``spacing_m``."""
    x, n = run.table["hip_x"], len(run.table["hip_x"])
    if n < 2:
        return 1
    per_sample = abs(float(x[-1] - x[0])) / (n - 1)
    return max(1, int(round(spacing_m / per_sample))) if per_sample > 0 else max(1, n // 40)


def strobe_rows(run, every: int | None = None, t_range=None) -> tuple[np.ndarray, np.ndarray]:
    """(rows, bold) of the poses to draw: every ``every``-th sample of each step counted from its
    heel strike, within ``t_range`` (t0, t1) if given; ``bold`` marks the heel-strike poses (each
    step's first sample and the walk's last one)."""
    every = auto_every(run) if every is None else int(every)
    if every < 1:
        raise ConfigError(out_of_range("every", every, "an integer >= 1"))
    t, step = np.asarray(run.table["t"], float), np.asarray(run.table["step"])
    n = len(t)
    if n == 0:
        return np.array([], int), np.array([], bool)
    first = np.r_[True, step[1:] != step[:-1]]
    starts = np.maximum.accumulate(np.where(first, np.arange(n), 0))
    bold = first.copy()
    bold[-1] = True
    keep = ((np.arange(n) - starts) % every == 0) | bold
    if t_range is not None:
        keep &= (t >= t_range[0] - 1e-12) & (t <= t_range[1] + 1e-12)
    rows = np.flatnonzero(keep)
    return rows, bold[rows]


def _segments(points: dict, legs, upper_body: bool) -> dict:
    """colour key (a leg, or "trunk") -> array of polylines (n, k, 2) for one LineCollection."""
    stance_lines = np.stack([points["stance_ankle"], points["hip"]], axis=1)
    swing_lines = np.stack([points["hip"], points["swing_hip"], points["knee"], points["swing_ankle"]], axis=1)
    out = {}
    for leg in legs:
        out[leg] = list(stance_lines[points["stance_leg"] == leg]) + list(swing_lines[points["swing_leg"] == leg])
    out["trunk"] = list(np.stack([points["hip"], points["head"]], axis=1)) if upper_body else []
    return out


def draw_ground(ax, x0: float, x1: float) -> None:
    ax.fill_between([x0, x1], -0.05, 0.0, color="#e9e3d9", lw=0, zorder=0)
    ax.plot([x0, x1], [0.0, 0.0], color=GROUND_COLOUR, lw=1.2, zorder=1)


def draw_strobe(ax, run, legs=("right", "left"), every: int | None = None, t_range=None,
                upper_body: bool | None = None, hip_path: bool = True, footfalls: bool = True,
                ground: bool = True) -> dict:
    """A strobe of ``run`` on ``ax``: the poses of :func:`strobe_rows` (heel-strike poses bold),
    ``legs`` in LEG_COLOURS, the upper body (default: when both legs are drawn), the hip path, the
    stance ankles on the ground and (``ground``) the ground under the poses. The axis limits and
    aspect are the caller's. Returns {"rows", "x_range", "y_max"} of what was drawn."""
    legs = tuple(legs)
    bad = [leg for leg in legs if leg not in LEG_COLOURS]
    if bad or not legs:
        raise ConfigError(out_of_range("legs", legs, f"one or both of {tuple(LEG_COLOURS)}"))
    upper_body = len(legs) == 2 if upper_body is None else upper_body
    rows, bold = strobe_rows(run, every, t_range)
    if rows.size == 0:
        return {"rows": rows, "x_range": (0.0, 1.0), "y_max": 1.0}
    points = pose_points(run, rows)
    for style, mask in ((_THIN, ~bold), (_BOLD, bold)):
        sub = {k: v[mask] for k, v in points.items()}
        for key, lines in _segments(sub, legs, upper_body).items():
            if lines:      # the upper body fainter than the legs: it barely moves
                trunk = key == "trunk"
                ax.add_collection(LineCollection(
                    lines, colors=TRUNK_COLOUR if trunk else LEG_COLOURS[key], capstyle="round", joinstyle="round",
                    zorder=3 if trunk else 4, lw=style["lw"], alpha=style["alpha"] * (0.55 if trunk else 1.0)))
    t = run.table["t"]
    window = np.ones(len(t), bool) if t_range is None else (t >= t_range[0]) & (t <= t_range[1])
    if hip_path:
        ax.plot(run.table["hip_x"][window], run.table["hip_y"][window], color="#000000", lw=0.6, ls=":", zorder=5)
    if footfalls:
        ks = sorted(set(points["step"].tolist()))
        for leg in legs:
            xs = [run.steps[k]["origin_x_m"] for k in ks if run.steps[k]["stance_leg"] == leg]
            ax.plot(xs, [0.0] * len(xs), ls="none", marker="^", ms=5, color=LEG_COLOURS[leg], mec="#000000",
                    mew=0.5, zorder=6, clip_on=False)
    every_pts = np.concatenate([points[k] for k in ("hip", "stance_ankle", "knee", "swing_ankle", "head")])
    x_range = (float(every_pts[:, 0].min()), float(every_pts[:, 0].max()))
    if ground:
        draw_ground(ax, x_range[0] - 0.2, x_range[1] + 0.2)
    return {"rows": rows, "x_range": x_range, "y_max": float(every_pts[:, 1].max())}


def sample_at(run, t: float) -> int:
    """The table row nearest walk time ``t``; at a heel strike (two rows at one instant) the row
    that opens the new step."""
    times = np.asarray(run.table["t"], float)
    if times.size == 0:
        raise ConfigError(out_of_range("t", t, "a time of a walk with samples (this one has none)"))
    i = int(np.clip(np.searchsorted(times, t, side="right") - 1, 0, times.size - 1))
    if i + 1 < times.size and abs(times[i + 1] - t) < abs(times[i] - t):
        i += 1
    return i


def draw_posture(ax, run, t: float, legs=("right", "left"), upper_body: bool = True,
                 origin_at: float | None = None, lw: float = 2.4, joints: bool = True,
                 ground: bool = True, colours: dict | None = None) -> dict:
    """The dynamic model of ``run`` at walk time ``t`` (e.g. a heel strike, ``steps[k]
    ["t_start_s"]``) on ``ax``. ``origin_at``: shift x so that the stance ankle is there (to set
    several walks side by side, figure 10); ``colours``: leg -> colour (default LEG_COLOURS).
    Returns the points drawn ({"hip": (x, y), ...} after the shift, plus "stance_leg")."""
    colours = {**LEG_COLOURS, **(colours or {})}
    row = sample_at(run, t)
    p = pose_points(run, [row])
    shift = 0.0 if origin_at is None else origin_at - float(p["stance_ankle"][0, 0])
    pts = {k: p[k][0] + np.array([shift, 0.0]) for k in ("hip", "swing_hip", "stance_ankle", "knee", "swing_ankle", "head")}
    stance, swing = str(p["stance_leg"][0]), str(p["swing_leg"][0])
    if upper_body:
        ax.plot(*np.stack([pts["hip"], pts["head"]]).T, color=TRUNK_COLOUR, lw=lw, solid_capstyle="round", zorder=3)
    if stance in legs:
        ax.plot(*np.stack([pts["stance_ankle"], pts["hip"]]).T, color=colours[stance], lw=lw,
                solid_capstyle="round", zorder=4)
    if swing in legs:
        ax.plot(*np.stack([pts["hip"], pts["swing_hip"], pts["knee"], pts["swing_ankle"]]).T, color=colours[swing], lw=lw,
                solid_capstyle="round", zorder=4)
    if joints:
        names = ["hip"] + (["stance_ankle"] if stance in legs else []) + (["knee", "swing_ankle"] if swing in legs else [])
        ax.plot(*np.array([pts[n] for n in names]).T, ls="none", marker="o", ms=3.5, color="#000000", zorder=5)
    if ground:
        xs = [v[0] for v in pts.values()]
        draw_ground(ax, min(xs) - 0.15, max(xs) + 0.15)
    return {**{k: tuple(v) for k, v in pts.items()}, "stance_leg": stance, "row": row}


def _panels(first: int, last: int, n_panels: int) -> list[tuple[int, int]]:
    """(first step, last step) of each panel: steps ``first`` to ``last`` in groups of about equal
    size."""
    bounds = first + np.linspace(0, last + 1 - first, n_panels + 1).round().astype(int)
    return [(int(a), int(b) - 1) for a, b in zip(bounds[:-1], bounds[1:]) if b > a]


def _x_extent(points: dict, mask: np.ndarray) -> tuple[float, float]:
    g = np.concatenate([points[k][mask, 0] for k in ("hip", "stance_ankle", "swing_ankle", "head")])
    return float(g.min()), float(g.max())


def _legend_handles(legs, upper_body: bool) -> list:
    handles = [Line2D([], [], color=LEG_COLOURS[leg], lw=2, label=f"{leg} leg") for leg in legs]
    if upper_body:
        handles.append(Line2D([], [], color=TRUNK_COLOUR, lw=2, label="upper body"))
    handles += [Line2D([], [], color="#000000", lw=1.8, label="pose at a heel strike (bold)"),
                Line2D([], [], color="#000000", lw=0.6, ls=":", label="hip path"),
                Line2D([], [], ls="none", marker="^", color="#777777", mec="#000000", label="stance ankle x")]
    return handles


def legs_figure(run, legs=("right", "left"), every: int | None = None):
    """``legs.png``: the strobe of :func:`draw_strobe` over the whole walk at one scale
    (M_PER_INCH, equal aspect), in as many panels (rows) as keep each under MAX_PANEL_M, as the
    paper's figure 8; a long walk's first and last steps only (plot_style.drawn_steps: a
    1000-step walk was 93 panels), the title and the panel after the gap saying so."""
    legs = tuple(legs)
    if not run.steps or len(run.table["t"]) == 0:
        fig = new_figure(8.0, 3.0)
        ax = fig.add_subplot()
        ax.text(0.5, 0.5, f"{run.name}: no completed step, no strobe", ha="center", va="center", fontsize=FONT_PT + 2)
        ax.set_axis_off()
        return fig
    upper = len(legs) == 2
    # one leg: half the lines per pose, so twice the poses (figure 8)
    every = auto_every(run, POSE_SPACING_M if upper else POSE_SPACING_M / 2) if every is None else every
    all_points = pose_points(run, np.arange(len(run.table["t"])))
    parts = drawn_steps(len(run.steps))
    groups, ranges, longest = [], [], MAX_PANEL_M
    for a, b in parts:        # a later part in panels as long as the first part's (its last steps: one)
        lo, hi = _x_extent(all_points, (all_points["step"] >= a) & (all_points["step"] <= b))
        panels = _panels(a, b, max(1, math.ceil((hi - lo) / longest)))
        ranges += [_x_extent(all_points, (all_points["step"] >= p) & (all_points["step"] <= q)) for p, q in panels]
        groups += panels
        longest = max([longest] + [r1 - r0 for r0, r1 in ranges])
    skipped = {a1: (b0 + 1, a1 - 1) for (_, b0), (a1, _) in zip(parts, parts[1:])}   # first drawn -> left out
    width_m = max(hi - lo for lo, hi in ranges) + 0.3
    y_top = float(max(all_points["head"][:, 1].max() if upper else 0.0, all_points["hip"][:, 1].max())) + 0.08
    y_bottom = -0.08
    # fixed layout, inches: the axes are exactly the drawing at M_PER_INCH, centred
    handles = _legend_handles(legs, upper)
    ax_w, ax_h = width_m / M_PER_INCH, (y_top - y_bottom) / M_PER_INCH
    fig_w = max(8.0, 0.75 + ax_w + 0.3)
    ncols = len(handles) if fig_w >= 10.5 else 3          # the legend needs about 10 in in one row
    top, gap, bottom = 0.82 + (0.22 if len(parts) > 1 else 0.0), 0.72, 0.62 + 0.25 * -(-len(handles) // ncols)
    left = 0.75 + (fig_w - 0.75 - ax_w - 0.3) / 2
    fig = new_figure(fig_w, top + len(groups) * ax_h + (len(groups) - 1) * gap + bottom, layout=None)
    axes = axes_column(fig, [ax_h] * len(groups), left, fig_w - left - ax_w, top, gap, sharex=False)
    for ax, (a, b), (lo, hi) in zip(axes, groups, ranges):
        style_axes(ax)
        t0 = run.steps[a]["t_start_s"]
        t1 = run.steps[b]["t_start_s"] + run.steps[b]["t_step_s"]
        x0 = lo - 0.15
        draw_ground(ax, x0, x0 + width_m)
        draw_strobe(ax, run, legs=legs, every=every, t_range=(t0, t1), upper_body=upper, ground=False)
        ax.set_xlim(x0, x0 + width_m)
        ax.set_ylim(y_bottom, y_top)
        ax.set_aspect("equal", adjustable="box")
        ax.yaxis.set_major_locator(MultipleLocator(0.5))
        ax.xaxis.set_major_locator(MultipleLocator(1.0 if width_m < 12 else 2.0))
        ax.set_ylabel("y (m)")
        left_out = f"   (after steps {skipped[a][0]}–{skipped[a][1]}, not drawn)" if a in skipped else ""
        ax.set_title(f"steps {a}–{b}, t = {t0:.2f}–{t1:.2f} s{left_out}", loc="left", fontsize=FONT_PT + 1)
    axes[-1].set_xlabel("x (m), forward from the first stance ankle")
    which = " and ".join(legs) + (" legs" if len(legs) == 2 else " leg")
    height = fig.get_size_inches()[1]
    note = drawn_note(len(run.steps))
    fig.suptitle(f"Strobe of the dynamic model (paper's figure 8), {which}, a pose every {every} samples\n"
                 f"{run.label}" + (f"\n{note}" if note else ""), fontsize=FONT_PT + 2, y=1 - 0.08 / height, va="top")
    fig.legend(handles=handles, loc="lower center", bbox_to_anchor=(0.5, 0.06 / height), ncols=ncols,
               fontsize=FONT_PT, frameon=False, borderaxespad=0.0)
    return fig
