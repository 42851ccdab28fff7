"""The pelvis's second hip (§4.2, issue #35; kinematics/pelvis.py): rotation and list about the
stance hip with the paper's timing, the swing leg hanging from the other hip in its equations of
motion, eq. 3 splitting the step by the rotation, the heel-strike map passing the stance model's
hip to the landing leg's hip, and the body's skeleton putting the hips where the dynamics had them."""
import math

import numpy as np
import pytest

from klaw_ocp.body import Body
from klaw_ocp.body_motion import body_motion
from klaw_ocp.control.swing_law import SWING_FORCES
from klaw_ocp.body_motion.skeleton import ANGLE_NAMES, JOINTS, forward_kinematics
from klaw_ocp.dynamics import heel_strike_map, stance_hip
from klaw_ocp.gait import LocomotionAttributes, stance_leg
from klaw_ocp.gait.symmetry import landing_heel, step_constraints
from klaw_ocp.kinematics.pelvis import PelvisSchedule
from klaw_ocp.walk import simulate_walk

COL = {name: i for i, name in enumerate(ANGLE_NAMES)}
JOINT = {j.name: i for i, j in enumerate(JOINTS)}


def _config(list_deg=5.0, rotation_deg=4.0, steps=6, **walk):
    return {"name": "pelvis", "body": {"height": 1.8, "mass": 80},
            "walk": {"speed": 5.0, "steps": steps, **walk},
            "attributes": {"pelvic_list": list_deg, "pelvic_rotation": rotation_deg}}


# -- the schedule ------------------------------------------------------------------------------

def test_schedule_has_the_papers_timing_and_its_derivatives_are_exact():
    """Rotation largest at heel strike, 0 at mid-step; list 0 at heel strike, largest at mid-step;
    both with zero rate at heel strike; the offset's rates are its derivatives."""
    p = PelvisSchedule(width=0.18, rotation_start=math.radians(4), rotation_end=math.radians(4),
                       list_peak=math.radians(5), t_step=0.55)
    rotation, lowered = p.angles(np.array([0.0, 0.275, 0.55]))
    np.testing.assert_allclose(rotation, [math.radians(4), 0.0, -math.radians(4)], atol=1e-15)
    np.testing.assert_allclose(lowered, [0.0, math.radians(5), 0.0], atol=1e-15)
    t, h = np.linspace(0.0, 0.55, 23), 1e-6
    (x, y), (vx, vy), (ax, ay) = p.swing_hip_offset(t)
    (x1, y1), (vx1, vy1), _ = p.swing_hip_offset(t + h)
    (x0, y0), (vx0, vy0), _ = p.swing_hip_offset(t - h)
    np.testing.assert_allclose(vx, (x1 - x0) / (2 * h), atol=1e-8)
    np.testing.assert_allclose(vy, (y1 - y0) / (2 * h), atol=1e-8)
    np.testing.assert_allclose(ax, (vx1 - vx0) / (2 * h), atol=1e-6)
    np.testing.assert_allclose(ay, (vy1 - vy0) / (2 * h), atol=1e-6)
    np.testing.assert_allclose([vx[0], vy[0], vx[-1], vy[-1]], 0.0, atol=1e-15)
    # at heel strike the hips are level, the landing one l0 sin(rotation) ahead; at mid-step the
    # swing side is l0 sin(list) below
    assert x[0] == pytest.approx(-0.18 * math.sin(math.radians(4))) and y[0] == pytest.approx(0.0, abs=1e-15)
    assert x[-1] == pytest.approx(0.18 * math.sin(math.radians(4)))
    assert y[11] == pytest.approx(-0.18 * math.sin(math.radians(5)))


# -- eq. 3 and the heel-strike map --------------------------------------------------------------

