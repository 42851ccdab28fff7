"""The upper body and the lateral displacement (body_motion/upper_body.py, docs/upper-body.md):
§2.4 principle 3 and the determinants of gait of §4.2."""
import math

import numpy as np
import pytest

from klaw_ocp.body import Body
from klaw_ocp.body_motion import pose
from klaw_ocp.body_motion.skeleton import ANGLE_NAMES, forward_kinematics, rest_root_position
from klaw_ocp.body_motion.upper_body import (ELBOW_MIN_FLEXION, LATERAL_PEAK_SINGLE_SUPPORT_FRACTION,
                                             REFERENCE_HIP_HALF_RANGE, SHOULDER_MEAN_FLEXION,
                                             SHOULDER_ROTATION_SHARE, THORAX_COUNTER_ROTATION,
                                             StepWindow, lateral_displacement, upper_body_motion)
from klaw_ocp.gait import LocomotionAttributes

DEFAULTS = LocomotionAttributes.defaults()
BODY = Body(1.8, 75.0)
DT = 1e-4            # s: the sampling of the continuity checks (finer than the 500 fps check)
T_STEP, T_DS = 0.56, 0.13   # s: the paper's 5 km/h walk (107.5 steps/min, eq. 2)


def attrs(**overrides):
    return DEFAULTS.with_overrides(overrides)


def walk_windows(first=0.3, moving_steps=5, closing=True, gap_after=None):
    """Alternating steps from the right leg; the last one (if ``closing``) still; an optional gap
    of 0.2 s after window ``gap_after``."""
    windows, start = [], first
    for k in range(moving_steps + int(closing)):
        side = ("right", "left")[k % 2]
        windows.append(StepWindow(start, T_STEP, T_DS, side, moving=k < moving_steps))
        start += T_STEP + (0.2 if k == gap_after else 0.0)
    return windows


def dense_time(windows):
    end = max(w.t_start + w.t_step for w in windows)
    return np.arange(0.0, end + 0.3, DT)


def peak_time(w: StepWindow) -> float:
    return w.t_start + w.t_ds + LATERAL_PEAK_SINGLE_SUPPORT_FRACTION * (w.t_step - w.t_ds)


def sinusoidal_hips(n=400, half_range=REFERENCE_HIP_HALF_RANGE, mean=math.radians(10.0)):
    """Two hips in antiphase about a common mean (walking hips flex more than they extend)."""
    phase = np.linspace(0.0, 4 * math.pi, n)
    return phase, {"right": mean + half_range * np.sin(phase), "left": mean - half_range * np.sin(phase)}


# --- lateral displacement ------------------------------------------------------------------

def test_lateral_displacement_is_zero_at_every_heel_strike_and_outside_the_walk():
    windows = walk_windows()
    strikes = np.array([w.t_start for w in windows] + [windows[-1].t_start + T_STEP])
    z = lateral_displacement(DEFAULTS, windows, strikes)
    np.testing.assert_allclose(z, 0.0, atol=1e-15)
    outside = np.array([-1.0, 0.0, 0.29, strikes[-1] + 0.01, 100.0])
    np.testing.assert_allclose(lateral_displacement(DEFAULTS, windows, outside), 0.0, atol=0.0)


def test_lateral_displacement_peaks_towards_the_stance_leg_shortly_after_toe_off():
    """In each moving step the extreme is +shift for a right stance, -shift for a left one, reached
    after the hind leg's toe-off and before the middle of single support."""
    shift = attrs().get("pelvic_lateral_shift")
    windows = walk_windows(closing=False)
    t = dense_time(windows)
    z = lateral_displacement(DEFAULTS, windows, t)
    for w in windows:
        inside = (t >= w.t_start) & (t <= w.t_start + w.t_step)
        sign = 1.0 if w.stance_side == "right" else -1.0
        towards = sign * z[inside]
        assert towards.min() >= -1e-15                      # never towards the swing side
        assert towards.max() == pytest.approx(shift, rel=1e-3)
        t_extreme = t[inside][np.argmax(towards)]
        toe_off, mid_single_support = w.t_start + w.t_ds, w.t_start + (w.t_ds + w.t_step) / 2
        assert toe_off < t_extreme < mid_single_support
        assert t_extreme == pytest.approx(peak_time(w), abs=DT)


def test_lateral_displacement_alternates_sides_step_to_step():
    windows = walk_windows(closing=False)
    z = lateral_displacement(DEFAULTS, windows, np.array([peak_time(w) for w in windows]))
    assert np.all(np.sign(z) == [1, -1, 1, -1, 1])
    assert np.all(np.diff(np.sign(z)) != 0)


