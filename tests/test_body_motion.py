"""The body on the simulated walk (body_motion/motion.py, docs/body.md): the 56 angles are
checked through the skeleton's own forward kinematics of angles.csv's degrees, not through the
arrays they were computed from. Feet stay planted, bones keep their lengths, the hips are the
pelvis's, nothing jumps between frames, and the attributes of the lateral geometry and the upper
body act."""
import io
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from klaw_ocp.body import Body
from klaw_ocp.body_motion import ANGLES_COLUMNS, body_motion
from klaw_ocp.body_motion.motion import swing_hips
from klaw_ocp.body_motion.stance_legs import toe_off_feet
from klaw_ocp.body_motion.skeleton import ANGLE_NAMES, forward_kinematics
from klaw_ocp.body_motion.stance_legs import stance_frames
from klaw_ocp.body_motion.swing_kernel import TOE_OFF_BLEND
from klaw_ocp.body_motion.swing_legs import swing_legs
from klaw_ocp.body_motion.walk_samples import frame_times, hermite, locate_steps, spline_rates, swing_curves
from klaw_ocp.config import ExperimentConfig
from klaw_ocp.dynamics import stance_hips
from klaw_ocp.dynamics.points import foot_points_arrays, foot_points_float
from klaw_ocp.gait import LocomotionAttributes, stance_leg
from klaw_ocp.result_files.run_data import RunData
from klaw_ocp.result_files.tables import angles_csv
from klaw_ocp.kinematics.leg_geometry import leg_ik, meta_off_band
from klaw_ocp.kinematics.virtual_leg import hind_foot_at_rest
from klaw_ocp.walk import simulate_walk, walk_spec

ROOT = Path(__file__).resolve().parents[1]
FPS = 500.0
PLANTED_M = 1e-3
MAX_FRAME_STEP_DEG = 2.0
WALKS = [("natural_walk", "multiple-shooting"), ("natural_walk", "plain-shooting"),
         ("start_stop_5kmh", "multiple-shooting"), ("start_stop_5kmh", "plain-shooting"),
         ("start_stop_2kmh", "multiple-shooting"), ("accelerate", "multiple-shooting")]


@pytest.fixture(scope="module", params=WALKS, ids=["-".join(w) for w in WALKS])
def walked(request):
    """(walk, angles.csv at FPS read back from its text, the walk's own BodyMotion at FPS)."""
    name, method = request.param
    walk = simulate_walk(ROOT / "configs" / f"{name}.yaml", method=method)
    motion = body_motion(walk, FPS)
    path = io.StringIO(angles_csv(motion.table()))
    return walk, _read_csv(path), motion, request.param


def _read_csv(handle) -> dict:
    header = handle.readline().strip().split(",")
    rows = np.loadtxt(handle, delimiter=",", ndmin=2)
    return dict(zip(header, rows.T))


def _skeleton(walk, table):
    """Forward kinematics of angles.csv's columns (degrees)."""
    root = np.column_stack([table["root_x"], table["root_y"], table["root_z"]])
    angles = np.radians(np.column_stack([table[name] for name in ANGLE_NAMES]))
    return forward_kinematics(walk.spec.body, root, angles)


def _stances(walk):
    """(side, StanceFoot, walk time of its heel strike) of every foot that stands in the walk:
    step 0's hind foot (standing when the walk begins) and each step's stance foot, completed by
    the next step's double support where the walk has one."""
    first = walk.steps[0]
    hind = ("left" if stance_leg(0) == "right" else "right", first.hind_foot, first.t_start - first.hind_foot.t_step)
    return [hind] + [(stance_leg(s.index), walk.stance_foot(s.index), s.t_start) for s in walk.steps]


# -- angles.csv -------------------------------------------------------------------------------
def test_angles_table_has_time_root_and_the_56_angles_at_every_frame(walked):
    walk, table, motion, _ = walked
    assert list(table) == list(ANGLES_COLUMNS) and len(ANGLES_COLUMNS) == 4 + 56
    n = math.floor(walk.duration * FPS + 1e-9) + 1
    assert np.array_equal(motion.t, np.arange(n) / FPS)
    np.testing.assert_allclose(table["time"], motion.t, rtol=1e-11, atol=1e-12)
    assert motion.angles.shape == (n, 56) and np.all(np.isfinite(motion.angles))


