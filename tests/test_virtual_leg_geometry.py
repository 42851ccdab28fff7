"""The virtual leg's geometry (kinematics/virtual_leg.py) held against independently rebuilt
geometry, without a walk: the foot's periods (heel-up about the metatarsal head with the toe flat,
then, through a C1 band about meta-off, about the toe tip), the two-link inverse kinematics, the
reach pitch, the knee's schedule in the double support, the toe-off pitch and the ankle angle."""
import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import example, given, settings, strategies as st

from klaw_ocp.body import Body
from klaw_ocp.dynamics.points import foot_points_float
from klaw_ocp.gait.attributes import LocomotionAttributes
from klaw_ocp.kinematics.leg_geometry import knee_flexion_for_reach, reach_for_knee_flexion
from klaw_ocp.kinematics.pitch_rules import REACH_FRACTION
from klaw_ocp.kinematics.virtual_leg import (MIN_SWING1_THIGH_TRAVEL, FlatFoot, StanceFoot, ankle_angle,
                                             hind_foot_at_rest, leg_ik, toe_off_pitch)

BODY = Body(1.8, 80)
ATTRS = LocomotionAttributes.defaults()
Q = math.radians(ATTRS.meta_off_theta6)              # meta-off: the toe angle's limit
OFF = math.sqrt(BODY.l12 ** 2 - BODY.l9 ** 2)        # flat foot: metatarsal head (OFF, -l9) from the ankle
ANKLE_X = 0.3
M_X = ANKLE_X + OFF                                  # the metatarsal head on the ground
FAST = settings(max_examples=60, deadline=None)


def unit(angle):
    """(sin a, cos a): a segment at angle a from the vertical (the swing model's convention)."""
    return np.array([math.sin(angle), math.cos(angle)])


def clockwise(v, a):
    return np.array([v[0] * math.cos(a) + v[1] * math.sin(a), -v[0] * math.sin(a) + v[1] * math.cos(a)])


BAND = math.radians(12.0)                            # the meta-off blend's half width (q/2 at most)


def toe_joint(p, q=Q):
    """θ6 of the heel-up foot: the pitch, then held at q, joined by a parabola over q ± BAND whose
    slope runs from 1 to 0 (rebuilt here from that description)."""
    w = min(BAND, q / 2)
    if p <= q - w:
        return p
    if p >= q + w:
        return q
    return p - (p - q + w) ** 2 / (4 * w)


def pitched(p, ankle_x=ANKLE_X, body=BODY, q=Q):
    """Heel, ankle, metatarsal head, toe tip of a foot with its heel raised by pitch p >= 0: the
    toe tip on the ground, the toe segment turned up by p - θ6 about it, the rest of the foot
    turned clockwise by p about the metatarsal head, wherever the toe segment puts the head."""
    off = math.sqrt(body.l12 ** 2 - body.l9 ** 2)
    head, ankle = np.array([ankle_x + off, 0.0]), np.array([ankle_x, body.l9])
    toe = head + np.array([body.l13, 0.0])
    rise = p - toe_joint(p, q)
    new_head = toe + body.l13 * np.array([-math.cos(rise), math.sin(rise)])
    rest = {"heel": np.array([ankle_x - body.l8, 0.0]), "ankle": ankle, "metatarsal": head}
    out = {k: new_head + clockwise(v - head, p) for k, v in rest.items()}
    out["toe"] = toe
    return out


def standing_foot(ankle_x=ANKLE_X):
    return StanceFoot.standing(BODY, ATTRS, ankle_x, 0.5)


def one(pose, name):
    return pose[name][0]


# -- the foot ------------------------------------------------------------------------------------

def test_the_metatarsal_head_is_l12_from_the_flat_ankle():
    foot = FlatFoot(BODY, ANKLE_X)
    assert math.hypot(*(foot.metatarsal - foot.ankle)) == pytest.approx(BODY.l12, rel=1e-12)
    assert foot.metatarsal[1] == 0.0 and foot.metatarsal[0] > ANKLE_X          # on the ground, ahead
    assert foot.toe == pytest.approx([foot.metatarsal[0] + BODY.l13, 0.0], abs=1e-15)
    pose = foot.pose(np.zeros(1), Q)
    for name, point in pitched(0.0).items():
        assert one(pose, name) == pytest.approx(point, abs=1e-15), name
    assert pose["theta6"][0] == 0.0 and pose["sole"][0] == 0.0