def test_lateral_displacement_is_continuous_across_windows_gaps_and_the_closing_step():
    windows = walk_windows(gap_after=1)
    z = lateral_displacement(DEFAULTS, windows, dense_time(windows))
    # the steepest ramp is shift / (t_ds + a quarter of single support) ~ 0.08 m/s: 8e-6 m per
    # sample; a step in the curve would be centimetres
    assert np.abs(np.diff(z)).max() < 2e-5


def test_lateral_displacement_scales_with_the_attribute_and_vanishes_with_it():
    windows = walk_windows()
    t = dense_time(windows)
    z2 = lateral_displacement(attrs(pelvic_lateral_shift=0.02), windows, t)
    z4 = lateral_displacement(attrs(pelvic_lateral_shift=0.04), windows, t)
    np.testing.assert_allclose(z4, 2.0 * z2, atol=1e-15)
    assert np.abs(z2).max() == pytest.approx(0.02, rel=1e-3)
    np.testing.assert_array_equal(lateral_displacement(attrs(pelvic_lateral_shift=0.0), windows, t), 0.0)


def test_a_still_step_has_no_lateral_displacement():
    windows = walk_windows()
    closing = windows[-1]
    assert not closing.moving
    t = dense_time(windows)
    z = lateral_displacement(DEFAULTS, windows, t)
    np.testing.assert_array_equal(z[t >= closing.t_start], 0.0)
    assert np.abs(z[t < closing.t_start]).max() > 0.019     # the moving steps do weave


@pytest.mark.parametrize("windows,t,message", [
    ([StepWindow(0.0, T_STEP, T_DS, "middle")], np.zeros(3), r"steps\[0\]\.stance_side"),
    ([StepWindow(0.0, T_STEP, T_STEP, "right")], np.zeros(3), r"steps\[0\]\.t_ds"),
    ([StepWindow(0.0, 0.0, 0.0, "right", moving=False)], np.zeros(3), r"steps\[0\]\.t_step"),
    ([StepWindow(0.0, T_STEP, T_DS, "right"), StepWindow(0.5, T_STEP, T_DS, "left")], np.zeros(3),
     "overlaps"),
    ([StepWindow(0.0, math.nan, T_DS, "right")], np.zeros(3), r"steps\[0\]"),
    ([StepWindow(0.0, T_STEP, T_DS, "right")], np.zeros((3, 1)), "t:"),
    ([StepWindow(0.0, T_STEP, T_DS, "right")], np.array([0.0, np.inf]), "t:"),
])
def test_lateral_displacement_refuses_bad_arguments_naming_them(windows, t, message):
    with pytest.raises(ValueError, match=message):
        lateral_displacement(DEFAULTS, windows, t)


# --- arms ------------------------------------------------------------------------------------

def correlation(a, b):
    return float(np.corrcoef(a, b)[0, 1])


def test_each_arm_swings_forward_with_the_opposite_leg():
    phase, hips = sinusoidal_hips()
    upper = upper_body_motion(DEFAULTS, phase, np.zeros_like(phase), hips)
    for side, other in (("right", "left"), ("left", "right")):
        assert correlation(upper.shoulder_flexion[side], hips[side]) < -0.9
        assert correlation(upper.shoulder_flexion[side], hips[other]) > 0.9


@pytest.mark.parametrize("amplitude_deg", [0.0, 10.0, 20.0, 45.0])
@pytest.mark.parametrize("hip_scale", [0.5, 1.0])
def test_the_shoulder_half_range_is_the_attribute_at_the_reference_hip_range(amplitude_deg, hip_scale):
    """Half range = arm_swing_amplitude x (hip half range / REFERENCE_HIP_HALF_RANGE), about
    SHOULDER_MEAN_FLEXION whatever the hips' mean; 0 leaves the arms still."""
    phase, hips = sinusoidal_hips(n=801, half_range=hip_scale * REFERENCE_HIP_HALF_RANGE)
    upper = upper_body_motion(attrs(arm_swing_amplitude=amplitude_deg), phase, np.zeros_like(phase), hips)
    for side in ("right", "left"):
        shoulder = upper.shoulder_flexion[side]
        half_range = (shoulder.max() - shoulder.min()) / 2
        assert half_range == pytest.approx(math.radians(amplitude_deg) * hip_scale, abs=1e-6)
        assert (shoulder.max() + shoulder.min()) / 2 == pytest.approx(SHOULDER_MEAN_FLEXION, abs=1e-6)