def test_no_angle_moves_more_than_2_degrees_between_frames_at_500_fps(walked):
    """Heel strikes, toe-offs, the start from rest and the stop included."""
    _, table, _, _ = walked
    steps = np.abs(np.diff(np.column_stack([table[name] for name in ANGLE_NAMES]), axis=0))
    worst = np.unravel_index(np.argmax(steps), steps.shape)
    assert steps.max() < MAX_FRAME_STEP_DEG, (ANGLE_NAMES[worst[1]], table["time"][worst[0]], steps.max())


EXTREMES = {
    "long_steps": ROOT / "configs" / "long_steps.yaml",
    "short_steps": ROOT / "configs" / "short_steps.yaml",
    "8kmh": {"name": "fast", "body": {"height": 1.8, "mass": 80}, "walk": {"speed": 8.0, "steps": 4}},
    "3.5kmh-1.5m": {"name": "short", "body": {"height": 1.5, "mass": 60}, "walk": {"speed": 3.5, "steps": 4}},
}


@pytest.mark.parametrize("name", list(EXTREMES))
def test_no_angle_moves_more_than_2_degrees_between_frames_in_the_extreme_steps(name):
    """configs/long_steps.yaml (the hip beyond the trailing leg's reach before toe-off, its foot at
    MAX_PITCH), configs/short_steps.yaml (a double support of 17 ms; the push-off begins in single
    support), 8 km/h (a landing on a flexed knee; the knee's reach at toe-off) and 3.5 km/h on a
    1.5 m body (the knee's reach at the end of single support): at 500 fps, no angle moves by 2°
    or more between frames."""
    walk = simulate_walk(EXTREMES[name], method="multiple-shooting")
    angles = np.degrees(body_motion(walk, FPS).angles)
    steps = np.abs(np.diff(angles, axis=0))
    worst = np.unravel_index(np.argmax(steps), steps.shape)
    assert steps.max() < MAX_FRAME_STEP_DEG, (ANGLE_NAMES[worst[1]], worst[0] / FPS, steps.max())


# -- the skeleton of angles.csv --------------------------------------------------------------
def test_stance_feet_stay_planted_on_their_centrelines(walked):
    """Heel while the foot turns about it and while flat, the metatarsal head while flat and during
    heel-off (the toe angle below the meta-off band), the toe tip from foot flat to toe-off (it
    lies flat during heel-off and is the pivot of meta-off): each within 1 mm of where the foot
    landed, on its ground line z = ±foot_lateral_distance/2."""
    walk, table, _, _ = walked
    skeleton, body, t = _skeleton(walk, table), walk.spec.body, table["time"]
    half = walk.spec.attributes.foot_lateral_distance / 2
    forward = math.sqrt(body.l12 ** 2 - body.l9 ** 2)
    meta_off = walk.spec.attributes.meta_off_theta6
    drift = 0.0
    for side, foot, t0 in _stances(walk):
        s = side[0]
        ankle_x, z = foot.foot.ankle_x, half if side == "right" else -half
        toe_off = min(t0 + foot.t_toe_off, walk.duration)
        # the head stays down until the toe joint starts to stop following the pitch (the meta-off band)
        toe_flat = table[f"{s}_toe_dorsiflexion"] < meta_off - math.degrees(meta_off_band(math.radians(meta_off))) - 1e-6
        windows = {
            "heel": (skeleton.landmarks[f"{s}_heel"], ankle_x - body.l8, (t >= t0) & (t < t0 + foot.t_heel_off)),
            "metatarsal": (skeleton.position(f"{s}_toes"), ankle_x + forward,
                           (t >= t0 + foot.t_flat) & (t <= toe_off) & toe_flat),
            "toe": (skeleton.end_sites[f"{s}_toes"], ankle_x + forward + body.l13, (t >= t0 + foot.t_flat) & (t <= toe_off)),
        }
        assert windows["toe"][2].sum() > 0.1 * FPS * 0.5, (side, t0)      # a good part of every stance
        for name, (points, x, rows) in windows.items():
            if rows.any():
                miss = np.linalg.norm(points[rows] - np.array([x, 0.0, z]), axis=1)
                drift = max(drift, float(miss.max()))
                assert miss.max() < PLANTED_M, (side, name, t0, float(miss.max()))
    print(f"worst planted-foot drift {drift * 1e3:.4f} mm")


