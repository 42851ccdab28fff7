"""The paper's figures from finished runs (``klaw-ocp reproduce``, :mod:`klaw_ocp.reproduce`).

- :func:`fig8_figure`: figure 8, "motion of one leg for two complete walking sequences at different
  speeds; top: 2 km/h, 4 cycles, bottom: 5 km/h, 3 cycles": for each walk the strobe of one leg
  (the right one: a telescope in its stance steps, two segments in its swings) with the hip height
  below it, against the same forward distance, so each bump sits under its step.
- :func:`fig10_figure`: figure 10, "heel-strike for 3 walking sequences at v = 5 km/h": the
  dynamic model at a steady heel strike of the natural, short-step and long-step walks, side by
  side on one scale, with sl and sf beside the paper's.
- :func:`fig9_figure`: figure 9, "illustration of pelvic list at toe-off. Left: natural pelvic
  list, right: accentuated pelvic list": the skeleton of each walk at the toe-off of the same
  steady step, seen from behind (the frontal plane, z the walker's right), a close-up of its pelvis
  beneath, and the swing hip torque F_theta3 over that step's swing with the swing hip's height
  below the stance hip, the list's effect on the dynamics (§2.4).
- :func:`acceleration_figure`: section 5's accelerations "with a granularity of one step": the
  requested and the achieved speed per step, sl and sf per step, and the hip height.

Like every plot here they only read results (:class:`~klaw_ocp.result_files.run_data.RunData`).
"""
from __future__ import annotations

import numpy as np

from matplotlib.lines import Line2D
from matplotlib.patches import Circle

from .body_plots import CHAINS, chain_points, skeleton_at
from .plot_style import FONT_PT, LEG_COLOURS, RUN_COLOURS, SUBPHASE_COLOURS, new_figure, style_axes
from .strobe import GROUND_COLOUR, TRUNK_COLOUR, draw_posture, draw_strobe


#: figure 9's walks in the torque panels (not the legs' colours): natural, accentuated
FIG9_COLOURS = ("#000000", "#D55E00")
ROLE_COLOURS = {"stance": SUBPHASE_COLOURS["stance"], "landing": SUBPHASE_COLOURS["swing2"]}


def _step_spans(run):
    return [(s["t_start_s"], s["t_start_s"] + s["t_step_s"]) for s in run.steps]


def fig8_figure(slow, fast):
    """Figure 8: one leg's strobe and the hip height of two start-stop walks (``slow`` above)."""
    # strobe panels about as tall as their metre of height is wide in x (the 2 km/h walk covers
    # 4.3 m, the 5 km/h walk 5.1 m), so the legs are not foreshortened
    fig = new_figure(13.0, 10.6)
    grid = fig.add_gridspec(4, 1, height_ratios=[3.7, 1.0, 3.2, 1.0])
    for row, (run, title) in enumerate(((slow, "top: 2 km/h, 4 cycles"), (fast, "bottom: 5 km/h, 3 cycles"))):
        ax = fig.add_subplot(grid[2 * row])
        draw_strobe(ax, run, legs=("right",))
        ax.set_title(f"Figure 8, {title}: the right leg from standing to standing "
                     f"({len(run.steps)} steps, {run.duration:.2f} s)", fontsize=FONT_PT + 1)
        ax.set_ylabel("height (m)")
        style_axes(ax)
        hip = fig.add_subplot(grid[2 * row + 1], sharex=ax)
        x, y = run.table["hip_x"], run.table["hip_y"]
        hip.plot(x, y, color=LEG_COLOURS["right"], lw=1.2, label="hip height")
        for step in run.steps:
            hip.axvline(step["origin_x_m"], color="0.6", lw=0.5, ls=":")
        hip.set_ylabel("hip (m)")
        hip.set_xlabel("forward distance x (m); dotted: stance ankles")
        lo, hi = float(np.nanmin(y)), float(np.nanmax(y))
        hip.set_ylim(lo - 0.15 * (hi - lo + 1e-3), hi + 0.25 * (hi - lo + 1e-3))
        style_axes(hip)
    return fig


def _heel_strike_time(run) -> tuple[int, float]:
    """A steady heel strike: the end of the middle step (its swing leg lands)."""
    k = len(run.steps) // 2
    step = run.steps[k]
    return k, step["t_start_s"] + step["t_step_s"]