@FAST
@given(p=st.floats(0.0, Q - BAND))
@example(p=Q - BAND)
def test_heel_up_about_the_metatarsal_head_keeps_head_and_toe_down_and_the_toe_flat(p):
    pose = FlatFoot(BODY, ANKLE_X).pose(np.array([p]), Q)
    assert one(pose, "metatarsal") == pytest.approx([M_X, 0.0], abs=1e-15)
    assert one(pose, "toe") == pytest.approx([M_X + BODY.l13, 0.0], abs=1e-15)
    assert pose["theta6"][0] == p and pose["sole"][0] == -p                    # toe flat: theta6 = pitch
    for name, point in pitched(p).items():
        assert one(pose, name) == pytest.approx(point, abs=1e-12), name
    assert one(pose, "heel")[1] == pytest.approx((BODY.l8 + OFF) * math.sin(p), abs=1e-12)
    assert math.hypot(*(one(pose, "ankle") - one(pose, "metatarsal"))) == pytest.approx(BODY.l12, rel=1e-12)


@FAST
@given(p=st.floats(Q + BAND, 1.5))
def test_beyond_meta_off_the_foot_turns_about_the_toe_tip_with_theta6_held(p):
    pose = FlatFoot(BODY, ANKLE_X).pose(np.array([p]), Q)
    toe = np.array([M_X + BODY.l13, 0.0])
    assert one(pose, "toe") == pytest.approx(toe, abs=1e-15)
    assert pose["theta6"][0] == Q and pose["sole"][0] == -p
    head = one(pose, "metatarsal")
    assert head == pytest.approx(toe + BODY.l13 * np.array([-math.cos(p - Q), math.sin(p - Q)]), abs=1e-12)
    for name, point in pitched(p).items():
        assert one(pose, name) == pytest.approx(point, abs=1e-12), name


@FAST
@given(p=st.floats(Q - BAND, Q + BAND))
def test_about_meta_off_the_pivot_passes_from_the_head_to_the_toe_tip_with_a_continuous_rate(p):
    """In the band θ6 stops following the pitch with a continuous slope; the toe tip stays down,
    the foot keeps its shape, and the ankle's path has no corner (its direction turns smoothly
    from the circle about the head to the circle about the toe tip)."""
    foot = FlatFoot(BODY, ANKLE_X)
    pose = foot.pose(np.array([p]), Q)
    assert one(pose, "toe") == pytest.approx([M_X + BODY.l13, 0.0], abs=1e-15)
    assert pose["theta6"][0] == pytest.approx(toe_joint(p), abs=1e-15)
    for name, point in pitched(p).items():
        assert one(pose, name) == pytest.approx(point, abs=1e-12), name
    assert math.hypot(*(one(pose, "ankle") - one(pose, "metatarsal"))) == pytest.approx(BODY.l12, rel=1e-12)
    h = 1e-6
    ankles = foot.pose(np.array([p - h, p, p + h]), Q)["ankle"]
    left, right = (ankles[1] - ankles[0]) / h, (ankles[2] - ankles[1]) / h
    assert np.linalg.norm(right - left) < 1e-4
    at = lambda x: foot.pose(np.array([x]), Q)["ankle"][0]
    for edge in (Q - BAND, Q + BAND):         # the band's ends: the rigid motions' rates meet
        left, right = (at(edge) - at(edge - h)) / h, (at(edge + h) - at(edge)) / h
        assert np.linalg.norm(right - left) < 1e-4


# -- the leg's inverse kinematics ----------------------------------------------------------------

def forward(body, hip, theta3, theta4):
    knee = hip - body.l3 * unit(theta3)
    return knee, knee - body.l4 * unit(theta3 + theta4)


