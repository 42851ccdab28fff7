"""The body's plots (docs/body.md), drawn from a run's ``angles.csv`` (:attr:`RunData.angles`) and
its heel strikes and toe-offs (:func:`~klaw_ocp.figures.gait_diagram.gait_events`):

- ``joint_angles.png``: hip flexion, knee flexion and ankle dorsiflexion of each leg over the
  normalised gait cycle (0-100 % from a heel strike of that leg to its next), the way gait
  laboratories show them: every cycle thin, their mean bold, the mean toe-off marked (a long
  walk's thin lines only for the cycles of the steps the other plots draw, plot_style.drawn_steps).
- ``body.png``: the skeleton at the heel strikes that open the steps, drawn side on from the
  forward kinematics of the angles (:func:`klaw_ocp.body_motion.skeleton.forward_kinematics`), with
  the dynamic model of ``legs.png`` over it (the new stance leg's telescope, the hind leg with the
  virtual leg's angles, the upper body), so that the two can be seen to agree. (At the walk's last
  heel strike the model would show the leg finishing its stance as a telescope, which has no knee
  to compare with.)

Like every plot they read results only: the angles are in degrees, as in the file.
"""
from __future__ import annotations

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.lines import Line2D
from matplotlib.patches import Circle
from matplotlib.ticker import MultipleLocator

from ..body_motion.skeleton import ANGLE_NAMES, SIDES, forward_kinematics
from .gait_diagram import gait_events
from .plot_style import FONT_PT, LEG_COLOURS, add_axes_in, drawn_steps, new_figure, part_spans, style_axes
from .strobe import TRUNK_COLOUR, draw_ground, draw_posture

#: (row label, angle name after the side prefix)
JOINT_ROWS = (("hip flexion (°)", "hip_flexion"), ("knee flexion (°)", "knee_flexion"),
              ("ankle dorsiflexion (°)", "ankle_dorsiflexion"))
CYCLE_POINTS = 101            # 0, 1, ..., 100 % of the cycle
MAX_POSTURES = 8              # body.png draws at most this many heel strikes, evenly chosen
POSTURE_HALF_WIDTH_M = 0.75   # each posture's panel spans the pelvis x ± this
MODEL_COLOUR = "#000000"

# -- the stick figure, shared with walk.gif (:mod:`klaw_ocp.figures.animation`) ----------------------------
SPINE = ("pelvis", "L5", "L3", "L1", "T12", "T6", "T1", "C7", "C4", "C1")


def _leg(s):
    return [("joint", f"{s}_hip"), ("joint", f"{s}_knee"), ("joint", f"{s}_ankle"), ("landmark", f"{s}_heel"),
            ("joint", f"{s}_toes"), ("end", f"{s}_toes")]


#: the polylines of the stick figure: name -> (colour key, points); a point is (kind, name), kind
#: "joint", "landmark" or "end" (site). The pelvis (hip to hip) is drawn only from the front.
CHAINS = {
    "spine": ("trunk", [("joint", j) for j in SPINE]),
    "shoulders": ("trunk", [("joint", "r_shoulder"), ("joint", "T1"), ("joint", "l_shoulder")]),
    "pelvis": ("trunk", [("joint", "r_hip"), ("joint", "pelvis"), ("joint", "l_hip")]),
    **{f"{side}_leg": (side, _leg(s)) for s, side in SIDES},
    **{f"{side}_foot": (side, [("joint", f"{s}_ankle"), ("joint", f"{s}_toes")]) for s, side in SIDES},
    **{f"{side}_arm": (side, [("joint", f"{s}_shoulder"), ("joint", f"{s}_elbow"), ("end", f"{s}_elbow")])
       for s, side in SIDES},
}


def has_angles(run) -> bool:
    """Whether ``run`` has a body to draw: a completed step and two frames of angles."""
    return bool(run.steps) and run.angles is not None and len(run.angles["time"]) > 1


def skeleton_at(run, times):
    """The skeleton (skeleton.SkeletonFrames) at walk times ``times``: the root and the angles
    interpolated linearly between the frames of angles.csv (degrees, as in the file)."""
    a, times = run.angles, np.clip(np.atleast_1d(np.asarray(times, float)), run.angles["time"][0],
                                   run.angles["time"][-1])
    root = np.column_stack([np.interp(times, a["time"], a[f"root_{axis}"]) for axis in "xyz"])
    angles = np.radians(np.column_stack([np.interp(times, a["time"], a[name]) for name in ANGLE_NAMES]))
    return forward_kinematics(run.body_model(), root, angles)


