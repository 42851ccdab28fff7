"""``gait_diagram.png``: the state-phase timings of a walk drawn as the paper's figure 3
("Locomotion cycle for bipedal walking", §3 "state-phase timings", eq. 2).

One row per leg (right, left) over walk time: a stance bar from the leg's heel strike to its
toe-off in the next step, a swing bar split into swing1 / swing2 / swing3 (they end at 50 / 85 /
100 % of t_swing after toe-off, §4.3), the double supports (both feet down) shaded across both
rows, heel strikes and toe-offs marked. The lower panel zooms on one representative step (a
middle one) and writes t_step, t_ds, t_stance and t_swing on it as dimension lines, with their
values in a box.

The bar geometry is the pure function :func:`gait_bars` (tested against the summary timings):

- step k starts at ``t_start_s`` with the heel strike of its stance leg; the other (hind) leg
  stays down until its toe-off at ``t_start_s + t_ds_s``, then swings until ``t_start_s +
  t_step_s``, where it strikes and becomes the stance leg of step k + 1;
- a leg's stance therefore lasts from its heel strike to the toe-off of the next step,
  ``t_step(k) + t_ds(k + 1)`` (= t_stance of eq. 2 when the timings do not change);
- before t = 0 nothing is drawn (the hind leg's stance bar starts at 0); a walk that starts from
  rest has no heel strike at 0 (both feet stand side by side); a leg still down when the walk
  ends has its stance bar drawn to the end (for a walk that ends at rest both feet are down).
"""
from __future__ import annotations

from dataclasses import dataclass

from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from .plot_style import (FONT_PT, SUBPHASE_COLOURS, SUBPHASE_LABELS, axes_rows, drawn_note, mark_breaks, new_figure,
                         part_spans, style_axes)

LEGS = ("right", "left")
SWING_KINDS = ("swing1", "swing2", "swing3")
_ROW_Y = {"right": 1.0, "left": 0.0}      # row centres (the right leg on top)
_ZOOM_ROW_Y = {"right": 1.6, "left": 0.0}  # more room between the rows for the dimension lines
_BAR_H = 0.56
_DS_SHADE = {"color": "#bbbbbb", "alpha": 0.35, "lw": 0}
_EVENT_STYLE = {"heel_strike": {"marker": "v", "color": "#000000", "label": "heel strike"},
                "toe_off": {"marker": "^", "color": "#ffffff", "label": "toe-off"}}


@dataclass(frozen=True)
class GaitBar:
    """One bar of the gait diagram: ``leg`` in ``kind`` (stance, swing1, swing2, swing3) from
    ``t0`` to ``t1`` (walk time, s); ``step`` is the step in which the bar starts."""
    leg: str
    kind: str
    t0: float
    t1: float
    step: int


def other_leg(leg: str) -> str:
    return "left" if leg == "right" else "right"


def walk_end(run) -> float:
    """Walk time of the last heel strike (s): where the walk and every bar end."""
    steps = run.steps
    return steps[-1]["t_start_s"] + steps[-1]["t_step_s"] if steps else 0.0


def gait_bars(run) -> list[GaitBar]:
    """Every stance and swing bar of ``run`` (a :class:`~klaw_ocp.result_files.run_data.RunData`), in time
    order of their start. See the module docstring for the rules."""
    steps, end = run.steps, walk_end(run)
    bars: list[GaitBar] = []
    if not steps:
        return bars
    first = steps[0]
    # the hind leg of step 0 is down from t = 0 (nothing before) until its toe-off
    bars.append(GaitBar(other_leg(first["stance_leg"]), "stance", first["t_start_s"],
                        first["t_start_s"] + first["t_ds_s"], 0))
    for k, step in enumerate(steps):
        t0, hind = step["t_start_s"], other_leg(step["stance_leg"])
        nxt = steps[k + 1] if k + 1 < len(steps) else None
        toe_off_next = nxt["t_start_s"] + nxt["t_ds_s"] if nxt else end
        bars.append(GaitBar(step["stance_leg"], "stance", t0, min(toe_off_next, end), k))
        toe_off = t0 + step["t_ds_s"]
        ends = (toe_off + step["t_swing1_end_s"], toe_off + step["t_swing2_end_s"], t0 + step["t_step_s"])
        start = toe_off
        for kind, stop in zip(SWING_KINDS, ends):
            bars.append(GaitBar(hind, kind, start, stop, k))
            start = stop
    bars.sort(key=lambda b: (b.t0, LEGS.index(b.leg)))
    return bars


def gait_events(run) -> list[tuple[str, str, float]]:
    """(leg, "heel_strike" | "toe_off", t) of every event of the walk. A walk that starts from
    rest has no heel strike at its start."""
    events = []
    for k, step in enumerate(run.steps):
        t0, hind = step["t_start_s"], other_leg(step["stance_leg"])
        if k > 0 or not run.summary.get("start_from_rest", False):
            events.append((step["stance_leg"], "heel_strike", t0))
        events.append((hind, "toe_off", t0 + step["t_ds_s"]))
    if run.steps:
        events.append((other_leg(run.steps[-1]["stance_leg"]), "heel_strike", walk_end(run)))
    return events