def test_the_root_is_the_pelvis_centre_and_the_angles_rebuild_the_legs(walked):
    """The skeleton of the CSV puts the hips, knees, ankles and feet where the body motion computed
    them (so the angles say what the legs do), the root midway between the hips, and the legs'
    bones at their lengths (thigh l3, shank l4). The tolerance is the virtual leg's: the leg that
    stands at a stop reaches 1.3 µm beyond l1 (the telescope's standing length, ERRATA on l11),
    and its straight knee cannot bridge that."""
    walk, table, motion, _ = walked
    skeleton, body = _skeleton(walk, table), walk.spec.body
    root = np.column_stack([table["root_x"], table["root_y"], table["root_z"]])
    np.testing.assert_allclose(0.5 * (skeleton.position("r_hip") + skeleton.position("l_hip")), root, atol=1e-9)
    for s, side in (("r", "right"), ("l", "left")):
        legs = motion.legs[side]
        for joint, point in (("hip", legs.hip), ("knee", legs.knee), ("ankle", legs.ankle), ("toes", legs.metatarsal)):
            np.testing.assert_allclose(skeleton.position(f"{s}_{joint}"), point, atol=1e-5, err_msg=f"{side} {joint}")
        np.testing.assert_allclose(skeleton.landmarks[f"{s}_heel"], legs.heel, atol=1e-5)
        np.testing.assert_allclose(skeleton.end_sites[f"{s}_toes"], legs.toe, atol=1e-5)
        np.testing.assert_allclose(np.linalg.norm(legs.hip - legs.knee, axis=1), body.l3, atol=1e-9)
        np.testing.assert_allclose(np.linalg.norm(legs.knee - legs.ankle, axis=1), body.l4, atol=1e-5)


def test_the_root_follows_the_simulated_hip(walked):
    """The root is the pelvis's centre on the planar model: the simulated (stance) hip plus half
    the pelvis's offset to the other hip (kinematics/pelvis.py), x for x, and as high as the
    stance leg in its tilted plane lets it be: a few mm below the planar model's at most.
    (dynamics.csv's hip is interpolated linearly within each step here, up to 1.1 mm off between
    its nodes 26 ms apart at 5 km/h, where the hip decelerates after impact, and 1.5 mm at 2 km/h,
    nodes 45 ms apart.)"""
    walk, _, motion, _ = walked
    table = RunData.from_walk(walk, fps=1.0).table
    step, tau = locate_steps(walk.steps, motion.t)
    centre = np.full((len(motion.t), 2), np.nan)
    for k in np.unique(step):
        rows, mine = step == k, table["step"] == k
        (dx, dy), _, _ = walk.steps[k].pelvis.swing_hip_offset(tau[rows])
        centre[rows, 0] = np.interp(motion.t[rows], table["t"][mine], table["hip_x"][mine]) + dx / 2
        centre[rows, 1] = np.interp(motion.t[rows], table["t"][mine], table["hip_y"][mine]) + dy / 2
    np.testing.assert_allclose(motion.root[:, 0], centre[:, 0], atol=2e-3)
    below = centre[:, 1] - motion.root[:, 1]
    print(f"root below the planar pelvis centre: {below.min() * 1e3:.2f} to {below.max() * 1e3:.2f} mm")
    assert below.min() > -1.5e-3 and below.max() < 4e-3, (below.min(), below.max())


def test_no_heel_or_toe_tip_below_the_ground_in_stance(walked):
    walk, table, _, _ = walked
    skeleton, t = _skeleton(walk, table), table["time"]
    lowest = {}
    for side, foot, t0 in _stances(walk):
        s = side[0]
        rows = (t >= max(t0, 0.0)) & (t <= t0 + foot.t_toe_off)
        for name, points in (("heel", skeleton.landmarks[f"{s}_heel"]), ("toe", skeleton.end_sites[f"{s}_toes"])):
            lowest[name] = min(lowest.get(name, 0.0), float(points[rows, 1].min()))
    print(f"lowest in stance: heel {lowest['heel'] * 1e3:.3f} mm, toe tip {lowest['toe'] * 1e3:.3f} mm")
    assert min(lowest.values()) > -PLANTED_M, lowest