def fig10_figure(runs, paper: dict):
    """Figure 10: the heel-strike posture of the natural, short- and long-step walks."""
    fig = new_figure(12.0, 6.6)
    axes = fig.subplots(1, len(runs), sharey=True)
    keys = ("natural", "short", "long")
    titles = {"natural": "natural walk (only v given)", "short": "short steps (v and sl = 0.50 m)",
              "long": "long steps (v and sl = 1.05 m)"}
    for ax, run, key in zip(np.atleast_1d(axes), runs, keys):
        k, t = _heel_strike_time(run)
        step = run.steps[k]
        stance = step["stance_leg"]
        landing = "left" if stance == "right" else "right"
        # colour by role, not by side: the middle step's stance leg is the right or left one
        draw_posture(ax, run, t - 1e-9, origin_at=0.0,     # the landing leg still swinging, knee straight
                     colours={stance: ROLE_COLOURS["stance"], landing: ROLE_COLOURS["landing"]})
        ax.set_xlim(-0.25, 1.3)          # one scale for the three walks
        ax.set_ylim(-0.1, 1.9)
        # no fixed aspect (it fights the constrained layout and clips the titles): the figure's
        # size makes a metre about as long across as up
        ours = f"sl = {step['step_length_m']:.3f} m, sf = {step['step_frequency_spm']:.1f} steps/min"
        ref = paper.get(key, {})
        theirs = f"paper: sl = {ref.get('sl_m', float('nan')):.2f} m, sf = {ref.get('sf_spm', float('nan')):.1f}"
        ax.set_title(f"{titles[key]}\n{ours}\n{theirs}", fontsize=FONT_PT + 1)
        ax.set_xlabel("x from the stance ankle (m)")
        style_axes(ax)
    np.atleast_1d(axes)[0].set_ylabel("height (m)")
    fig.legend(handles=[
        Line2D([], [], color=ROLE_COLOURS["stance"], lw=2.4, label="stance leg (telescope, w)"),
        Line2D([], [], color=ROLE_COLOURS["landing"], lw=2.4, label="landing swing leg (thigh, shank)"),
        Line2D([], [], color="0.3", lw=2.4, label="upper body")],
        fontsize=FONT_PT, loc="outside lower center", ncols=3,
        title="Figure 10: heel strike of three walks at v = 5 km/h, the landing leg in front", title_fontsize=FONT_PT + 2)
    return fig


def acceleration_figure(run):
    """Speed, step length and frequency per step, and the hip height, of a scheduled walk."""
    steps = run.steps
    index = np.array([s["index"] for s in steps])
    requested = np.array([s["speed_kmh"] for s in steps])
    t, x = run.table["t"], run.table["hip_x"]
    achieved = []
    for s in steps:
        t0, t1 = s["t_start_s"], s["t_start_s"] + s["t_step_s"]
        achieved.append(3.6 * (np.interp(t1, t, x) - np.interp(t0, t, x)) / (t1 - t0))
    fig = new_figure(10.0, 8.0)
    ax_v, ax_l, ax_h = fig.subplots(3, 1)
    ax_v.step(index, requested, where="mid", color=RUN_COLOURS[0], lw=1.5, label="requested v (the plan, eq. 1)")
    ax_v.plot(index, achieved, "o", color=RUN_COLOURS[1], ms=5, label="achieved: hip travel over the step / t_step")
    ax_v.set_xlabel("step")
    ax_v.set_ylabel("v (km/h)")
    ax_v.set_title(f"{run.name}: the speed changes with a granularity of one step (section 5)")
    ax_v.legend(fontsize=FONT_PT, loc="lower center")
    ax_l.plot(index, [s["step_length_m"] for s in steps], "s-", color=RUN_COLOURS[0], label="sl (m)")
    ax_l.set_xlabel("step")
    ax_l.set_ylabel("sl (m)", color=RUN_COLOURS[0])
    ax_f = ax_l.twinx()
    ax_f.plot(index, [s["step_frequency_spm"] for s in steps], "^-", color=RUN_COLOURS[2], label="sf (steps/min)")
    ax_f.set_ylabel("sf (steps/min)", color=RUN_COLOURS[2])
    ax_f.tick_params(labelsize=FONT_PT)
    ax_l.set_title("step length and step frequency of each step")
    ax_h.plot(t, run.table["hip_y"], color=RUN_COLOURS[0], lw=1.2, label="hip height")
    ax_h.plot(t, run.table["hip_y_ref"], color="0.3", lw=0.9, ls="--", label="the sinusoid it is guided towards")
    for t0, _ in _step_spans(run):
        ax_h.axvline(t0, color="0.6", lw=0.5, ls=":")
    ax_h.set_xlabel("t (s); dotted: heel strikes")
    ax_h.set_ylabel("hip height (m)")
    ax_h.set_title("hip height")
    ax_h.legend(fontsize=FONT_PT, loc="lower right")
    for ax in (ax_v, ax_l, ax_h):
        style_axes(ax)
    return fig