@FAST
@given(rel=st.floats(0.2, 1.0), beta=st.floats(-1.2, 1.2), hx=st.floats(-1, 1), hy=st.floats(0.5, 1.2))
@example(rel=1.0, beta=0.3, hx=0.2, hy=0.9)
def test_leg_ik_puts_the_knee_l3_from_the_hip_and_the_ankle_l4_from_the_knee(rel, beta, hx, hy):
    hip = np.array([hx, hy])
    ankle = hip - rel * BODY.l1 * unit(beta)
    th3, th4, knee = leg_ik(BODY, hip[None], ankle[None])
    k, a = forward(BODY, hip, th3[0], th4[0])
    assert k == pytest.approx(knee[0], abs=1e-14)
    assert a == pytest.approx(ankle, abs=1e-12)
    assert np.linalg.norm(knee[0] - hip) == pytest.approx(BODY.l3, abs=1e-12)
    assert np.linalg.norm(ankle - knee[0]) == pytest.approx(BODY.l4, abs=1e-12)
    assert th4[0] >= 0                                                    # never hyperextended
    if rel < 1 - 1e-6:     # knee forward of the hip-ankle line (hip->ankle x hip->knee)
        d, kk = ankle - hip, knee[0] - hip
        assert d[0] * kk[1] - d[1] * kk[0] > 0 and th4[0] > 0


def test_leg_ik_is_well_conditioned_at_the_straight_knee():
    """At d = l1 exactly the cosine law's arccos loses half the digits (1e-8 m); the leg is exact."""
    hips = np.array([[0.0, 0.9], [0.1, 0.95], [-0.2, 0.85], [0.4, 1.0]])
    betas = np.array([0.0, 0.3, -0.4, 0.7])
    ankles = hips - BODY.l1 * np.column_stack([np.sin(betas), np.cos(betas)])
    th3, th4, knee = leg_ik(BODY, hips, ankles)
    for i in range(len(hips)):
        k, a = forward(BODY, hips[i], th3[i], th4[i])
        assert np.linalg.norm(a - ankles[i]) < 1e-12
        assert np.linalg.norm(k - knee[i]) < 1e-12
        assert th3[i] == pytest.approx(betas[i], abs=1e-7) and th4[i] == pytest.approx(0.0, abs=1e-7)


def test_the_reach_fraction_bends_the_knee_about_ten_degrees():
    hip = np.array([[0.0, 0.9]])
    ankle = hip - REACH_FRACTION * BODY.l1 * unit(0.2)
    th4 = leg_ik(BODY, hip, ankle)[1][0]
    # the cosine law at the knee, independently: d^2 = l3^2 + l4^2 + 2 l3 l4 cos(theta4)
    d = REACH_FRACTION * BODY.l1
    assert math.cos(th4) == pytest.approx((d ** 2 - BODY.l3 ** 2 - BODY.l4 ** 2) / (2 * BODY.l3 * BODY.l4))
    assert math.degrees(th4) == pytest.approx(10.25, abs=0.1)
    assert float(knee_flexion_for_reach(BODY, d)) == pytest.approx(th4, abs=1e-9)
    assert float(reach_for_knee_flexion(BODY, th4)) == pytest.approx(d, rel=1e-12)


# -- the reach pitch -----------------------------------------------------------------------------

def gap(p, hip, fraction):
    return np.linalg.norm(pitched(p)["ankle"] - hip) - fraction * BODY.l1


# hips from the metatarsal head: (distance / l1, angle from the vertical, reach fraction)
HIPS = st.lists(st.tuples(st.floats(0.85, 1.27), st.floats(-1.1, 0.8), st.floats(REACH_FRACTION, 1.0)),
                min_size=1, max_size=6)


@FAST
@given(hips=HIPS)
@example(hips=[(0.9, 0.3, 1.0), (1.09, 0.1, REACH_FRACTION), (1.22, 0.0, 1.0),   # flat, heel-off, meta-off
               (1.18, -0.86, 1.0), (1.15, 0.0, 1.0)])   # behind the foot; in the meta-off band