def test_no_heel_or_toe_tip_below_the_ground_in_swing(walked):
    """Also in the first step from rest and the closing step, where the dynamic leg's ankle comes
    below l9 and the body bends the knee to lift the foot (SwingFoot.lifted_foot)."""
    walk, table, _, key = walked
    skeleton, t = _skeleton(walk, table), table["time"]
    lowest = {}
    for s, side in (("r", "right"), ("l", "left")):
        on_ground = np.zeros(len(t), bool)
        for leg, foot, t0 in _stances(walk):
            if leg == side:
                on_ground |= (t >= t0) & (t <= t0 + foot.t_toe_off)
        for name, points in (("heel", skeleton.landmarks[f"{s}_heel"]), ("toe", skeleton.end_sites[f"{s}_toes"])):
            if (~on_ground).any():
                lowest[name] = min(lowest.get(name, 0.0), float(points[~on_ground, 1].min()))
    print(f"lowest in swing: heel {lowest['heel'] * 1e3:.3f} mm, toe tip {lowest['toe'] * 1e3:.3f} mm")
    assert min(lowest.values()) > -PLANTED_M, lowest


# -- the attributes act ------------------------------------------------------------------------
@pytest.fixture(scope="module")
def short_walk():
    config = ExperimentConfig.from_mapping({"name": "short", "body": {"height": 1.8, "mass": 80},
                                            "walk": {"speed": 5.0, "steps": 3}})
    return simulate_walk(walk_spec(config))


def _with(walk, **attributes):
    """The body of ``walk`` with other attributes (the walk's and every step's: a step's own are
    the ones its body moves with)."""
    spec = replace(walk.spec, attributes=walk.spec.attributes.with_overrides(attributes))
    steps = [replace(s, plan=replace(s.plan, attributes=s.plan.attributes.with_overrides(attributes)))
             for s in walk.steps]
    return body_motion(replace(walk, spec=spec, steps=steps), 30.0)


def _column(motion, name):
    return motion.angles[:, ANGLE_NAMES.index(name)]


def test_wider_feet_abduct_the_hips(short_walk):
    narrow, wide = _with(short_walk, foot_lateral_distance=0.0), _with(short_walk, foot_lateral_distance=0.3)
    for side, s in (("right", "r"), ("left", "l")):
        assert np.all(_column(wide, f"{s}_hip_adduction") < _column(narrow, f"{s}_hip_adduction") - math.radians(3))
        for motion, distance in ((narrow, 0.0), (wide, 0.3)):
            on_ground = np.abs(motion.legs[side].toe[:, 1]) < 1e-12      # the toe tip on its ground line
            z = motion.legs[side].toe[on_ground, 2]
            np.testing.assert_allclose(z, (distance if side == "right" else -distance) / 2, atol=1e-12)


def test_the_lateral_shift_moves_the_root_sideways(short_walk):
    still, weaving = _with(short_walk, pelvic_lateral_shift=0.0), _with(short_walk, pelvic_lateral_shift=0.05)
    assert np.all(still.root[:, 2] == 0.0)
    assert np.abs(weaving.root[:, 2]).max() > 0.03
    # towards the stance leg: right (+z) while step 0's right leg stands
    first_step = weaving.t < short_walk.steps[1].t_start
    assert weaving.root[first_step, 2].max() > 0.03 and weaving.root[first_step, 2].min() >= 0


def test_the_arm_swing_amplitude_sets_the_shoulders_range(short_walk):
    small, large = _with(short_walk, arm_swing_amplitude=5.0), _with(short_walk, arm_swing_amplitude=40.0)
    for s in ("r", "l"):
        assert np.ptp(_column(large, f"{s}_shoulder_flexion")) > 4 * np.ptp(_column(small, f"{s}_shoulder_flexion"))


# -- the pieces --------------------------------------------------------------------------------
def test_frame_times_include_a_last_frame_on_the_walk_end_and_refuse_bad_fps():
    assert np.array_equal(frame_times(1.0, 30.0), np.arange(31) / 30.0)
    assert len(frame_times(0.999999, 30.0)) == 30
    for fps in (0.0, -1.0, math.nan, "30"):
        with pytest.raises(ValueError, match="fps"):
            frame_times(1.0, fps)


