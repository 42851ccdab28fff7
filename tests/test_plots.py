"""The plots of a run (klaw_ocp.figures.plots, gait_diagram, strobe, body_plots): they render readable PNGs,
the gait diagram's bars are the summary's state-phase timings (§3, eq. 2, figure 3), the strobe is
the dynamic model's geometry (figure 2, figure 8), and plotting never imports a solver."""
import io
import math
import subprocess
import sys
from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
import pytest

from klaw_ocp.config import load_config
from klaw_ocp.errors import ConfigError
from klaw_ocp.result_files import RunData, write_walk
from klaw_ocp.figures.gait_diagram import gait_bars, gait_events, representative_step, walk_end
from klaw_ocp.figures.plot_style import DPI, LEG_COLOURS, encode_png, png_bytes
from klaw_ocp.figures.plots import boundaries, render_plots, subphase_lines, swing2_recoveries
from klaw_ocp.figures.registry import PLOTS
from klaw_ocp.result_files.registry import load
from klaw_ocp.figures.strobe import draw_posture, draw_strobe, legs_figure, pose_points, sample_at, strobe_rows
from klaw_ocp.gait import stance_leg
from klaw_ocp.walk import simulate_walk

ROOT = Path(__file__).resolve().parents[1]
TOL = 1e-12


@pytest.fixture(scope="module")
def natural_walk():
    return simulate_walk(ROOT / "configs" / "natural_walk.yaml")


@pytest.fixture(scope="module")
def start_stop_walk():
    return simulate_walk(ROOT / "configs" / "start_stop_5kmh.yaml")


@pytest.fixture(scope="module")
def natural(natural_walk):
    return RunData.from_walk(natural_walk)


@pytest.fixture(scope="module")
def start_stop(start_stop_walk):
    return RunData.from_walk(start_stop_walk)


@pytest.fixture(scope="module")
def accelerate_plan():
    """The accelerate schedule's timings as a run (the plan, nothing solved): the bars only read
    the step timings, which change from step to step here."""
    config = load_config(ROOT / "configs" / "accelerate.yaml")
    steps = [dict(p.as_dict(), stance_leg=stance_leg(p.index)) for p in config.full_plan()]
    return RunData(name="accelerate", summary={"steps": steps, "body": {}, "start_from_rest": False,
                                               "end_at_rest": False}, table={})


@pytest.fixture(scope="module", params=["natural", "start_stop"])
def run(request):
    return request.getfixturevalue(request.param)


def _figure(name: str):
    """The figure function the registry names for plot ``name``."""
    return load(PLOTS[name].figure)


def _decode(png: bytes) -> np.ndarray:
    return mpimg.imread(io.BytesIO(png), format="png")


# -- every plot renders ------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(PLOTS))
def test_every_plot_renders_a_png_of_its_figure_size_that_is_not_blank(run, name):
    assert PLOTS[name].file == f"{name}.png"
    fig = _figure(name)(run)
    width, height = fig.get_size_inches() * DPI
    image = _decode(png_bytes(fig))
    assert abs(image.shape[0] - height) < 1 and abs(image.shape[1] - width) < 1   # Agg truncates
    rgb = np.round(image[..., :3] * 255).astype(np.int32)
    ink = np.any(rgb < 230, axis=-1).mean()
    colours = len(np.unique((rgb[..., 0] << 16) | (rgb[..., 1] << 8) | rgb[..., 2]))
    assert ink > 0.03, f"{name}: only {ink:.1%} of the pixels are not white"
    assert colours > 50, f"{name}: only {colours} distinct colours"


def test_render_plots_gives_the_seven_files_and_rejects_unknown_names(natural):
    files = render_plots(natural)
    assert {n: f for n, (f, _) in files.items()} == {
        "hip_height": "hip_height.png", "gait_diagram": "gait_diagram.png", "torques": "torques.png",
        "states": "states.png", "legs": "legs.png", "joint_angles": "joint_angles.png", "body": "body.png"}
    assert all(data.startswith(b"\x89PNG\r\n\x1a\n") for _, data in files.values())
    assert list(render_plots(natural, ["states"])) == ["states"]
    with pytest.raises(ConfigError, match="plot names: got \\['nope'\\], allowed"):
        render_plots(natural, ["nope"])


