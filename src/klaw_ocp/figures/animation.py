"""``walk.gif``: the body walking, a stick figure drawn from a run's ``angles.csv`` (docs/gif.md).

Three panels, drawn at :data:`GIF_FPS` frames per second of walk time (the GIF's own rate: the
angles' frames, at ``output.fps``, are interpolated linearly to it) and played back in real time:

- *side* (x forward, y up): the skeleton as in ``body.png`` (:mod:`klaw_ocp.figures.body_plots`: legs
  and arms coloured by side, the far left side fainter, spine, shoulders, head), in a window that
  follows the pelvis, over a ground line with a tick every 0.25 m and a label every metre, and a
  footprint on the ground wherever a foot was planted (from its heel strike on, drawn where the
  foot lay flat);
- *seen from behind* (z to the right, the walker's right, y up): the legs, the pelvis
  (hip to hip), the trunk, shoulders, arms and head, the feet's lines on the ground (each foot
  walks along its own line) and the pelvis centre's plumb line, which weaves between them;
- *from above* (z across, stretched; x forward, up the panel): the footprints along the two
  feet's lines and the pelvis centre's path, the lateral weave, following the walker.

A title names the walk and counts the time. Like every plot it reads results only (a
:class:`~klaw_ocp.result_files.run_data.RunData`, from a walk in memory or a finished results folder), so
``klaw-ocp plot DIR --animation`` redraws it. Every artist is made once; a frame only moves them
(``set_data``) and the figure is drawn once per frame on its Agg canvas, small (8 x 4 in at
80 dpi), with no constrained layout and no axis machinery in the moving panels; it draws only
what its views show, so a frame costs the same at any length of walk. Each frame is mapped to one
shared palette (taken from the first frame, no dithering: flat colours compress well and no frame
flickers) and written to the file as soon as it is drawn (:mod:`.gif_file`, no ffmpeg): the
memory does not grow with the walk. The file is written atomically (a temporary file in the same
folder, then a rename).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Rectangle
from matplotlib.transforms import blended_transform_factory

from ..body_motion.skeleton import SIDES, Dimensions
from ..result_files.atomic import atomic_path
from ..result_files.registry import RUN_FILES
from .body_plots import CHAINS, chain_points, has_angles, skeleton_at
from .gait_diagram import gait_events
from .gif_file import GifStream
from .gif_pixels import FONT, Blitter, LiveText, MovingLabels, StaticText
from .plot_style import LEG_COLOURS, add_axes_in, new_figure
from .strobe import GROUND_COLOUR, TRUNK_COLOUR

GIF_FILE = RUN_FILES["animation"].name
#: frames per second of walk.gif; GIF stores frame durations in 1/100 s, so 1000 / GIF_FPS is a
#: whole number of 10 ms (80 ms) and the GIF plays back in real time
GIF_FPS = 12.5
GIF_DPI = 80
FIGURE_IN = (8.0, 4.0)
SIDE_WINDOW_M = 2.7              # the side view's width of walk
SIDE_LEAD = 0.45                 # the pelvis at this fraction of the side window from its left edge
FRONT_HALF_WIDTH_M = 0.42        # the front view spans z = ± this
PLAN_HALF_WIDTH_M = 0.16         # the view from above spans z = ± this (stretched)
PLAN_BEHIND_M, PLAN_AHEAD_M = 1.55, 0.75   # ... and x from the pelvis back and forward
GROUND_LOW_M = -0.17             # room below the ground for the tick labels
FOOTPRINT = {"lw": 4.0, "alpha": 0.55}
POSE_CHUNK = 256                 # frames whose poses are computed at once (_Poses)

_FAINT_SIDE = {"left": 0.55, "right": 1.0}       # side view: the left side is the far one


@dataclass(frozen=True)
class Footprint:
    """Where a foot was planted: ``side``, from walk time ``t`` (its heel strike, or the walk's
    start for a foot standing there), ``heel`` and ``toe`` (3,) where the foot lay flat (m)."""
    side: str
    t: float
    heel: np.ndarray
    toe: np.ndarray


def gif_times(run, fps: float = GIF_FPS) -> np.ndarray:
    """Walk time of every GIF frame: k / fps (k = 0, 1, ...) from the walk's first heel strike to
    its end, whatever the frame rate of angles.csv (a frame after its last one holds that pose)."""
    start = float(run.steps[0]["t_start_s"])
    return start + np.arange(int(np.floor(run.duration * fps + 1e-9)) + 1) / fps


def _events(run) -> list[tuple[float, str, str]]:
    """(time, side, event) of every foot event: the summary's (as events.csv) and the walk's last
    heel strike, which closes it and is not among them; for results written before the events
    were, the heel strikes and toe-offs of :func:`gait_events`."""
    strikes = sorted((t, leg, kind) for leg, kind, t in gait_events(run))
    events = run.summary.get("events")
    if not events:
        return strikes
    found = sorted((float(e["time"]), e["side"], e["event"]) for e in events)
    if strikes and strikes[-1][2] == "heel_strike" and not any(
            abs(t - strikes[-1][0]) < 1e-9 and side == strikes[-1][1] and kind == "heel_strike"
            for t, side, kind in found):
        found.append(strikes[-1])
    return found


def footprints(run) -> list[Footprint]:
    """Every planting of a foot, in time order: from each heel strike (and the walk's start for a
    foot already standing there, one whose first event is not a heel strike), the foot laid flat
    on the ground where it stands at its next foot flat (the heel strike itself when none follows
    before the foot lifts, as at the heel strike that closes the walk; the start for a standing
    foot): :func:`_laid_flat`."""
    t0 = float(run.angles["time"][0])
    plants = []                      # (side, appears, flat)
    for _, side in SIDES:
        mine = [(t, kind) for t, leg, kind in _events(run) if leg == side]
        if mine and mine[0][1] != "heel_strike":          # standing there when the walk starts
            plants.append((side, t0, t0))
        for k, (t, kind) in enumerate(mine):
            if kind != "heel_strike":
                continue
            following = mine[k + 1:k + 2]
            plants.append((side, t, following[0][0] if following and following[0][1] == "foot_flat" else t))
    if not plants:
        return []
    plants.sort(key=lambda p: p[1])
    skeleton = skeleton_at(run, [flat for _, _, flat in plants])
    d = Dimensions.of(run.body_model())
    length = d.heel_back + d.metatarsal_forward + d.toe_length     # heel to toe tip, flat
    prints = []
    for i, (side, t, _) in enumerate(plants):
        heel, toe = _laid_flat(skeleton.landmarks[f"{side[0]}_heel"][i], skeleton.end_sites[f"{side[0]}_toes"][i], length)
        prints.append(Footprint(side, float(t), heel, toe))
    return prints


def _laid_flat(heel: np.ndarray, toe: np.ndarray, length: float) -> tuple[np.ndarray, np.ndarray]:
    """The foot from ``heel`` to ``toe`` (tip) laid flat on the ground (y = 0), ``length`` long
    (its toes straight: a walking start's hind foot stands on its bent toes), in its direction
    seen from above, about its lower end (a flat foot stays where it is; a foot on its toes keeps
    its toes, one on its heel its heel)."""
    along = np.array([toe[0] - heel[0], 0.0, toe[2] - heel[2]])
    along *= length / max(float(np.linalg.norm(along)), 1e-12)
    if heel[1] <= toe[1]:
        heel = np.array([heel[0], 0.0, heel[2]])
        return heel, heel + along
    toe = np.array([toe[0], 0.0, toe[2]])
    return toe - along, toe


# -- the figure -------------------------------------------------------------------------------------
class _Poses:
    """The stick figure at the GIF's frames: the points of CHAINS (name -> (k, 3)) and the head's
    centre (3,), computed :data:`POSE_CHUNK` frames at a time as the frames come, so that the
    memory does not grow with the walk (the skeleton of all 7000 frames of a 1000-step walk at
    once: 75 MB)."""

    def __init__(self, run, times: np.ndarray):
        self.run, self.times = run, times
        neck, top = self._load(0)
        #: the head's radius, from the first frames (the head is rigid)
        self.radius = 0.55 * float(np.median(np.linalg.norm(top - neck, axis=1)))

    def _load(self, chunk: int) -> tuple[np.ndarray, np.ndarray]:
        skeleton = skeleton_at(self.run, self.times[chunk * POSE_CHUNK:(chunk + 1) * POSE_CHUNK])
        self.chains = chain_points(skeleton)
        neck, top = skeleton.position("C1"), skeleton.end_sites["C1"]
        self.head = neck + 0.45 * (top - neck)
        self.chunk = chunk
        return neck, top

    def __getitem__(self, i: int) -> tuple[dict, np.ndarray]:
        if self.chunk != i // POSE_CHUNK:
            self._load(i // POSE_CHUNK)
        j = i - self.chunk * POSE_CHUNK
        return {name: points[j] for name, points in self.chains.items()}, self.head[j]


class _Panel:
    """One view: an axes without axis machinery (no ticks, no spines: a frame draws fast), placed
    in inches with the limits at one scale in both directions, and the stick figure in the view's
    two world coordinates ``(u, v)`` (0, 1, 2: x, y, z): one line per colour (the chains
    ``names`` of that colour, NaN between them) and the head."""

    def __init__(self, fig, rect_in, u: int, v: int, alpha: dict, names, limits):
        self.ax = add_axes_in(fig, *rect_in)
        self.ax.set_axis_off()
        self.ax.set_autoscale_on(False)
        self.ax.set_xlim(*limits[0])
        self.ax.set_ylim(*limits[1])
        self.u, self.v = u, v
        self.names, self.lines = {}, {}
        for key in ("left", "trunk", "right"):
            self.names[key] = [name for name in names if CHAINS[name][0] == key]
            colour = TRUNK_COLOUR if key == "trunk" else LEG_COLOURS[key]
            zorder = {"left": 3, "trunk": 4, "right": 5}[key] if alpha is _FAINT_SIDE else 4
            self.lines[key] = self.ax.add_line(Line2D([], [], color=colour, lw=2.2, alpha=alpha.get(key, 1.0),
                                                      solid_capstyle="round", solid_joinstyle="round",
                                                      zorder=zorder))
        self.head = self.ax.add_patch(Circle((0, 0), 0.1, facecolor="white", edgecolor=TRUNK_COLOUR, lw=1.4,
                                             zorder=4))

    def pose(self, chains: dict, head: np.ndarray) -> None:
        """The figure at one frame: ``chains`` name -> (k, 3) points, ``head`` (3,)."""
        for key, line in self.lines.items():
            p = np.concatenate([part for name in self.names[key] for part in (chains[name], _GAP)][:-1])
            line.set_data(p[:, self.u], p[:, self.v])
        self.head.center = (head[self.u], head[self.v])


_GAP = np.full((1, 3), np.nan)


def _ticks(u0: float, u1: float, minor: float, major: float) -> tuple[list, np.ndarray]:
    """The ground's ticks from u0 to u1, one every ``minor``, longer every ``major``: their
    segments, and the positions of the long ones (for their labels)."""
    ticks = np.arange(np.ceil(u0 / minor - 1e-9), np.floor(u1 / minor + 1e-9) + 1) * minor
    is_major = np.isclose(np.remainder(ticks + major / 2, major) - major / 2, 0.0, atol=1e-9)
    length = np.where(is_major, 0.07, 0.035)
    return [[(u, 0.0), (u, -h)] for u, h in zip(ticks, length)], np.round(ticks[is_major], 9)


def _ground(ax, u0: float, u1: float, minor: float, major: float, ticks: bool = True):
    """A ground line from u0 to u1 with a tick every ``minor``, longer every ``major`` (``ticks``:
    else none yet); returns the ticks' collection and the positions of the long ticks."""
    ax.fill_between([u0, u1], -0.045, 0.0, color="#e9e3d9", lw=0, zorder=0)
    ax.plot([u0, u1], [0.0, 0.0], color=GROUND_COLOUR, lw=1.2, zorder=1)
    segments, majors = _ticks(u0, u1, minor, major) if ticks else ([], np.array([]))
    return ax.add_collection(LineCollection(segments, colors=GROUND_COLOUR, lw=0.9, zorder=1)), majors


def _footprint_lines(ax):
    return {s: ax.add_collection(LineCollection([], colors=LEG_COLOURS[s], zorder=2, capstyle="butt",
                                                lw=FOOTPRINT["lw"], alpha=FOOTPRINT["alpha"])) for _, s in SIDES}


def animation_figure(run, fps: float = GIF_FPS) -> "Animation":
    """walk.gif's figure, every artist made once, and the function that moves them to a frame
    (:class:`Animation`). Nothing is drawn here but the static texts. What a frame draws is only
    what its views show (the ground's ticks, the footprints, the path near the walker), so that a
    frame costs the same at any length of walk."""
    times = gif_times(run, fps)
    poses = _Poses(run, times)
    a = run.angles                   # the pelvis at every frame (as the skeleton has it): 24 bytes a frame
    root = np.column_stack([np.interp(np.clip(times, a["time"][0], a["time"][-1]), a["time"], a[f"root_{axis}"])
                            for axis in "xyz"])
    prints = footprints(run)
    y_range = (GROUND_LOW_M, float(run.body["height"]) + 0.12)

    # layout, inches: the side and front views at one scale (per_m), the view from above beside them
    width, fig_h = FIGURE_IN
    fig = new_figure(width, fig_h, layout=None)
    fig.set_dpi(GIF_DPI)
    fig.patch.set_facecolor("white")
    top_in, bottom_in, gap, left = 0.42, 0.08, 0.22, 0.12
    panel_h = fig_h - top_in - bottom_in
    per_m = panel_h / (y_range[1] - y_range[0])
    side_w, front_w = SIDE_WINDOW_M * per_m, 2 * FRONT_HALF_WIDTH_M * per_m
    front_left = left + side_w + gap
    plan_left = front_left + front_w + gap
    plan_w, plan_bottom = width - plan_left - 0.1, 0.24
    static = StaticText()
    side = _Panel(fig, (left, bottom_in, side_w, panel_h), 0, 1, _FAINT_SIDE, [n for n in CHAINS if n != "pelvis"],
                  ((0.0, SIDE_WINDOW_M), y_range))
    front = _Panel(fig, (front_left, bottom_in, front_w, panel_h), 2, 1, {}, list(CHAINS),
                   ((-FRONT_HALF_WIDTH_M, FRONT_HALF_WIDTH_M), y_range))
    plan = add_axes_in(fig, plan_left, plan_bottom, plan_w, panel_h - (plan_bottom - bottom_in))
    for panel in (side, front):
        panel.head.set_radius(poses.radius)
    static.add(side.ax.transAxes, (0.0, 1.0), "side", va="bottom")
    static.add(front.ax.transAxes, (0.0, 1.0), "seen from behind", va="bottom")

    # side: the ground along the whole walk, its ticks only about the window (set at each frame);
    # the metre labels move with it (shown only in the window)
    x_all = np.concatenate([root[:, 0]] + [[f.heel[0], f.toe[0]] for f in prints])
    ground_x = (float(x_all.min()) - SIDE_WINDOW_M, float(x_all.max()) + SIDE_WINDOW_M)
    side_ticks, _ = _ground(side.ax, *ground_x, 0.25, 1.0, ticks=False)
    metres = _ticks(*ground_x, 0.25, 1.0)[1]
    labels = MovingLabels(fig, side.ax, metres, [f"{u:.0f} m" for u in metres], -0.085, {"color": "#555555"})
    side_prints = _footprint_lines(side.ax)

    # front: ground, the feet's lines (where the footprints lie across), the pelvis centre's plumb line
    for u in _ground(front.ax, -FRONT_HALF_WIDTH_M, FRONT_HALF_WIDTH_M, 0.1, 0.2)[1]:
        if abs(u) < 0.3:
            static.add(front.ax.transData, (u, -0.085), f"{100 * u:.0f}" + (" cm" if u > 0 else ""),
                       fontsize=FONT - 1, ha="center", va="top", color="#555555")
    foot_lines = {}
    for _, s in SIDES:
        z = np.array([[f.heel[2], f.toe[2]] for f in prints if f.side == s]).ravel()
        if z.size:
            foot_lines[s] = (float(z.min()), float(z.max()))
            front.ax.plot(foot_lines[s], [0.004, 0.004], color=LEG_COLOURS[s], lw=FOOTPRINT["lw"],
                          alpha=FOOTPRINT["alpha"], solid_capstyle="butt", zorder=2)
    plumb = front.ax.add_line(Line2D([], [], color="#333333", lw=0.8, ls=(0, (2, 2)), zorder=6))
    centre = front.ax.add_line(Line2D([], [], color="#000000", marker="o", ms=3.5, lw=0, zorder=7))

    # from above: the feet's lines, the footprints and the pelvis centre's path, z stretched
    plan.set_axis_off()
    plan.set_autoscale_on(False)
    plan.set_xlim(-PLAN_HALF_WIDTH_M, PLAN_HALF_WIDTH_M)
    plan.add_patch(Rectangle((0, 0), 1, 1, transform=plan.transAxes, facecolor="#f4f1ec", edgecolor="#bbbbbb",
                             lw=0.8, zorder=0))
    stretch = (plan_w / (2 * PLAN_HALF_WIDTH_M)) / per_m
    static.add(plan.transAxes, (0.0, 1.0), f"from above (z ×{stretch:.0f})", va="bottom")
    below = blended_transform_factory(plan.transData, plan.transAxes)
    for z, text in ((-0.1, "-10"), (0.0, "0"), (0.1, "10 cm")):
        plan.plot([z, z], [0.0, -0.012], transform=below, color="#777777", lw=0.8, clip_on=False)
        static.add(below, (z, -0.02), text, fontsize=FONT - 1, ha="center", va="top", color="#555555")
    for s, (z0, z1) in foot_lines.items():
        plan.axvline(0.5 * (z0 + z1), color=LEG_COLOURS[s], lw=0.6, ls=(0, (4, 3)), alpha=0.8, zorder=1)
    plan_prints = _footprint_lines(plan)
    path = plan.add_line(Line2D([], [], color="#000000", lw=1.1, zorder=3))
    here = plan.add_line(Line2D([], [], color="#000000", marker="o", ms=3.5, lw=0, zorder=4))

    # the title (the only text that changes); the legend in the side view's top right corner, where
    # the walker (at SIDE_LEAD of the window) never reaches
    title = LiveText(fig.text(left / width, 1 - 0.1 / fig_h, f"{run.name}   t =", fontsize=FONT + 2, va="top",
                              ha="left"), "")
    for k, (text, s) in enumerate((("right leg and arm", "right"), ("left leg and arm (far side)", "left"))):
        static.add(side.ax.transAxes, (1.0, 0.99 - 0.055 * k), text, va="top", ha="right", color=LEG_COLOURS[s],
                   fontweight="bold")
    static.freeze(fig)
    # what a frame moves: the whole side view (its window follows the walker), the front view's
    # body and plumb line, the view from above's footprints and path (it scrolls), the title
    moving = ([*side.ax.collections, *side.ax.lines, *side.ax.patches]
              + [*front.lines.values(), front.head, plumb, centre]
              + [*plan_prints.values(), path, here, title])

    mine = {s: [f for f in prints if f.side == s] for _, s in SIDES}
    side_segments = {s: [((f.heel[0], 0.004), (f.toe[0], 0.004)) for f in mine[s]] for s in mine}
    plan_segments = {s: [((f.heel[2], f.heel[0]), (f.toe[2], f.toe[0])) for f in mine[s]] for s in mine}
    # a foot planted after the last frame (the heel strike that closes the walk, up to 1 / fps
    # later) shows on the last one
    planted = {s: np.minimum([f.t for f in mine[s]], times[-1]) for s in mine}
    # how far forward the walk had reached by each footprint / frame: those before the first that
    # reach a view's back edge lie wholly behind it and are not drawn
    reach = {s: np.maximum.accumulate([max(f.heel[0], f.toe[0]) for f in mine[s]] or [0.0]) for s in mine}
    path_reach = np.maximum.accumulate(root[:, 0])
    shown = {}

    def frame(i: int) -> None:
        t, x = times[i], root[i, 0]
        x0 = x - SIDE_LEAD * SIDE_WINDOW_M
        side.ax.set_xlim(x0, x0 + SIDE_WINDOW_M)
        first_tick = int(np.floor(x0 / 0.25)) - 1
        if shown.get("ticks") != first_tick:
            shown["ticks"] = first_tick
            side_ticks.set_segments(_ticks(0.25 * first_tick, 0.25 * first_tick + SIDE_WINDOW_M + 0.5, 0.25, 1.0)[0])
        labels.place()
        chains, head = poses[i]
        side.pose(chains, head)
        front.pose(chains, head)
        plumb.set_data([root[i, 2], root[i, 2]], [0.0, root[i, 1]])
        centre.set_data([root[i, 2]], [root[i, 1]])
        behind = min(x0, x - PLAN_BEHIND_M) - 0.5
        for s in mine:
            window = (int(np.searchsorted(reach[s], behind)), int(np.searchsorted(planted[s], t, side="right")))
            if shown.get(s) != window:
                shown[s] = window
                side_prints[s].set_segments(side_segments[s][slice(*window)])
                plan_prints[s].set_segments(plan_segments[s][slice(*window)])
        plan.set_ylim(x - PLAN_BEHIND_M, x + PLAN_AHEAD_M)
        start = max(0, int(np.searchsorted(path_reach, x - PLAN_BEHIND_M - 0.1)) - 1)
        path.set_data(root[start: i + 1, 2], root[start: i + 1, 0])
        here.set_data([root[i, 2]], [x])
        title.set_text(f" {t:5.2f} s")           # after f"{run.name}   t ="

    return Animation(fig, frame, len(times), Blitter(fig, moving, [static]), [labels], poses)


@dataclass
class Animation:
    """walk.gif before it is drawn: ``frame(i)`` moves ``fig`` to frame ``i`` of ``frames``;
    :meth:`pixels` draws it (:class:`~.gif_pixels.Blitter`: the still parts were drawn once)."""
    fig: object
    frame: object
    frames: int
    blitter: Blitter
    overlays: list       # drawn over each frame's pixels (blend(rgb)): the side view's moving labels
    poses: object = None     # the stick figure's points, a chunk of frames at a time (_Poses)

    def pixels(self) -> np.ndarray:
        """The frame as it stands: (h, w, 4) uint8 RGBA (opaque)."""
        return self.blitter.pixels(self.overlays)


def write_animation(run, path, fps: float = GIF_FPS) -> Path | None:
    """Render ``run``'s walk.gif to ``path`` atomically (a temporary file in the same folder, then
    a rename; the user's normal file mode), each frame written to the file as it is drawn
    (:class:`~.gif_file.GifStream`); None, writing nothing, if it has no body to animate."""
    if not has_angles(run):
        return None
    path = Path(path)
    animation = animation_figure(run, fps)
    with atomic_path(path, suffix=path.suffix or ".gif") as tmp, open(tmp, "wb") as handle:
        gif = GifStream(handle, fps)
        for i in range(animation.frames):
            animation.frame(i)
            gif.add_frame(animation.pixels())
        gif.finish()
    return path