def test_hermite_reproduces_a_cubic_and_takes_the_later_of_two_nodes_at_one_time():
    t = np.array([0.0, 0.3, 0.3, 1.0])
    y, dy = t ** 3 - t, 3 * t ** 2 - 1
    dy_after = dy.copy()
    dy_after[2] += 5.0                 # a rate jump at the repeated node (a lock event)
    samples = np.linspace(0.0, 1.0, 41)
    exact = samples ** 3 - samples
    before = samples < 0.3
    np.testing.assert_allclose(hermite(t, y, dy_after, samples)[before], exact[before], atol=1e-14)
    after = hermite(t, y, dy_after, np.array([0.3, 0.3 + 1e-7]))
    assert after[0] == pytest.approx(0.3 ** 3 - 0.3) and (after[1] - after[0]) / 1e-7 == pytest.approx(dy_after[2], rel=1e-4)
    rates = spline_rates(t, y)
    assert rates[1] == rates[2]


def test_swing_foot_points_for_arrays_equal_the_float_form():
    rng = np.random.default_rng(3)
    dims = (0.053, 0.069, 0.160, 0.089)
    ankle, angles = rng.normal(size=(7, 2)), rng.uniform(-2, 2, size=(7, 3))
    heel, meta, toe = foot_points_arrays(ankle, *angles.T, *dims)
    for k in range(7):
        expected = foot_points_float(*ankle[k], *angles[k], *dims)
        np.testing.assert_allclose(np.array([heel[k], meta[k], toe[k]]), np.array(expected), atol=1e-15)


def test_many_stances_at_once_are_each_stance_alone(short_walk):
    """body_motion.stance_legs: one pass over every stance of a walk gives what one call per stance
    gives, to rounding (each stance is evaluated in its own foot's frame), which a knee within
    rounding of straight turns into 1e-8 rad (the flexion grows as the root of the shortening)."""
    feet = [short_walk.steps[0].hind_foot] + [short_walk.stance_foot(k) for k in range(len(short_walk.steps))]
    t = [np.linspace(0.0, min(f.t_toe_off, f.t_step + 0.1), 37) for f in feet]
    hips = [np.column_stack([f.foot.ankle_x + np.linspace(-0.35, 0.45, 37), np.full(37, 0.9)]) for f in feet]
    together = stance_frames(feet, np.repeat(np.arange(len(feet)), 37), np.concatenate(t), np.vstack(hips))
    for k, foot in enumerate(feet):
        alone, rows = foot.frames(t[k], hips[k]), slice(37 * k, 37 * (k + 1))
        for name in ("pitch", "knee", "ankle", "heel", "metatarsal", "toe", "theta3", "theta4", "theta5", "theta6"):
            np.testing.assert_allclose(getattr(together, name)[rows], getattr(alone, name), atol=1e-7, err_msg=name)
        assert np.array_equal(together.period[rows], alone.period)


# -- the virtual leg is continuous where the body needs it ---------------------------------------
def test_the_foot_comes_down_as_fast_as_the_hip_approaches_it_at_heel_strike(short_walk):
    """The leg is straight at heel strike; the hip-ankle distance then starts still, so the knee
    bends at a finite rate (a shortening rate would bend it as sqrt(t))."""
    step = short_walk.steps[1]
    foot = short_walk.stance_foot(1)
    stance = step.subphase("stance")
    hips, velocities = stance_hips(short_walk.spec.body, stance.states[:1], np.array([step.origin_x, short_walk.spec.body.l9]))
    dt = np.array([0.0, 1e-4, 2e-4])
    legs = foot.frames(dt, hips[0] + dt[:, None] * velocities[0])
    reach = np.hypot(*(legs.ankle - legs.hip).T)
    assert reach[0] == pytest.approx(short_walk.spec.body.l1, abs=1e-12)
    assert abs(reach[1] - reach[0]) < 1e-6 and foot.rocker_rate > 0      # a shortening rate: 5e-5
    assert np.degrees(legs.theta4[2]) < 0.5          # sqrt(t) would give about 1.8° after 0.2 ms
    # the rocker alone (up to foot flat; the hip held where it struck, far beyond the flat foot's reach)
    later = foot.frames(np.linspace(0, foot.t_flat * (1 - 1e-12), 50), np.tile(hips[0], (50, 1)))
    assert np.all(np.diff(later.pitch) >= 0) and later.pitch[-1] == pytest.approx(0.0, abs=1e-12)