def test_reach_pitch_is_the_smallest_pitch_that_reaches(hips):
    xy = np.array([[M_X + r * BODY.l1 * math.sin(a), r * BODY.l1 * math.cos(a)] for r, a, _ in hips])
    fractions = np.array([f for *_, f in hips])
    pitches = standing_foot().reach_pitch(xy, fractions)
    for p, hip, fraction in zip(pitches, xy, fractions):
        if p == 0.0:
            assert gap(0.0, hip, fraction) <= 0
            continue
        if p == math.radians(89):                                   # out of reach at any pitch
            assert all(gap(q, hip, fraction) > 0 for q in np.linspace(0.0, p, 90))
            continue
        assert 0 < p < math.radians(89)
        assert gap(p, hip, fraction) == pytest.approx(0.0, abs=1e-10)
        assert gap(p - 1e-6, hip, fraction) > 0                  # any less pitch leaves the ankle out of reach
        assert all(gap(q, hip, fraction) > 0 for q in np.linspace(0.0, p - 1e-6, 40))


def test_reach_pitch_covers_both_pivots():
    """The example hips of the test above: one reaches flat, one about the head, one about the toe,
    one in the meta-off band between them."""
    xy = np.array([[M_X, 0.9 * BODY.l1], [M_X + 1.09 * BODY.l1 * math.sin(0.1), 1.09 * BODY.l1 * math.cos(0.1)],
                   [M_X, 1.22 * BODY.l1], [M_X, 1.15 * BODY.l1]])
    p = standing_foot().reach_pitch(xy, np.array([1.0, REACH_FRACTION, 1.0, 1.0]))
    assert p[0] == 0.0 and 0 < p[1] <= Q - BAND and Q + BAND < p[2] < math.radians(89)
    assert Q - BAND < p[3] < Q + BAND and gap(p[3], xy[3], 1.0) == pytest.approx(0.0, abs=1e-10)


# -- the double support's pitch ------------------------------------------------------------------

def check_leg(hip, leg, i):
    """The leg rebuilt from its angles: thigh l3, shank l4, its ankle on the pitched foot."""
    knee, ankle = forward(BODY, hip, leg.theta3[i], leg.theta4[i])
    assert ankle == pytest.approx(leg.ankle[i], abs=1e-9)
    assert ankle == pytest.approx(pitched(leg.pitch[i])["ankle"], abs=1e-9)
    assert leg.theta4[i] >= 0 and leg.overreach[i] <= 1e-12          # straight at most, never beyond
    a, k = ankle - hip, knee - hip
    assert a[0] * k[1] - a[1] * k[0] > (0 if leg.theta4[i] > 1e-6 else -1e-12)   # knee forward


def test_from_rest_the_double_support_flexes_the_knee_on_its_schedule_from_straight():
    """A standing hind foot's knee schedule starts at rest, straight: κ_to s² over the double
    support. The heel stays down while the flat foot keeps the knee above it, then rises by the
    least pitch that keeps the knee on it; the pitch never falls."""
    hip = np.array([M_X + 0.05 * 1.8, 0.47 * 1.8])   # nearly over the head: the flat foot reaches
    foot = hind_foot_at_rest(BODY, ATTRS, ANKLE_X)
    assert foot.reach_pitch(hip[None])[0] == 0.0
    foot = foot.with_double_support(hip, 0.12, 0.6)
    t = np.linspace(0.0, 0.12, 13)
    leg = foot.frames(t, np.tile(hip, (len(t), 1)))
    schedule = math.radians(ATTRS.toe_off_knee_flexion) * (t / 0.12) ** 2
    flat = knee_flexion_for_reach(BODY, np.linalg.norm(pitched(0.0)["ankle"] - hip))
    assert leg.pitch[0] == 0.0 and np.all(np.diff(leg.pitch) >= 0)
    for i in range(len(t)):
        check_leg(hip, leg, i)
        if leg.pitch[i] == 0:
            assert flat >= schedule[i] - 1e-9
        else:
            assert leg.theta4[i] == pytest.approx(schedule[i], abs=1e-9)