def double_supports(run) -> list[tuple[float, float]]:
    """(t0, t1) of every double support: from a step's heel strike to the hind leg's toe-off."""
    return [(s["t_start_s"], s["t_start_s"] + s["t_ds_s"]) for s in run.steps]


def representative_step(run) -> int:
    """The step whose timings the diagram annotates: a middle step (not the start or the closing
    step when there are more than two)."""
    n = len(run.steps)
    return min(max(n // 2, 0), max(n - 2, 0)) if n > 2 else 0


# -- drawing ---------------------------------------------------------------------------------
def draw_gait_bars(ax, run, bars: list[GaitBar] | None = None, markers: bool = True,
                   rows: dict | None = None) -> None:
    """The bars, double-support shading and event markers of ``run`` on ``ax`` (``rows``: leg ->
    row centre, default 1 right, 0 left); one ``broken_barh`` per leg and kind."""
    bars = gait_bars(run) if bars is None else bars
    rows = _ROW_Y if rows is None else rows
    spans = [(t0, t1 - t0) for t0, t1 in double_supports(run)]
    if spans:   # one collection over the axis' full height (not one patch per double support)
        ax.broken_barh(spans, (0, 1), transform=ax.get_xaxis_transform(), facecolors=_DS_SHADE["color"],
                       alpha=_DS_SHADE["alpha"], lw=0, zorder=0)
    for leg in LEGS:
        for kind in ("stance",) + SWING_KINDS:
            spans = [(b.t0, b.t1 - b.t0) for b in bars if b.leg == leg and b.kind == kind]
            if spans:
                ax.broken_barh(spans, (rows[leg] - _BAR_H / 2, _BAR_H), facecolors=SUBPHASE_COLOURS[kind],
                               edgecolor="white", linewidth=0.4, zorder=2)
    if markers:
        for kind, style in _EVENT_STYLE.items():
            pts = [(t, rows[leg] + _BAR_H / 2 + 0.09) for leg, k, t in gait_events(run) if k == kind]
            if pts:
                ax.plot(*zip(*pts), ls="none", marker=style["marker"], ms=5, mfc=style["color"],
                        mec="#000000", mew=0.7, zorder=4)
    ax.set_yticks([rows[leg] for leg in LEGS], [f"{leg} leg" for leg in LEGS])
    ax.set_ylim(min(rows.values()) - 0.55, max(rows.values()) + 0.62)
    ax.grid(False)


def _legend_handles() -> list:
    handles = [Patch(facecolor=SUBPHASE_COLOURS[k], label=SUBPHASE_LABELS[k]) for k in ("stance",) + SWING_KINDS]
    handles.append(Patch(facecolor=_DS_SHADE["color"], alpha=_DS_SHADE["alpha"], label="double support"))
    handles += [Line2D([], [], ls="none", marker=s["marker"], mfc=s["color"], mec="#000000", ms=6, label=s["label"])
                for s in _EVENT_STYLE.values()]
    return handles


def _dimension(ax, t0, t1, y, text, above=True) -> None:
    """A dimension line ``|<-- text -->|`` from t0 to t1 at height y, the text above or below."""
    ax.annotate("", xy=(t0, y), xytext=(t1, y),
                arrowprops={"arrowstyle": "<->", "lw": 0.9, "color": "#000000", "shrinkA": 0, "shrinkB": 0})
    ax.vlines([t0, t1], y - 0.08, y + 0.08, colors="#000000", lw=0.8)
    ax.annotate(text, xy=(0.5 * (t0 + t1), y), xytext=(0, 3 if above else -3), textcoords="offset points",
                ha="center", va="bottom" if above else "top", fontsize=FONT_PT + 1)


def _annotate_step(ax, run, k: int) -> list[str]:
    """Dimension lines of step k on the zoomed axis; returns the lines of the value box."""
    steps, step, rows = run.steps, run.steps[k], _ZOOM_ROW_Y
    t0, stance_leg = step["t_start_s"], step["stance_leg"]
    hind = other_leg(stance_leg)
    t_toe, t_hs = t0 + step["t_ds_s"], t0 + step["t_step_s"]
    nxt = steps[k + 1] if k + 1 < len(steps) else None
    top, bottom = max(rows.values()), min(rows.values())
    outer = {leg: (rows[leg] + 0.6 if rows[leg] == top else rows[leg] - 0.5) for leg in LEGS}
    mid = 0.5 * (top + bottom)
    _dimension(ax, t0, t_hs, mid + 0.2, "t_step", above=True)
    _dimension(ax, t0, t_toe, mid - 0.2, "t_ds", above=False)
    _dimension(ax, t_toe, t_hs, outer[hind], "t_swing", above=outer[hind] > mid)
    lines = [f"step {k}: {stance_leg} stance", f"t_step   = {step['t_step_s']:.3f} s",
             f"t_ds     = {step['t_ds_s']:.3f} s", f"t_stance = {step['t_stance_s']:.3f} s",
             f"t_swing  = {step['t_swing_s']:.3f} s"]
    if nxt is not None:
        t_stance_bar = nxt["t_start_s"] + nxt["t_ds_s"] - t0
        _dimension(ax, t0, t0 + t_stance_bar, outer[stance_leg], "t_stance", above=outer[stance_leg] > mid)
        if abs(t_stance_bar - step["t_stance_s"]) > 5e-4:
            lines += [f"stance bar: t_step({k})", f"  + t_ds({k + 1}) = {t_stance_bar:.3f} s"]
    lines += ["swing1 | swing2 | swing3", "end at " + " | ".join(
        [_pct(step, "t_swing1_end_s"), _pct(step, "t_swing2_end_s"), "100 %"]), "of t_swing after toe-off"]
    return lines


def _pct(step, key) -> str:
    return f"{100 * step[key] / step['t_swing_s']:.0f} %" if step["t_swing_s"] > 0 else "-"


def _rest_notes(first, last, run) -> None:
    """The notes of a walk from or to rest over the first and the last part of the whole walk."""
    end = walk_end(run)
    if run.summary.get("start_from_rest"):
        first.annotate("start from rest: both feet down", xy=(0, 1.0), xycoords=("data", "axes fraction"),
                       xytext=(0, 3), textcoords="offset points", ha="left", va="bottom", fontsize=FONT_PT)
    if run.summary.get("end_at_rest"):
        last.annotate("end at rest: both feet down", xy=(end, 1.0), xycoords=("data", "axes fraction"),
                      xytext=(0, 3), textcoords="offset points", ha="right", va="bottom", fontsize=FONT_PT)


def gait_diagram_figure(run):
    """The gait diagram of ``run`` (figure 3 of the paper) as a :class:`matplotlib.figure.Figure`;
    a long walk's whole-walk row in two parts (plot_style.drawn_steps), the title saying which."""
    if not run.steps:
        fig = new_figure(8.0, 3.0)
        ax = fig.add_subplot()
        ax.text(0.5, 0.5, f"{run.name}: no completed step", ha="center", va="center", fontsize=FONT_PT + 2)
        ax.set_axis_off()
        return fig
    # fixed layout, inches: rows of labels on the left, the legend and the value box on the right
    note, spans = drawn_note(len(run.steps)), part_spans(run)
    extra = 0.2 if note else 0.0             # the title's second line
    fig = new_figure(10.5, 5.5 + extra, layout=None)
    rows = axes_rows(fig, [1.6, 2.1], 0.85, 2.3, 0.58 + extra, 0.78, spans, split=[0], sharex=False)
    wholes, zoom = rows[0], rows[1][0]
    bars, end = gait_bars(run), walk_end(run)
    for ax, rows_y in [(whole, _ROW_Y) for whole in wholes] + [(zoom, _ZOOM_ROW_Y)]:
        style_axes(ax)
        draw_gait_bars(ax, run, bars, rows=rows_y)
        if ax is wholes[0] or ax is zoom:
            ax.set_xlabel("t (s)")
    if len(wholes) == 1:
        wholes[0].set_xlim(-0.012 * end, 1.012 * end)    # room for the markers at 0 and at the end
    else:                                                 # ... and at the ends of each part
        margin = 0.012 * sum(t1 - t0 for t0, t1 in spans)
        for whole, (t0, t1) in zip(wholes, spans):
            whole.set_xlim(t0 - margin, t1 + margin)
    for whole in wholes:
        whole.vlines([s["t_start_s"] for s in run.steps] + [end], 0, 1, transform=whole.get_xaxis_transform(),
                     colors="#555555", lw=0.5, zorder=1)
    mark_breaks(wholes)
    _rest_notes(wholes[0], wholes[-1], run)
    wholes[0].set_title(f"Gait diagram: {run.label}, {len(run.steps)} steps, {end:.2f} s"
                        + (f"\n{note}" if note else ""), loc="left", pad=15)
    k = representative_step(run)
    step = run.steps[k]
    t0 = step["t_start_s"]
    t1 = run.steps[k + 1]["t_start_s"] + run.steps[k + 1]["t_ds_s"] if k + 1 < len(run.steps) else end
    margin = 0.3 * step["t_step_s"]
    zoom.set_xlim(max(0.0, t0 - margin), min(end, t1 + margin))
    zoom.set_ylim(-1.0, 2.65)
    zoom.set_title(f"Step {k} as in the paper's figure 3 (eq. 2: t_step = t_stance − t_ds = t_swing + t_ds)",
                   loc="left")
    lines = _annotate_step(zoom, run, k)
    wholes[-1].legend(handles=_legend_handles(), loc="upper left", bbox_to_anchor=(1.03, 1.0), fontsize=FONT_PT,
                      frameon=False, borderaxespad=0.0)
    zoom.text(1.03, 0.5, "\n".join(lines), transform=zoom.transAxes, ha="left", va="center",
              family="monospace", fontsize=FONT_PT,
              bbox={"boxstyle": "round,pad=0.4", "fc": "#f7f7f7", "ec": "#999999"})
    return fig