def _point(skeleton, kind: str, name: str) -> np.ndarray:
    if kind == "joint":
        return skeleton.position(name)
    return (skeleton.landmarks if kind == "landmark" else skeleton.end_sites)[name]


def chain_points(skeleton) -> dict:
    """CHAINS name -> (n, k, 3): each polyline's points at every frame of ``skeleton``."""
    return {name: np.stack([_point(skeleton, *p) for p in points], axis=1) for name, (_, points) in CHAINS.items()}


def _note(text: str):
    fig = new_figure(8.0, 3.0)
    ax = fig.add_subplot()
    ax.text(0.5, 0.5, text, ha="center", va="center", fontsize=FONT_PT + 2)
    ax.set_axis_off()
    return fig


def gait_cycles(run, side: str) -> list[tuple[float, float, float | None]]:
    """(heel strike, next heel strike, toe-off between them or None) of every complete gait cycle
    of ``side``'s leg (s, walk time)."""
    events = gait_events(run)
    strikes = [t for leg, kind, t in events if leg == side and kind == "heel_strike"]
    toe_offs = np.array([t for leg, kind, t in events if leg == side and kind == "toe_off"])
    cycles = []
    for t0, t1 in zip(strikes, strikes[1:]):
        inside = toe_offs[(toe_offs > t0) & (toe_offs < t1)]
        cycles.append((t0, t1, float(inside[0]) if inside.size else None))
    return cycles


def cycle_curves(run, side: str, angle: str) -> tuple[np.ndarray, list[float]]:
    """The angle ``<side prefix>_<angle>`` (degrees) of every cycle of :func:`gait_cycles`,
    resampled at CYCLE_POINTS points of 0-100 %: (cycles, CYCLE_POINTS), and each cycle's
    toe-off in % (where it has one)."""
    t, values = run.angles["time"], run.angles[f"{side[0]}_{angle}"]
    percent = np.linspace(0.0, 100.0, CYCLE_POINTS)
    curves, toe_offs = [], []
    for t0, t1, toe_off in gait_cycles(run, side):
        curves.append(np.interp(t0 + percent / 100 * (t1 - t0), t, values))
        if toe_off is not None:
            toe_offs.append(100 * (toe_off - t0) / (t1 - t0))
    return np.array(curves).reshape(-1, CYCLE_POINTS), toe_offs


def _grid(fig, rows: int, columns: int, width: float, height: float, left: float, top: float,
          hgap: float, vgap: float) -> np.ndarray:
    """rows x columns axes of width x height inches, placed from the figure's top-left corner (a
    fixed layout: a constrained one costs about as much as drawing the figure again)."""
    fig_height = fig.get_size_inches()[1]
    return np.array([[add_axes_in(fig, left + c * (width + hgap), fig_height - top - (r + 1) * height - r * vgap,
                                  width, height) for c in range(columns)] for r in range(rows)])


