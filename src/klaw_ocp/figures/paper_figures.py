"""The paper's figures from finished runs (``klaw-ocp reproduce``, :mod:`klaw_ocp.reproduce`).

- :func:`fig8_figure`: figure 8, "motion of one leg for two complete walking sequences at different
  speeds; top: 2 km/h, 4 cycles, bottom: 5 km/h, 3 cycles": for each walk the strobe of one leg
  (the right one: a telescope in its stance steps, two segments in its swings) with the hip height
  below it, against the same forward distance, so each bump sits under its step.
- :func:`fig10_figure`: figure 10, "heel-strike for 3 walking sequences at v = 5 km/h": the
  dynamic model at a steady heel strike of the natural, short-step and long-step walks, side by
  side on one scale, with sl and sf beside the paper's.
- :func:`acceleration_figure`: section 5's accelerations "with a granularity of one step": the
  requested and the achieved speed per step, sl and sf per step, and the hip height.

Like every plot here they only read results (:class:`~klaw_ocp.result_files.run_data.RunData`).
"""
from __future__ import annotations

import numpy as np

from matplotlib.lines import Line2D

from .plot_style import FONT_PT, LEG_COLOURS, RUN_COLOURS, SUBPHASE_COLOURS, new_figure, style_axes
from .strobe import draw_posture, draw_strobe


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