def test_a_results_folder_gives_the_same_plots_as_the_walk(start_stop_walk, start_stop, tmp_path):
    write_walk(start_stop_walk, tmp_path)
    from_folder = render_plots(RunData.from_folder(tmp_path))
    from_walk = render_plots(start_stop)
    assert list(from_folder) == list(from_walk)
    for name in from_walk:
        assert _decode(from_folder[name][1]).shape == _decode(from_walk[name][1]).shape, name


def test_a_run_without_steps_renders_a_note_not_an_error(natural):
    empty = RunData(name="nothing", summary={"steps": [], "body": natural.body},
                    table={c: np.array([]) for c in natural.table})
    for name in PLOTS:
        assert _decode(png_bytes(_figure(name)(empty))).shape[0] > 100, name


def test_encode_png_is_lossless():
    pixels = np.random.default_rng(0).integers(0, 256, size=(37, 53, 3), dtype=np.uint8)
    assert np.array_equal(np.round(_decode(encode_png(pixels)) * 255).astype(np.uint8), pixels)


def test_plotting_imports_no_solver():
    code = "import sys, klaw_ocp.figures.plots; print(any(m.startswith('klaw_ocp.solvers') for m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert out.stdout.strip() == "False"


# -- the gait diagram is the state-phase timings -----------------------------------------------
def _expected_bars(run):
    """The bars from the rules of §3 (figure 3), one step at a time."""
    steps, end = run.steps, walk_end(run)
    other = {"right": "left", "left": "right"}
    bars = {("stance", other[steps[0]["stance_leg"]], 0.0, steps[0]["t_ds_s"])}
    for k, s in enumerate(steps):
        t0, hind = s["t_start_s"], other[s["stance_leg"]]
        toe_off = t0 + s["t_ds_s"]
        stance_end = steps[k + 1]["t_start_s"] + steps[k + 1]["t_ds_s"] if k + 1 < len(steps) else end
        bars.add(("stance", s["stance_leg"], t0, stance_end))
        ends = [toe_off + 0.5 * s["t_swing_s"], toe_off + 0.85 * s["t_swing_s"], toe_off + s["t_swing_s"]]
        assert math.isclose(ends[-1], t0 + s["t_step_s"], abs_tol=1e-9)       # eq. 2: t_step = t_swing + t_ds
        starts = [toe_off] + ends[:2]
        for kind, a, b in zip(("swing1", "swing2", "swing3"), starts, ends):
            bars.add((kind, hind, a, b))
    return bars


@pytest.mark.parametrize("which", ["natural", "start_stop", "accelerate_plan"])
def test_gait_bars_are_the_summary_timings(request, which):
    run = request.getfixturevalue(which)
    got = gait_bars(run)
    expected = _expected_bars(run)
    assert len(got) == len(expected)
    for bar in got:
        match = [e for e in expected if e[0] == bar.kind and e[1] == bar.leg
                 and abs(e[2] - bar.t0) < 1e-9 and abs(e[3] - bar.t1) < 1e-9]
        assert match, f"unexpected bar {bar}"
    # each leg's bars tile the walk from 0 to its end, no gap and no overlap; stance and swing alternate
    for leg in ("right", "left"):
        own = sorted((b for b in got if b.leg == leg), key=lambda b: b.t0)
        assert own[0].t0 == 0.0 and abs(own[-1].t1 - walk_end(run)) < TOL
        assert all(abs(a.t1 - b.t0) < 1e-9 for a, b in zip(own, own[1:]))
        kinds = [b.kind for b in own]
        assert all(k == "stance" for k in kinds[::4]) or all(k == "stance" for k in kinds[3::4])


def test_a_leg_stance_lasts_t_step_plus_the_next_double_support(accelerate_plan):
    steps = accelerate_plan.steps
    assert len({round(s["t_step_s"], 6) for s in steps}) > 2          # the timings do change
    stance = {(b.leg, round(b.t0, 9)): b for b in gait_bars(accelerate_plan) if b.kind == "stance"}
    for k in range(len(steps) - 1):
        bar = stance[(steps[k]["stance_leg"], round(steps[k]["t_start_s"], 9))]
        assert bar.t1 - bar.t0 == pytest.approx(steps[k]["t_step_s"] + steps[k + 1]["t_ds_s"], abs=1e-12)