def joint_angles_figure(run):
    """``joint_angles.png``: hip, knee and ankle of both legs over the normalised gait cycle."""
    if not has_angles(run):
        return _note(f"{run.name}: no angles.csv (no completed step, or written before it), no joint angles")
    percent = np.linspace(0.0, 100.0, CYCLE_POINTS)
    parts, spans = drawn_steps(len(run.steps)), part_spans(run)
    note = "" if len(parts) == 1 else ("a long walk: the mean of every cycle; thin, the cycles that start in steps "
                                       + " and ".join(f"{a}–{b}" for a, b in parts))
    extra = 0.2 if note else 0.0                  # the title's second line
    fig = new_figure(10.5, 7.4 + extra, layout=None)
    axes = _grid(fig, len(JOINT_ROWS), 2, 4.55, 1.85, 0.85, 0.62 + extra, 0.3, 0.18)
    for col, (_, side) in enumerate(SIDES):
        colour = LEG_COLOURS[side]
        # the thin lines: the cycles of the steps drawn (a band of a long walk's hundreds is no more
        # readable, and drawing them took 50 MB)
        starts = np.array([t0 for t0, _, _ in gait_cycles(run, side)])
        thin = np.ones(len(starts), bool) if len(parts) == 1 else np.any(
            [(starts >= t0 - 1e-9) & (starts < t1 - 1e-9) for t0, t1 in spans], axis=0)
        for row, (label, angle) in enumerate(JOINT_ROWS):
            ax = axes[row, col]
            style_axes(ax)
            curves, toe_offs = cycle_curves(run, side, angle)
            if len(curves):
                # every cycle in one artist: NaN ends each cycle's line
                shown = curves[thin]
                cycles = np.column_stack([shown, np.full(len(shown), np.nan)]).ravel()
                ax.plot(np.tile(np.r_[percent, np.nan], len(shown)), cycles, color=colour, lw=0.6, alpha=0.35)
                ax.plot(percent, curves.mean(axis=0), color=colour, lw=2.2)
            else:
                ax.text(0.5, 0.5, "no complete gait cycle", transform=ax.transAxes, ha="center", va="center",
                        fontsize=FONT_PT)
            if toe_offs:
                mean = float(np.mean(toe_offs))
                ax.axvline(mean, color="#444444", lw=1.0, ls="--")
                ax.text(mean + 1, 0.96, f"toe-off {mean:.0f} %", transform=ax.get_xaxis_transform(),
                        va="top", fontsize=FONT_PT - 1, color="#444444")
            ax.axhline(0.0, color="#777777", lw=0.6)
            ax.set_xlim(0, 100)
            if col == 0:
                ax.set_ylabel(label)
            else:                       # the left column's scale (set below) serves both
                ax.tick_params(labelleft=False)
            if row == 0:
                ax.set_title(f"{side} leg: {len(curves)} cycle{'s' if len(curves) != 1 else ''}", loc="left")
            if row < len(JOINT_ROWS) - 1:
                ax.tick_params(labelbottom=False)
        axes[-1, col].set_xlabel("% of the gait cycle (from heel strike to heel strike)")
    for row in range(len(JOINT_ROWS)):         # one scale per joint, both legs
        low = min(a.get_ylim()[0] for a in axes[row])
        high = max(a.get_ylim()[1] for a in axes[row])
        for ax in axes[row]:
            ax.set_ylim(low, high)
    handles = [Line2D([], [], color="#777777", lw=0.6, alpha=0.6, label="one cycle"),
               Line2D([], [], color="#777777", lw=2.2, label="mean of the cycles"),
               Line2D([], [], color="#444444", lw=1.0, ls="--", label="mean toe-off")]
    fig.legend(handles=handles, loc="lower center", bbox_to_anchor=(0.5, 0.01), ncols=3, fontsize=FONT_PT,
               frameon=False)
    fig.suptitle(f"Joint angles over the gait cycle (flexion and dorsiflexion positive): {run.label}"
                 + (f"\n{note}" if note else ""), fontsize=FONT_PT + 2, y=0.985)
    return fig


def step_heel_strikes(run) -> list[tuple[float, str]]:
    """(walk time, leg) of every heel strike that opens a step (not the walk's last one)."""
    starts = {s["t_start_s"] for s in run.steps}
    return [(t, leg) for leg, kind, t in gait_events(run) if kind == "heel_strike" and t in starts]


#: the side view's polylines per colour key, from the CHAINS of :func:`chain_points` (the pelvis,
#: hip to hip, shows only from the front): body.png draws each key's in this order
_SIDE_VIEW = {"trunk": ("spine", "shoulders"),
              **{side: (f"{side}_leg", f"{side}_arm", f"{side}_foot") for _, side in SIDES}}


def _side_view_chains(skeleton) -> dict:
    """colour key -> polylines (each (k, 2), side view x-y) of one skeleton frame: each leg with its
    foot, each arm from the shoulder line, and the trunk from the pelvis to the top of the head."""
    points = chain_points(skeleton)
    return {key: [points[name][0, :, :2] for name in names] for key, names in _SIDE_VIEW.items()}