def swing_hip_torque(run, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Step ``k``'s swing (its swing1-3 rows): time from toe-off (s), F_theta3 (N m), subphase."""
    table, step = run.table, run.steps[k]
    rows = (table["step"] == k) & np.char.startswith(table["subphase"].astype(str), "swing")
    return (table["t"][rows] - step["t_start_s"] - step["t_ds_s"], table["F_theta3"][rows],
            table["subphase"][rows].astype(str))


def _hips(skeleton, stance: str) -> tuple[np.ndarray, np.ndarray]:
    """The stance-side and the swing-side hip (n, 3) of a skeleton."""
    s, o = ("r", "l") if stance == "right" else ("l", "r")
    return skeleton.position(f"{s}_hip"), skeleton.position(f"{o}_hip")


def _front_view(ax, chains: dict, head: tuple, names=None) -> None:
    """The stick figure at one instant in the frontal plane (z right, y up), seen from behind."""
    for name, (key, _) in CHAINS.items():
        if names is None or name in names:
            colour = TRUNK_COLOUR if key == "trunk" else LEG_COLOURS[key]
            p = chains[name][0]
            ax.plot(p[:, 2], p[:, 1], color=colour, lw=3.2 if name == "pelvis" else 2.2, marker="o", ms=2.5,
                    solid_capstyle="round", solid_joinstyle="round", zorder=4 if name == "pelvis" else 3)
    if head is not None:
        ax.add_patch(Circle(head[0], head[1], facecolor="white", edgecolor=TRUNK_COLOUR, lw=1.4, zorder=3))


def fig9_figure(runs, step: int, labels):
    """Figure 9: ``runs`` (natural list first) at the toe-off of step ``step`` (``labels``: what
    each list is called), each seen from behind with its pelvis close up below it, and their swing
    hip torque and swing hip height over that step's swing."""
    fig = new_figure(14.0, 8.2)
    grid = fig.add_gridspec(2, 3, width_ratios=[1.0, 1.0, 2.0], height_ratios=[3.0, 1.3])
    ax_f = fig.add_subplot(grid[0, 2])
    ax_h = fig.add_subplot(grid[1, 2], sharex=ax_f)
    for i, (run, label) in enumerate(zip(runs, labels)):
        s = run.steps[step]
        stance = s["stance_leg"]
        swing = "left" if stance == "right" else "right"
        listed = float(run.summary["attributes"]["pelvic_list"])
        t_off = s["t_start_s"] + s["t_ds_s"]
        sk = skeleton_at(run, [t_off])
        chains = chain_points(sk)
        neck, top = sk.position("C1")[0], sk.end_sites["C1"][0]
        hip_st, hip_sw = (h[0] for h in _hips(sk, stance))
        now = float(np.interp(t_off, run.angles["time"], run.angles["pelvis_list"]))
        drop = hip_st[1] - hip_sw[1]
        ax = fig.add_subplot(grid[0, i])
        _front_view(ax, chains, (neck[[2, 1]] + 0.45 * (top - neck)[[2, 1]], 0.55 * np.linalg.norm(top - neck)))
        ax.axhline(0.0, color=GROUND_COLOUR, lw=2.0, zorder=1)
        centre = float(sk.position("pelvis")[0, 2])
        ax.set_ylim(-0.05, float(run.body["height"]) + 0.1)     # x follows: one scale across and up
        ax.set_aspect("equal", adjustable="datalim")
        for side, word in ((stance, "stance leg"), (swing, "swing leg\n(toe-off)")):
            knee = chains[f"{side}_leg"][0][1]
            out = 1 if knee[2] > centre else -1
            ax.annotate(word, (knee[2], knee[1]), xytext=(14 * out, 0), textcoords="offset points",
                        ha="left" if out > 0 else "right", va="center", fontsize=FONT_PT, color=LEG_COLOURS[side])
        ax.set_title(f"{label} list: pelvic_list = {listed:g}°\nat toe-off (step {step}): list {now:.1f}°,\n"
                     f"swing ({swing}) hip {100 * drop:.1f} cm lower", fontsize=FONT_PT + 1)
        ax.set_xlabel("z: the walker's right (m)")
        style_axes(ax)
        # the pelvis close up, with the level through the stance hip
        zoom = fig.add_subplot(grid[1, i])
        _front_view(zoom, chains, None, names=("pelvis", "spine", "right_leg", "left_leg"))
        zoom.axhline(hip_st[1], color="0.35", lw=0.9, ls="--", zorder=2)
        zoom.annotate(f"list {now:.1f}°", (hip_sw[2], hip_sw[1]), xytext=(0, -16), textcoords="offset points",
                      ha="center", va="top", fontsize=FONT_PT + 1)
        zoom.set_xlim(centre - 0.15, centre + 0.15)
        zoom.set_ylim(hip_st[1] - 0.085, hip_st[1] + 0.04)
        zoom.set_aspect("equal", adjustable="box")
        zoom.set_title("pelvis close up (dashed: level)", fontsize=FONT_PT + 1)
        zoom.set_xlabel("z (m)")
        style_axes(zoom)
        # the swing: F_theta3 (each subphase its own line: the torque jumps between them) and the hip
        t, f, sub = swing_hip_torque(run, step)
        colour = FIG9_COLOURS[i % len(FIG9_COLOURS)]
        for j, name in enumerate(("swing1", "swing2", "swing3")):
            rows = sub == name
            ax_f.plot(t[rows], f[rows], color=colour, lw=1.6,
                      label=f"{label}: pelvic_list {listed:g}°" if j == 0 else None)
        k = int(np.nanargmax(np.abs(f)))
        ax_f.plot(t[k], f[k], "o", color=colour, ms=6)
        ax_f.annotate(f"peak {f[k]:.1f} N m", (t[k], f[k]), xytext=(-8, 0), textcoords="offset points",
                      ha="right", va="center", fontsize=FONT_PT, color=colour)
        tt = np.linspace(t_off, s["t_start_s"] + s["t_step_s"], 160)
        hip_st, hip_sw = _hips(skeleton_at(run, tt), stance)
        ax_h.plot(tt - t_off, 100 * (hip_sw[:, 1] - hip_st[:, 1]), color=colour, lw=1.6,
                  label=f"{label}: lowest {100 * (hip_sw[:, 1] - hip_st[:, 1]).min():.1f} cm")
    ref = runs[0].steps[step]
    for ax in (ax_f, ax_h):
        for edge in (ref["t_swing1_end_s"], ref["t_swing2_end_s"]):
            ax.axvline(edge, color="0.5", lw=0.7, ls=":")
        style_axes(ax)
    bounds = (0.0, ref["t_swing1_end_s"], ref["t_swing2_end_s"], ref["t_swing_s"])
    for name, a, b in zip(("swing1", "swing2", "swing3"), bounds, bounds[1:]):
        ax_f.text((a + b) / 2, 1.01, name, transform=ax_f.get_xaxis_transform(), ha="center", va="bottom",
                  fontsize=FONT_PT + 1, color="0.3")
    ax_f.axhline(0.0, color="0.3", lw=0.6)
    ax_f.set_ylabel("swing hip torque F_θ3 (N m)")
    ax_f.set_title(f"the swing hip torque over step {step}'s swing (§2.4: the lowered hip \"might 'force' the\n"
                   "dynamic leg to increase its hip torque to avoid stubbing its toe\")", fontsize=FONT_PT + 1, pad=16)
    ax_f.legend(fontsize=FONT_PT, loc="lower right")
    ax_h.set_ylabel("swing hip − stance hip (cm)")
    ax_h.set_xlabel("time from toe-off (s); dotted: the ends of swing1 and swing2")
    ax_h.legend(fontsize=FONT_PT, loc="lower right")
    fig.suptitle(f"Figure 9: pelvic list at toe-off, left natural, right accentuated ({ref['speed_kmh']:g} km/h, "
                 f"{runs[0].body['height']:g} m, {runs[0].body['mass']:g} kg; seen from behind)",
                 fontsize=FONT_PT + 3)
    return fig