def test_the_heel_rises_from_the_ground_at_heel_off(short_walk):
    step = short_walk.steps[1]
    foot, stance = short_walk.stance_foot(1), step.subphase("stance")
    hip = np.array([[np.interp(foot.t_heel_off, stance.t, step.stance_hips[:, k]) for k in range(2)]])
    just_after = foot.pitch(np.array([foot.t_heel_off + 1e-9]), hip)
    assert 0.0 <= just_after[0] < 1e-5


def test_a_foot_that_stood_still_starts_its_push_off_from_rest():
    """A standing hind foot with no scheduled knee flexion (virtual_leg.hind_foot_at_rest): while
    the hip is within the flat foot's reach the foot stays flat and the knee bends as the reach
    needs; once the hip has passed out of it the leg is straight and the heel rises, never coming
    down, from zero rate."""
    body, attrs = Body(height=1.8, mass=80.0), LocomotionAttributes.defaults()
    t = np.linspace(0.0, 0.2, 41)
    hips = np.column_stack([np.linspace(-0.05, 0.45, 41), np.full(41, body.l9 + body.l1 - 0.01)])
    foot = hind_foot_at_rest(body, attrs, 0.0).with_double_support(hips[0], 0.2, 0.0)
    legs = foot.frames(t, hips)
    assert legs.pitch[0] == 0.0 and np.all(np.diff(legs.pitch) >= -1e-12) and legs.pitch[-1] > 0.5
    flat, up = legs.pitch == 0.0, legs.pitch > 0.0
    reach = np.hypot(*(legs.ankle[flat] - hips[flat]).T)
    knee = math.pi - np.arccos((body.l3 ** 2 + body.l4 ** 2 - reach ** 2) / (2 * body.l3 * body.l4))
    np.testing.assert_allclose(legs.theta4[flat], knee, atol=1e-9)
    np.testing.assert_allclose(legs.theta4[up], 0.0, atol=1e-9)
    assert legs.pitch[np.argmax(up)] < 0.01                          # the heel leaves the ground gently


def test_the_body_swing_knee_is_the_dynamic_knee_between_the_toe_off_and_landing_blends(short_walk):
    """body_motion/swing_legs.py: the swing leg hangs from its own hip in its plane with the
    dynamics' hip-to-ankle distance, so its knee is the dynamic θ4 once the blend out of the
    virtual leg's toe-off posture is over and until swing3, where it blends into the next stance's
    landing (no lift in this walk: the turned foot clears); it starts from the virtual leg's
    toe-off ankle and lands on the next stance's heel-strike ankle, its heel on the planned point."""
    walk, body = short_walk, short_walk.spec.body
    hips_at = swing_hips(walk, lambda t: np.zeros((len(t), 3)))
    feet = toe_off_feet(walk, hips_at)
    start = feet[0]
    for k, step in enumerate(walk.steps):
        foot = step.swing_foot
        after = foot.t_toe_off + TOE_OFF_BLEND * (foot.t1 - foot.t_toe_off)
        tau = np.r_[foot.t_toe_off, np.linspace(after, foot.t2, 50), foot.t_heel_strike]
        steps = np.full(len(tau), k)
        leg = swing_legs(walk, steps, tau, hips_at, feet)
        _, knee, _ = leg_ik(body, leg["hip"], leg["ankle"])
        # 1e-7: at the straight knee of swing3 a round-off of the distance is 1e-8 rad of knee
        assert knee[1:-1] == pytest.approx(swing_curves(walk)(steps[1:-1], tau[1:-1])[:, 1], abs=1e-7), k
        if k + 1 < len(walk.steps):
            lands = walk.stance_foot(k + 1)
            at_strike = lands.frames(np.array([0.0]), leg["hip"][-1:])
            assert leg["ankle"][-1] == pytest.approx(at_strike.ankle[0], abs=1e-9), k
            assert leg["heel"][-1] == pytest.approx([lands.foot.ankle_x - body.l8, 0.0], abs=1e-9), k
            assert leg["toe"][-1] == pytest.approx(at_strike.toe[0], abs=1e-9), k
        assert leg["ankle"][0] == pytest.approx(start[k], abs=1e-12), k