def test_elbows_stay_flexed_and_bend_more_in_front():
    phase, hips = sinusoidal_hips()
    # a swing of ±20° (the default's at about 6 km/h; docs/upper-body.md)
    upper = upper_body_motion(attrs(arm_swing_amplitude=20.0), phase, np.zeros_like(phase), hips)
    for side in ("right", "left"):
        elbow = np.degrees(upper.elbow_flexion[side])
        assert 15.0 <= elbow.min() <= 20.0 and 35.0 <= elbow.max() <= 45.0   # people's range
        assert correlation(upper.elbow_flexion[side], upper.shoulder_flexion[side]) > 0.99
        abduction = np.degrees(upper.shoulder_abduction[side])
        assert np.all((abduction > 0.0) & (abduction < 15.0))                # hands clear the hips
    # the largest swing on long steps still leaves the elbow bent
    _, big = sinusoidal_hips(half_range=math.radians(35.0))
    wide = upper_body_motion(attrs(arm_swing_amplitude=60.0), phase, np.zeros_like(phase), big)
    assert wide.elbow_flexion["right"].min() >= ELBOW_MIN_FLEXION - 1e-12


# --- trunk and head --------------------------------------------------------------------------

def walking_pelvis(phase):
    """Pelvis tilt, list and rotation of a few degrees, each with its own phase."""
    return np.radians(np.column_stack([3.0 + 2.0 * np.sin(2 * phase), 5.0 * np.sin(phase + 0.7),
                                       4.0 * np.cos(phase)]))


def test_the_totals_keep_the_trunk_lean_and_the_head_level():
    """Plane by plane: the trunk's pitch in the world is θ2, the head's pitch and yaw are zero,
    the shoulder line turns against the pelvis by THORAX_COUNTER_ROTATION of its rotation."""
    phase, hips = sinusoidal_hips()
    lean = math.radians(10.0) + math.radians(2.0) * np.sin(2 * phase)
    pelvis = walking_pelvis(phase)
    tilt, pelvic_list, rotation = pelvis.T
    upper = upper_body_motion(DEFAULTS, phase, lean, hips, pelvis)
    np.testing.assert_allclose(tilt + upper.trunk_flexion, lean, atol=1e-15)
    np.testing.assert_allclose(tilt + upper.trunk_flexion + upper.head_flexion, 0.0, atol=1e-15)
    np.testing.assert_allclose(rotation + upper.trunk_rotation + upper.head_rotation, 0.0, atol=1e-15)
    np.testing.assert_allclose(rotation + SHOULDER_ROTATION_SHARE * upper.trunk_rotation,
                               -THORAX_COUNTER_ROTATION * rotation, atol=1e-15)
    np.testing.assert_allclose(upper.trunk_bending, pelvic_list, atol=0.0)   # sign: see the FK test
    assert all(np.shape(getattr(upper, f)) == phase.shape
               for f in ("trunk_flexion", "trunk_bending", "trunk_rotation", "head_flexion", "head_rotation"))


def test_no_pelvis_angles_means_a_level_square_pelvis():
    phase, hips = sinusoidal_hips()
    lean = np.full_like(phase, 0.1)
    implicit = upper_body_motion(DEFAULTS, phase, lean, hips)
    explicit = upper_body_motion(DEFAULTS, phase, lean, hips, np.zeros((phase.size, 3)))
    for name in ("trunk_flexion", "trunk_bending", "trunk_rotation", "head_flexion", "head_rotation"):
        np.testing.assert_array_equal(getattr(implicit, name), getattr(explicit, name))
    np.testing.assert_allclose(implicit.trunk_flexion, 0.1)
    np.testing.assert_allclose(implicit.head_flexion, -0.1)


def skeleton_with(upper_of, pelvis_angles):
    """Forward kinematics of a standing pose with the given pelvis angles and the upper body that
    ``upper_of(n)`` computes, its angles through pose.skeleton_angles as the walk will make them."""
    n = pelvis_angles.shape[0]
    root = np.tile(rest_root_position(BODY), (n, 1))
    lower = np.zeros((n, len(ANGLE_NAMES)))
    lower[:, :3] = pelvis_angles
    frames = forward_kinematics(BODY, root, lower)
    legs = {side: pose.LegPoints(hip=frames.position(f"{s}_hip"), knee=frames.position(f"{s}_knee"),
                                 ankle=frames.position(f"{s}_ankle"), heel=frames.landmarks[f"{s}_heel"],
                                 metatarsal=frames.position(f"{s}_toes"), toe=frames.end_sites[f"{s}_toes"])
            for s, side in (("r", "right"), ("l", "left"))}
    angles = pose.skeleton_angles(BODY, root, pelvis_angles, legs, upper_of(n))
    return forward_kinematics(BODY, root, angles)