def test_eq3_splits_the_step_by_the_pelvis_and_lands_the_heel_where_it_says():
    body = Body(1.8, 80.0)
    attrs = LocomotionAttributes.defaults()
    plain = step_constraints(body, 0.775, attrs, ankle_x=1.0)
    shift = body.l0 * math.sin(math.radians(4))
    turned = step_constraints(body, 0.775, attrs, ankle_x=1.0, hip_shift=shift)
    assert plain.hip_shift == 0.0 and turned.hip_shift == pytest.approx(shift)
    # each leg spans (sl - shift)/2: the stance hip is that far ahead of its ankle ...
    assert turned.hip_x - turned.ankle_x == pytest.approx((0.775 - shift) / 2, abs=1e-15)
    assert turned.w * math.sin(turned.theta1) == pytest.approx((0.775 - shift) / 2, abs=1e-15)
    # ... and the rotation lengthens the step without lowering the hip (the first determinant)
    assert turned.hip_y > plain.hip_y + 1e-3
    assert turned.theta1 < plain.theta1 and abs(turned.theta3) < abs(plain.theta3)
    # the landing leg, from the other hip, puts its heel on the ground at the planned point
    heel = landing_heel(body, turned)
    assert heel == pytest.approx((turned.heel_x, 0.0), abs=1e-12)
    # a closing step's feet end side by side: no rotation there
    assert step_constraints(body, 0.0, attrs, ankle_x=1.0, closing=True, hip_shift=shift).hip_shift == 0.0


def test_heel_strike_map_hands_the_stance_to_the_landing_hip_with_the_same_velocity():
    body = Body(1.8, 80.0)
    x_pre = np.array([0.93, 0.42, 0.05, -0.2, -1.6, 0.3])
    ankle, new_ankle, shift = np.array([0.0, body.l9]), np.array([0.775, body.l9]), np.array([0.0126, 0.0])
    post = heel_strike_map(body, x_pre, new_ankle - ankle, hip_shift=shift)
    hip_pre, vel_pre = stance_hip(body, x_pre, ankle)
    hip_post, vel_post = stance_hip(body, post, new_ankle)
    np.testing.assert_allclose(hip_post, hip_pre + shift, atol=1e-14)
    np.testing.assert_allclose(vel_post, vel_pre, atol=1e-13)
    np.testing.assert_array_equal(post[[2, 5]], x_pre[[2, 5]])


# -- the walk ---------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def natural():
    walk = simulate_walk(_config(), method="multiple-shooting")
    return walk, body_motion(walk, 500.0)


def test_the_next_stance_starts_from_the_landing_legs_hip(natural):
    """The stance model's hip passes to the pelvis's other hip at heel strike: where the swing's
    hip was at the end of step k, the stance hip of step k + 1 starts."""
    walk, _ = natural
    for prev, step in zip(walk.steps[:-1], walk.steps[1:]):
        end = prev.stance_hips[-1] + np.array([prev.pelvis.landing_shift, 0.0])
        np.testing.assert_allclose(step.stance_hips[0], end, atol=1e-9)
        assert prev.pelvis.rotation_end == pytest.approx(step.pelvis.rotation_start)


def test_the_body_puts_the_pelvis_angles_and_hips_where_the_dynamics_had_them(natural):
    """angles.csv's pelvis_list and pelvis_rotation reach the attributes at the paper's instants,
    and through the skeleton's own forward kinematics the swing-side hip sits l0 sin(list) below
    the stance hip at mid-step (2 mm)."""
    walk, motion = natural
    body = walk.spec.body
    deg = np.degrees(motion.angles)
    frames = forward_kinematics(body, motion.root, motion.angles)
    checked = 0
    for step in walk.steps[1:-1]:
        sign = 1.0 if stance_leg(step.index) == "right" else -1.0
        other = "l" if sign > 0 else "r"
        own = "r" if sign > 0 else "l"
        mid = int(round((step.t_start + step.plan.timings.t_step / 2) * 500.0))
        strike = int(round(step.t_start * 500.0))
        if abs(motion.t[mid] - step.t_start - step.plan.timings.t_step / 2) > 1e-3:
            continue
        assert sign * deg[mid, COL["pelvis_list"]] == pytest.approx(5.0, abs=0.05)
        assert deg[mid, COL["pelvis_rotation"]] == pytest.approx(0.0, abs=0.3)
        assert abs(deg[strike, COL["pelvis_rotation"]]) == pytest.approx(4.0, abs=0.05)
        assert deg[strike, COL["pelvis_list"]] == pytest.approx(0.0, abs=0.05)
        hip = lambda s: frames.positions[mid, JOINT[f"{s}_hip"]]
        drop = hip(own)[1] - hip(other)[1]
        assert drop == pytest.approx(body.l0 * math.sin(math.radians(5.0)), abs=2e-3)
        checked += 1
    assert checked >= 3