def draw_skeleton(ax, skeleton, lw: float = 2.6) -> None:
    """One skeleton frame side on: the left side (the far one, z < 0) first and fainter."""
    chains = _side_view_chains(skeleton)
    for key, alpha, z in (("left", 0.55, 3), ("trunk", 0.8, 4), ("right", 1.0, 5)):
        colour = TRUNK_COLOUR if key == "trunk" else LEG_COLOURS[key]
        ax.add_collection(LineCollection(chains[key], colors=colour, lw=lw, alpha=alpha, zorder=z,
                                         capstyle="round", joinstyle="round"))
    # the head: a circle from just below the head joint (C1) to the top of the head
    neck, top = skeleton.position("C1")[0, :2], skeleton.end_sites["C1"][0, :2]
    ax.add_patch(Circle(neck + 0.45 * (top - neck), 0.55 * float(np.hypot(*(top - neck))), facecolor="white",
                        edgecolor=TRUNK_COLOUR, lw=lw * 0.6, zorder=4))


def body_figure(run):
    """``body.png``: the skeleton from angles.csv at up to MAX_POSTURES heel strikes that open steps,
    each with the dynamic model at the same instant drawn over it in thin black."""
    strikes = step_heel_strikes(run) if has_angles(run) else []
    if not strikes:
        return _note(f"{run.name}: no angles.csv (no completed step, or written before it) or no heel strike, no body")
    chosen = sorted(set(np.linspace(0, len(strikes) - 1, min(MAX_POSTURES, len(strikes))).round().astype(int)))
    columns = min(4, len(chosen))
    rows = -(-len(chosen) // columns)
    height = run.body["height"]
    y_low, y_high = -0.06, height + 0.08
    panel_w = 2.3                                             # inches; the panel's height keeps the scale
    panel_h = panel_w * (y_high - y_low) / (2 * POSTURE_HALF_WIDTH_M)
    fig = new_figure(0.55 + columns * (panel_w + 0.35), 0.75 + rows * (panel_h + 0.62) + 0.55, layout=None)
    axes = _grid(fig, rows, columns, panel_w, panel_h, 0.55, 0.95, 0.35, 0.62).ravel()
    for ax, index in zip(axes, chosen):
        t, leg = strikes[index]
        skeleton = skeleton_at(run, [t])
        centre = float(skeleton.position("pelvis")[0, 0])
        style_axes(ax)
        draw_ground(ax, centre - POSTURE_HALF_WIDTH_M, centre + POSTURE_HALF_WIDTH_M)
        draw_skeleton(ax, skeleton)
        draw_posture(ax, run, t, lw=0.9, ground=False, colours={"right": MODEL_COLOUR, "left": MODEL_COLOUR})
        ax.set_xlim(centre - POSTURE_HALF_WIDTH_M, centre + POSTURE_HALF_WIDTH_M)
        ax.set_ylim(y_low, y_high)
        ax.set_title(f"{leg} heel strike, t = {t:.2f} s", fontsize=FONT_PT)
        ax.tick_params(labelsize=FONT_PT - 1)
        ax.xaxis.set_major_locator(MultipleLocator(0.5))
    for ax in axes[len(chosen):]:
        ax.set_axis_off()
    handles = [Line2D([], [], color=LEG_COLOURS["right"], lw=2.6, label="right leg and arm"),
               Line2D([], [], color=LEG_COLOURS["left"], lw=2.6, alpha=0.55, label="left leg and arm (far side)"),
               Line2D([], [], color=TRUNK_COLOUR, lw=2.6, label="spine, shoulders, head"),
               Line2D([], [], color=MODEL_COLOUR, lw=0.9, marker="o", ms=3,
                      label="the dynamic model (legs.png): the new stance leg's telescope, the hind leg, the upper body")]
    fig.legend(handles=handles, loc="lower center", bbox_to_anchor=(0.5, 0.005), ncols=3 if columns == 4 else 2,
               fontsize=FONT_PT, frameon=False)
    which = (f"the {len(strikes)} heel strikes" if len(chosen) == len(strikes)
             else f"{len(chosen)} of the {len(strikes)} heel strikes") + " that open its steps"
    fig.suptitle(f"The body (angles.csv) at {which}, side on (x forward, y up, m)\n{run.label}",
                 fontsize=FONT_PT + 1, y=1 - 0.1 / fig.get_size_inches()[1], va="top")
    return fig