def still_hips(n):
    return {"right": np.zeros(n), "left": np.zeros(n)}


def test_with_a_level_pelvis_the_head_top_is_straight_above_c1_while_the_trunk_leans():
    lean = math.radians(10.0)
    frames = skeleton_with(lambda n: upper_body_motion(DEFAULTS, np.zeros(n), np.full(n, lean),
                                                       still_hips(n)), np.zeros((1, 3)))
    head_top, c1, l5 = frames.end_sites["C1"][0], frames.position("C1")[0], frames.position("L5")[0]
    np.testing.assert_allclose(head_top[[0, 2]], c1[[0, 2]], atol=1e-9)
    np.testing.assert_allclose(frames.rotation("C1")[0], np.eye(3), atol=1e-9)
    assert c1[0] - l5[0] > 0.5 * math.sin(lean) * (c1[1] - l5[1])      # the trunk does lean forward


@pytest.mark.parametrize("plane", ["list", "rotation"])
def test_a_single_pelvic_angle_is_compensated_exactly(plane):
    """List alone: the thorax (T1) stays upright and the head level. Rotation alone: the thorax
    turns the other way by THORAX_COUNTER_ROTATION of it, the head faces forward."""
    value = math.radians(6.0)
    pelvis = np.zeros((1, 3))
    pelvis[0, {"list": 1, "rotation": 2}[plane]] = value
    frames = skeleton_with(lambda n: upper_body_motion(DEFAULTS, np.zeros(n), np.zeros(n), still_hips(n),
                                                       pelvis), pelvis)
    thorax = frames.rotation("T1")[0]
    if plane == "list":
        assert frames.position("r_hip")[0, 1] > frames.position("l_hip")[0, 1]   # right side up
        np.testing.assert_allclose(thorax[:, 1], [0.0, 1.0, 0.0], atol=1e-12)
    else:
        thorax_yaw = math.atan2(-thorax[2, 0], thorax[0, 0])     # + front to the left, as the pelvis
        assert thorax_yaw == pytest.approx(-THORAX_COUNTER_ROTATION * value, abs=1e-12)
    np.testing.assert_allclose(frames.rotation("C1")[0], np.eye(3), atol=1e-12)


def test_with_every_pelvic_angle_and_a_lean_the_head_stays_level_to_first_order():
    """The totals add plane by plane; in 3-D the rotations do not commute, leaving a second-order
    error: about 1.5 deg for a 10 deg lean on a pelvis turned by several degrees in all three
    planes. A wrong sign anywhere would cost 5-20 deg."""
    phase = np.linspace(0.0, 2 * math.pi, 60)
    pelvis = walking_pelvis(phase)
    frames = skeleton_with(lambda n: upper_body_motion(DEFAULTS, phase, np.full(n, math.radians(10.0)),
                                                       still_hips(n), pelvis), pelvis)
    head = frames.rotation("C1")
    up_tilt = np.degrees(np.arccos(np.clip(head[:, 1, 1], -1.0, 1.0)))
    gaze_yaw = np.degrees(np.arctan2(-head[:, 2, 0], head[:, 0, 0]))
    assert up_tilt.max() < 2.0 and np.abs(gaze_yaw).max() < 2.0


# --- argument checks -------------------------------------------------------------------------

@pytest.mark.parametrize("change,message", [
    ({"t": np.zeros((5, 1))}, "t:"),
    ({"trunk_lean": np.zeros(4)}, "trunk_lean"),
    ({"trunk_lean": np.array([0.0, np.nan, 0.0, 0.0, 0.0])}, "trunk_lean"),
    ({"hip_flexion": {"right": np.zeros(5)}}, "hip_flexion"),
    ({"hip_flexion": {"right": np.zeros(5), "left": np.zeros(6)}}, r"hip_flexion\['left'\]"),
    ({"pelvis_angles": np.zeros((5, 2))}, "pelvis_angles"),
    ({"pelvis_angles": np.full((5, 3), np.inf)}, "pelvis_angles"),
])
def test_upper_body_motion_refuses_bad_arguments_naming_them(change, message):
    arguments = {"t": np.zeros(5), "trunk_lean": np.zeros(5), "hip_flexion": still_hips(5),
                 "pelvis_angles": None, **change}
    with pytest.raises(ValueError, match=message):
        upper_body_motion(DEFAULTS, **arguments)