@FAST
@given(dist=st.floats(0.75, 1.1), lean=st.floats(-0.1, 0.7), t=st.floats(0.0, 0.15))
def test_the_double_support_reaches_any_hip(dist, lean, t):
    """A walking leg in its double support: the knee on its schedule wherever the heel is clear
    of its blend, never straighter than it, and a leg of its own segments throughout."""
    hip = np.array([M_X, 0.0]) + dist * BODY.l1 * unit(lean)
    foot = hind_foot_at_rest(BODY, ATTRS, ANKLE_X, from_rest=False, t_cycle=1.1, t_ds=0.1)
    foot = foot.with_double_support(hip, 0.1, 0.0)
    leg = foot.frames(np.array([t]), hip[None])
    check_leg(hip, leg, 0)
    schedule = float(foot.knee_schedule(np.array([t]))[0])
    flat = float(np.linalg.norm(pitched(0.0)["ankle"] - hip))
    if leg.pitch[0] == 0:
        assert flat <= float(reach_for_knee_flexion(BODY, schedule)) - foot.heel_blend + 1e-12
    elif leg.pitch[0] < math.radians(89):
        assert leg.theta4[0] >= schedule - 1e-9
        if flat >= float(reach_for_knee_flexion(BODY, schedule)) + foot.heel_blend:
            assert leg.theta4[0] == pytest.approx(schedule, abs=1e-9)


def test_toe_off_pitch_keeps_the_attribute_in_steady_walking():
    foot, hip = standing_foot(), np.array([M_X + 0.35, 0.9])
    knee = math.radians(ATTRS.toe_off_knee_flexion)
    wanted = float(foot.reach_pitch(hip[None], reach_for_knee_flexion(BODY, knee) / BODY.l1)[0])
    start = float(foot.reach_pitch(hip[None], REACH_FRACTION)[0])
    assert 0 < start < wanted
    assert toe_off_pitch(foot, hip, start, wanted, -0.35) == wanted
    theta4 = leg_ik(BODY, hip[None], pitched(wanted)["ankle"][None])[1][0]
    assert theta4 == pytest.approx(knee, abs=1e-9)


def test_toe_off_pitch_from_standing_stops_the_thigh_at_its_bound():
    foot, hip = standing_foot(), np.array([M_X, 0.9])
    wanted, theta3_hs = math.radians(45), -0.3
    assert MIN_SWING1_THIGH_TRAVEL == 0.15                           # docs/paper-map.md
    pitch = toe_off_pitch(foot, hip, 0.0, wanted, theta3_hs)
    assert 0.0 < pitch < wanted                                      # heel raised, but less than asked
    theta3 = leg_ik(BODY, hip[None], pitched(pitch)["ankle"][None])[0][0]
    assert theta3 == pytest.approx(theta3_hs + MIN_SWING1_THIGH_TRAVEL, abs=1e-9)
    assert leg_ik(BODY, hip[None], pitched(wanted)["ankle"][None])[0][0] < theta3   # the attribute: ahead
    # a thigh already ahead of its bound at the lowest pitch: the heel stays where it starts
    assert toe_off_pitch(foot, hip, 0.05, wanted, 0.0) == 0.05


# -- the ankle angle -----------------------------------------------------------------------------

@FAST
@given(theta3=st.floats(-0.8, 0.8), lean=st.floats(-0.6, 1.0))
@example(theta3=-0.2, lean=0.0)
def test_ankle_angle_of_a_flat_foot_is_ninety_degrees_plus_the_shank_lean(theta3, lean):
    theta5 = ankle_angle(np.array([theta3]), np.array([lean - theta3]), np.zeros(1))[0]
    assert math.degrees(theta5) == pytest.approx(90 + math.degrees(lean), abs=1e-9)


@FAST
@given(shank=st.floats(-1.0, 1.0), theta3=st.floats(-0.8, 0.8), p=st.floats(0.0, 1.4))
def test_ankle_angle_is_the_foot_models_angle_of_the_pitched_foot(shank, theta3, p):
    """The dynamics' foot model, given θ5 and θ6 of a pitched foot, builds that foot."""
    pose = FlatFoot(BODY, ANKLE_X).pose(np.array([p]), Q)
    theta5 = ankle_angle(np.array([theta3]), np.array([shank - theta3]), pose["sole"])[0]
    assert math.remainder(theta5 - (math.pi / 2 + shank - p), 2 * math.pi) == pytest.approx(0.0, abs=1e-12)
    points = foot_points_float(*one(pose, "ankle"), shank, theta5, pose["theta6"][0],
                               BODY.l8, BODY.l9, BODY.l12, BODY.l13)
    for name, point in zip(("heel", "metatarsal", "toe"), points):
        assert point == pytest.approx(pitched(p)[name], abs=1e-12), name