def test_gait_events_mark_heel_strikes_and_toe_offs(natural, start_stop):
    for run, from_rest in ((natural, False), (start_stop, True)):
        events = gait_events(run)
        strikes = [(leg, t) for leg, kind, t in events if kind == "heel_strike"]
        toe_offs = [(leg, t) for leg, kind, t in events if kind == "toe_off"]
        assert len(toe_offs) == len(run.steps)
        assert (("right", 0.0) in strikes) is not from_rest       # standing at t = 0: no heel strike
        assert strikes[-1][1] == pytest.approx(walk_end(run))     # the last heel strike ends the walk
    assert start_stop.summary["end_at_rest"] and start_stop.steps[-1]["step_length_m"] == 0.0
    assert 0 < representative_step(start_stop) < len(start_stop.steps) - 1


# -- the time plots ----------------------------------------------------------------------------
def test_subphase_lines_break_at_every_step_boundary(natural):
    steps_at = np.asarray(natural.table["step"])
    t_of_step = {int(k): (natural.table["t"][steps_at == k].min(), natural.table["t"][steps_at == k].max())
                 for k in np.unique(steps_at)}
    for name, (t, y) in subphase_lines(natural.table, "theta1").items():
        pieces = np.split(t, np.flatnonzero(np.isnan(t)))
        for piece in pieces:
            piece = piece[np.isfinite(piece)]
            if piece.size:
                assert any(lo - TOL <= piece.min() and piece.max() <= hi + TOL for lo, hi in t_of_step.values()), name
    step_lines, sub_lines = boundaries(natural)
    assert len(step_lines) == len(natural.steps) + 1 and len(sub_lines) == 3 * len(natural.steps)


def test_a_swing2_recovery_is_found_from_the_summary(natural):
    assert swing2_recoveries(natural) == []
    steps = [dict(s) for s in natural.steps]
    steps[1] = dict(steps[1], subphases=[dict(sp, fallbacks=["recovery-loop"]) if sp["name"] == "swing2" else sp
                                         for sp in steps[1]["subphases"]])
    found = swing2_recoveries(RunData(name="x", summary=dict(natural.summary, steps=steps), table=natural.table))
    (k, t0, t1, note), = found
    s = steps[1]
    assert k == 1 and "recovery-loop" in note
    assert t0 == pytest.approx(s["t_start_s"] + s["t_ds_s"] + s["t_swing1_end_s"])
    assert t1 == pytest.approx(s["t_start_s"] + s["t_ds_s"] + s["t_swing2_end_s"])