def test_the_hips_move_continuously_through_heel_strikes(natural):
    """Each hip of the pelvis and the pelvis centre move continuously where the legs trade roles
    (no frame-to-frame step much beyond the walk's speed)."""
    walk, motion = natural
    speed = 5.0 / 3.6
    for points in [motion.root] + [motion.legs[side].hip for side in ("right", "left")]:
        step = np.linalg.norm(np.diff(points, axis=0), axis=1)
        assert step.max() < 2.0 * speed / 500.0


def test_an_accentuated_list_lowers_the_swing_hip_and_changes_the_swing_torques():
    """§2.4: 'the kinematic pelvic rotation can actually lower the hip during the swing phase, which
    might force the dynamic leg to increase its hip torque to avoid stubbing its toe'. From list 5
    to 12 deg the swing's torque parameters change and the swing hip torque's peak grows."""
    natural = simulate_walk(_config(steps=4), method="multiple-shooting")
    steep = simulate_walk(_config(list_deg=12.0, steps=4), method="multiple-shooting")
    k = 2
    for name in ("swing1", "swing2", "swing3"):
        a, b = natural.steps[k].subphase(name).parameters, steep.steps[k].subphase(name).parameters
        assert any(abs(a[p] - b[p]) > 1e-6 * max(1.0, abs(a[p])) for p in a), name
    peak = lambda w: max(float(np.abs(s.forces[:, SWING_FORCES.index("F_theta3")]).max()) for s in w.steps[k].subphases[1:])
    assert peak(steep) > peak(natural)


@pytest.mark.parametrize("method", ["multiple-shooting", "plain-shooting"])
def test_list_12_rotation_10_walks_with_feet_planted_and_above_ground(method):
    """Issue #35's acceptance walk: list 12, rotation 10, from rest to rest; both solver modes."""
    walk = simulate_walk(_config(12.0, 10.0, steps=5, start_from_rest=True, end_at_rest=True), method=method)
    assert walk.status == "ok"
    motion = body_motion(walk, 200.0)
    for side in ("right", "left"):
        for name in ("heel", "toe", "metatarsal"):
            # the body's tolerance for a foot on the ground (tests/test_body_motion.py's PLANTED_M)
            assert getattr(motion.legs[side], name)[:, 1].min() > -1e-3, (side, name)
    # a planted foot does not slide: from foot flat to toe-off its toe tip stays where it is
    for step in walk.steps[:-1]:
        foot, side = walk.stance_foot(step.index), stance_leg(step.index)
        rows = (motion.t >= step.t_start + foot.t_flat) & (motion.t <= step.t_start + foot.t_toe_off)
        toe = motion.legs[side].toe[rows]
        assert np.ptp(toe[:, 0]) < 1e-3 and np.ptp(toe[:, 2]) < 1e-3, (step.index, side)


def test_the_trunk_compensates_so_the_head_stays_level_and_faces_forward(natural):
    """Principle 3: the spine bends against the list and counter-rotates against the rotation, so
    the head's lateral axis stays horizontal and its face forward (within 0.5 deg), while the
    shoulder line turns against the pelvis."""
    walk, motion = natural
    frames = forward_kinematics(walk.spec.body, motion.root, motion.angles)
    head = frames.rotations[:, JOINT["C1"]]
    lateral = head[:, :, 2]                                   # the head's z axis in the world
    assert np.degrees(np.abs(np.arcsin(lateral[:, 1]))).max() < 0.5        # no roll
    assert np.degrees(np.abs(np.arctan2(lateral[:, 0], lateral[:, 2]))).max() < 0.5   # no yaw
    shoulders = frames.positions[:, JOINT["r_shoulder"]] - frames.positions[:, JOINT["l_shoulder"]]
    hips = frames.positions[:, JOINT["r_hip"]] - frames.positions[:, JOINT["l_hip"]]
    yaw = lambda v: np.degrees(np.arctan2(v[:, 0], v[:, 2]))
    moving = np.abs(yaw(hips)) > 2.0
    assert np.all(np.sign(yaw(shoulders)[moving]) == -np.sign(yaw(hips)[moving]))