# -- the strobe is the dynamic model -----------------------------------------------------------
def test_pose_points_are_the_models_geometry(start_stop):
    body, table = start_stop.body, start_stop.table
    rows = np.arange(len(table["t"]))
    p = pose_points(start_stop, rows)
    assert np.allclose(np.linalg.norm(p["hip"] - p["stance_ankle"], axis=1), table["w"], atol=1e-9)
    assert np.allclose(np.linalg.norm(p["swing_hip"] - p["knee"], axis=1), body["l3"])
    assert np.allclose(np.linalg.norm(p["knee"] - p["swing_ankle"], axis=1), body["l4"])
    assert np.allclose(np.linalg.norm(p["head"] - p["hip"], axis=1), body["l2"])
    assert np.allclose(p["stance_ankle"][:, 1], body["l9"])
    # the same geometry as the physics package's (strobe.py repeats it in numpy: the plots read
    # results and import no CasADi)
    from klaw_ocp.body import Body
    from klaw_ocp.dynamics import swing_leg_points
    model = Body(height=body["height"], mass=body["mass"])
    for r in rows[:: max(1, len(rows) // 25)]:
        points = swing_leg_points(model, [table["theta3"][r], table["theta4"][r]], p["swing_hip"][r])
        assert np.allclose(points["knee"], p["knee"][r], atol=1e-12)
        assert np.allclose(points["ankle"], p["swing_ankle"][r], atol=1e-12)
    # the legs alternate: the swing leg of step k is the stance leg of step k + 1 ...
    assert [p["stance_leg"][table["step"] == k][0] for k in range(len(start_stop.steps))] == \
        [s["stance_leg"] for s in start_stop.steps]
    # ... and it lands where the next stance starts: at heel strike the heel is on the ground at
    # origin - l8 (eq. 3), so the ankle is l11 = |(l8, l9)| from that point
    for k in range(len(start_stop.steps) - 1):
        last = np.flatnonzero(table["step"] == k)[-1]
        heel = np.array([start_stop.steps[k + 1]["origin_x_m"] - body["l8"], 0.0])
        assert np.linalg.norm(p["swing_ankle"][last] - heel) == pytest.approx(body["l11"], abs=2e-3)


def test_strobe_rows_keep_every_heel_strike_and_the_window(natural):
    rows, bold = strobe_rows(natural, every=7)
    first_rows = np.flatnonzero(np.r_[True, np.diff(natural.table["step"]) != 0])
    assert set(first_rows) <= set(rows[bold]) and rows[-1] == len(natural.table["t"]) - 1
    t0, t1 = natural.steps[3]["t_start_s"], natural.steps[5]["t_start_s"]
    window, _ = strobe_rows(natural, every=7, t_range=(t0, t1))
    assert natural.table["t"][window].min() >= t0 - TOL and natural.table["t"][window].max() <= t1 + TOL
    with pytest.raises(ValueError, match="every: got 0"):
        strobe_rows(natural, every=0)


def test_one_leg_strobe_draws_only_that_leg(start_stop):
    from klaw_ocp.figures.plot_style import new_figure
    fig = new_figure(6, 3)
    ax = fig.add_subplot()
    draw_strobe(ax, start_stop, legs=("right",))
    colours = {tuple(np.round(c.get_colors()[0][:3], 3)) for c in ax.collections if hasattr(c, "get_segments")}
    from matplotlib.colors import to_rgb
    assert tuple(np.round(to_rgb(LEG_COLOURS["right"]), 3)) in colours
    assert tuple(np.round(to_rgb(LEG_COLOURS["left"]), 3)) not in colours
    assert _decode(png_bytes(legs_figure(start_stop, legs=("right",)))).shape[0] > 100
    with pytest.raises(ValueError, match="legs: got"):
        draw_strobe(ax, start_stop, legs=("middle",))


def test_posture_at_a_heel_strike_is_the_new_steps_first_sample(natural):
    from klaw_ocp.figures.plot_style import new_figure
    k = 5
    t = natural.steps[k]["t_start_s"]
    row = sample_at(natural, t)
    assert natural.table["step"][row] == k and natural.table["subphase"][row] == "double_support"
    assert natural.table["step"][sample_at(natural, t - 1e-9)] == k - 1     # just before: the landing swing
    ax = new_figure(4, 4).add_subplot()
    drawn = draw_posture(ax, natural, t, origin_at=0.0)
    assert drawn["stance_ankle"][0] == pytest.approx(0.0) and drawn["stance_leg"] == natural.steps[k]["stance_leg"]
    assert drawn["hip"][0] - drawn["stance_ankle"][0] == pytest.approx(
        natural.table["hip_x"][row] - natural.steps[k]["origin_x_m"])


def test_the_hip_height_plot_shows_one_bump_per_step(natural):
    """What hip_height.png must let a user see (§4.2): within every steady step the hip rises to
    one peak and falls again, and the reference it follows does the same."""
    t, y, ref = natural.table["t"], natural.table["hip_y"], natural.table["hip_y_ref"]
    for step in natural.steps:
        inside = (t > step["t_start_s"]) & (t < step["t_start_s"] + step["t_step_s"])
        for curve in (y[inside], ref[inside]):
            rises = np.diff(curve) > 0
            # one rise then one fall (a sign change of the slope from + to -), ignoring the
            # 2-4 mm dip of the monitored stance right after heel strike
            peaks = np.flatnonzero(rises[:-1] & ~rises[1:])
            big = [p for p in peaks if curve[p + 1] - curve.min() > 0.5 * (curve.max() - curve.min())]
            # and the millimetre's wobble of the monitored stance on the hip's plateau (issue #34's
            # hip holds its height into terminal stance): peaks no deeper apart than 1 mm are one
            apart = [(a, b) for a, b in zip(big, big[1:])
                     if min(curve[a + 1], curve[b + 1]) - curve[a + 1:b + 2].min() > 1e-3]
            assert len(big) >= 1 and not apart, (step["index"], peaks)


# -- a long walk: a readable selection, and the figure says which --------------------------------
@pytest.fixture(scope="module")
def long_run(natural):
    """The natural walk's 22 steps walked 5 times end to end: 110 steps, nothing solved."""
    from _long_walks import tiled
    return tiled(natural, 5)


def test_a_walk_of_up_to_60_steps_is_drawn_whole_a_longer_one_its_first_40_and_last_10():
    from klaw_ocp.figures.plot_style import drawn_note, drawn_steps
    assert drawn_steps(22) == [(0, 21)] and drawn_steps(60) == [(0, 59)] and drawn_note(60) == ""
    assert drawn_steps(61) == [(0, 39), (51, 60)] and drawn_steps(1000) == [(0, 39), (990, 999)]
    assert "steps 0–39 and 990–999 of 1000 drawn, 40–989 left out" in drawn_note(1000)


@pytest.mark.parametrize("name", ["hip_height", "torques", "states", "gait_diagram"])
def test_a_long_walks_time_plots_draw_its_first_and_last_steps_and_say_so(natural, long_run, name):
    fig = _figure(name)(long_run)
    steps = long_run.steps
    first_end = steps[39]["t_start_s"] + steps[39]["t_step_s"]
    last_start, end = steps[-10]["t_start_s"], walk_end(long_run)
    texts = [fig._suptitle.get_text() if fig._suptitle else ""] + [ax.get_title(loc="left") for ax in fig.axes]
    assert any("steps 0–39 and 100–109 of 110 drawn, 40–99 left out" in t for t in texts), texts
    # the time axes come in pairs side by side: the first 40 steps, then the last 10
    # (the gait diagram's zoom on one step aside)
    timed = [ax for ax in fig.axes if not ax.get_title(loc="left").startswith("Step ")]
    parts = sorted({tuple(np.round(ax.get_xlim(), 1)) for ax in timed})
    assert len(parts) == 2 and len(timed) % 2 == 0, parts
    (a0, a1), (b0, b1) = parts                  # (the gait diagram leaves room for its markers)
    assert a0 == pytest.approx(0.0, abs=0.5) and a1 == pytest.approx(first_end, abs=0.5)
    assert b0 == pytest.approx(last_start, abs=0.5) and b1 == pytest.approx(end, abs=0.5)
    # a short walk has one time axis per row and no note
    short = _figure(name)(natural)
    assert not any("long walk" in t for t in [short._suptitle.get_text() if short._suptitle else ""]
                   + [ax.get_title(loc="left") for ax in short.axes])


def test_a_long_walks_strobe_draws_its_first_and_last_steps_in_a_few_panels_and_says_so(natural, long_run):
    fig = legs_figure(long_run)
    titles = [ax.get_title(loc="left") for ax in fig.axes]
    assert titles[0].startswith("steps 0–") and titles[-1].startswith("steps 100–109")
    assert "(after steps 40–99, not drawn)" in titles[-1]
    assert sum("not drawn" in t for t in titles) == 1
    drawn = [tuple(int(v) for v in t.split(",")[0].removeprefix("steps ").split("–")) for t in titles]
    assert [a for a, _ in drawn] == sorted(a for a, _ in drawn)
    assert sum(b - a + 1 for a, b in drawn) == 50              # 40 + 10 steps, each in one panel
    assert "steps 0–39 and 100–109 of 110 drawn" in fig._suptitle.get_text()
    width, height = fig.get_size_inches() * DPI
    assert len(fig.axes) <= 6 and height < 4000                 # a 1000-step strobe was 48 723 px high
    image = _decode(png_bytes(fig))
    assert np.any(image[..., :3] < 0.9, axis=-1).mean() > 0.03
    assert not any("not drawn" in ax.get_title(loc="left") for ax in legs_figure(natural).axes)


def test_a_long_walk_renders_every_plot(long_run):
    for name, (_, data) in render_plots(long_run).items():
        image = _decode(data)
        assert 100 < image.shape[0] < 4000 and np.any(image[..., :3] < 0.9, axis=-1).mean() > 0.02, name


@pytest.mark.parametrize("methods", [("multiple-shooting",), ("multiple-shooting", "plain-shooting")])
def test_the_sweep_legend_lies_inside_the_figure(methods):
    """sweep.png's legend was cut at both edges of a one-method (one-panel) figure."""
    from klaw_ocp.figures.sweep_plot import sweep_figure
    rows = [{"method": m, "walk.speed": v, "status": "ok" if v != 3 else "failed", "wall_s": 0.3 * v,
             "failed_step": 2, "failed_subphase": "swing2"} for m in methods for v in (1, 3, 5)]
    fig = sweep_figure(rows, ["walk.speed"], "natural_walk")
    fig.canvas.draw()
    (legend,) = fig.legends
    box, page = legend.get_window_extent(fig.canvas.get_renderer()), fig.bbox
    assert page.x0 <= box.x0 and box.x1 <= page.x1 and page.y0 <= box.y0, (box, page)
    assert "loading the solver kernels" in " ".join(t.get_text() for t in legend.get_texts())
