"""The virtual leg (§4.2, figure 6; kinematics/virtual_leg.py): a human leg on the telescopic
stance leg, through its three foot periods, checked on real walks."""
import dataclasses
import math

import numpy as np
import pytest

from klaw_ocp.dynamics import foot_points
from klaw_ocp.kinematics.virtual_leg import HEEL_OFF, META_OFF, NORMAL, FlatFoot
from klaw_ocp.walk import simulate_walk

METHODS = ("multiple-shooting", "plain-shooting")
WALKS = {"5kmh": {"speed": 5.0, "steps": 4}, "2kmh-rest": {"speed": 2.0, "steps": 3, "start_from_rest": True},
         "8kmh": {"speed": 8.0, "steps": 3}}


@pytest.fixture(scope="module", params=[(m, w) for m in METHODS for w in WALKS],
                ids=[f"{m}-{w}" for m in METHODS for w in WALKS])
def legs(request):
    method, name = request.param
    walk = simulate_walk({"name": "v", "body": {"height": 1.8, "mass": 80}, "walk": WALKS[name]}, method=method)
    assert walk.status == "ok"
    frames = [walk.stance_leg_frames(k) for k in range(len(walk.steps))]
    # every stance leg but the last is completed by the next step's double support
    assert frames[-1] is None and all(f is not None for f in frames[:-1])
    return walk, frames[:-1]


def test_each_step_is_built_once_and_the_next_one_completes_its_stance_leg(legs):
    """A solved step is frozen. Its ``stance_foot`` holds the rules its own stance fixed (heel
    strike, foot flat, heel-off; no toe-off yet); the walk's ``stance_foot(k)`` is the next step's
    ``hind_foot``: the same rules, the double support's added to them, none of its own changed.
    The last step's stance leg is its own rules."""
    walk, _ = legs
    with pytest.raises(dataclasses.FrozenInstanceError):
        walk.steps[0].stance_foot = walk.steps[0].hind_foot
    own_fields = ("foot", "rocker_pitch", "rocker_theta6", "t_flat", "heel_off_theta5", "meta_off_theta6",
                  "t_step", "t_heel_off", "rocker_rate", "single_t", "single_deficit", "landing_knee")
    for k, step in enumerate(walk.steps):
        own, completed = step.stance_foot, walk.stance_foot(k)
        assert not own.complete
        if k + 1 == len(walk.steps):
            assert completed is own
            continue
        assert completed is walk.steps[k + 1].hind_foot and completed.complete
        assert all(getattr(completed, name) == getattr(own, name) for name in own_fields), k


def _distance(a, b):
    return np.hypot(*(a - b).T)


def test_the_leg_reaches_the_simulated_hip_with_its_own_segments(legs):
    """Forward kinematics from the ankle through θ4 and θ3 reproduces the simulated hip to 1e-9 m;
    thigh and shank keep l3 and l4; the leg never has to reach beyond its length."""
    walk, frames = legs
    body = walk.spec.body
    assert frames
    for f in frames:
        phi = f.theta3 + f.theta4
        knee = f.ankle + body.l4 * np.column_stack([np.sin(phi), np.cos(phi)])
        hip = knee + body.l3 * np.column_stack([np.sin(f.theta3), np.cos(f.theta3)])
        assert np.abs(hip - f.hip).max() <= 1e-9
        assert np.abs(_distance(f.knee, f.hip) - body.l3).max() <= 1e-12
        assert np.abs(_distance(f.ankle, f.knee) - body.l4).max() <= 1e-12
        assert f.overreach.max() <= 1e-12 and np.all(f.theta4 >= 0)


def test_each_period_turns_the_foot_about_its_pivot(legs):
    """Normal: about the heel until flat, then flat; heel-off: about the metatarsal head with the
    toe flat; meta-off (from the band where the toe joint stops following the pitch): about the toe
    tip. The pivot stays put to 1e-9 m; the periods come in that order and each stance has all
    three."""
    walk, frames = legs
    body = walk.spec.body
    for f in frames:
        order = [p for i, p in enumerate(f.period) if i == 0 or p != f.period[i - 1]]
        assert order == [NORMAL, HEEL_OFF, META_OFF]
        rocker = (f.period == NORMAL) & (f.pitch < 0)
        flat = (f.period == NORMAL) & (f.pitch == 0)
        standing = f.t[0] == 0 and f.pitch[0] == 0      # the first stance of a start from rest
        assert (standing or rocker.sum() >= 2) and flat.sum() >= 2
        for mask, point in ((rocker, f.heel), (flat, f.ankle), (flat, f.heel), (f.period == HEEL_OFF, f.metatarsal),
                            (f.period == HEEL_OFF, f.toe), (f.period == META_OFF, f.toe)):
            if mask.any():     # the standing start has no heel rocker
                assert np.abs(point[mask] - point[mask][0]).max() <= 1e-9
        assert np.abs(f.heel[rocker | flat, 1]).max() <= 1e-12           # the heel on the ground
        assert np.abs(f.toe[f.period != NORMAL, 1]).max() <= 1e-12      # the toe on the ground
        assert np.all(np.diff(f.pitch[f.period != NORMAL]) >= -1e-12)    # the heel never comes down again
        # the foot is rigid
        for a, b in (("heel", "ankle"), ("ankle", "metatarsal"), ("heel", "metatarsal")):
            d = _distance(getattr(f, a), getattr(f, b))
            assert np.ptp(d) <= 1e-12, (a, b)
        assert min(f.heel[:, 1].min(), f.toe[:, 1].min(), f.metatarsal[:, 1].min()) >= -1e-12
        assert _distance(f.ankle, f.metatarsal)[0] == pytest.approx(body.l12, abs=1e-12)


def test_the_angles_are_the_foot_models_angles(legs):
    """θ5 and θ6 as dynamics.foot_points defines them: the foot it builds from the ankle, the
    shank angle, θ5 and θ6 is the virtual leg's foot, at every sample."""
    walk, frames = legs
    body = walk.spec.body
    for f in frames:
        for i in range(len(f.t)):
            pts = foot_points(body, f.ankle[i], f.theta3[i] + f.theta4[i], f.theta5[i], f.theta6[i])
            for name in ("heel", "metatarsal", "toe"):
                assert pts[name] == pytest.approx(getattr(f, name)[i], abs=1e-9), (i, name)


def test_heel_strike_and_heel_off_follow_the_attributes(legs):
    """The leg lands on its heel, straight with the foot at θ5 = theta5_impact where the straight
    leg manages the hip's approach, else with the knee flexed by the landing's least angle
    (kinematics/landing.py; at 8 km/h); the heel comes off where θ5 reaches heel_off_theta5 (the
    knee then held, its heel leaving the ground over the blend, so the flat foot passes the limit by
    a fraction of a degree at most) or where the knee's schedule lifts it; meta-off as θ6 nears
    meta_off_theta6, which it reaches and then keeps."""
    walk, frames = legs
    attrs = walk.spec.attributes
    feet = [walk.stance_foot(k) for k in range(len(walk.steps) - 1)]
    assert len(feet) == len(frames) and all(foot.complete for foot in feet)
    for foot, f in zip(feet, frames):
        if f.pitch[0] == 0:
            continue      # a start from rest: the foot stands flat
        assert f.theta4[0] == pytest.approx(foot.landing_knee, abs=1e-6)
        assert f.heel[0] == pytest.approx([foot.foot.ankle_x - walk.spec.body.l8, 0.0], abs=1e-12)
        if foot.landing_knee == 0:
            # eq. 3 built the landing with Table B-1's l11; the foot's heel-ankle is sqrt(l8² + l9²),
            # equal to its 4 digits: 0.011° at 1.8 m
            assert math.degrees(f.theta5[0]) == pytest.approx(attrs.theta5_impact, abs=0.02)
        flat = (f.period == NORMAL) & (f.pitch == 0)
        assert np.all(np.degrees(f.theta5[flat]) <= attrs.heel_off_theta5 + 1.0)
        meta = f.period == META_OFF
        assert np.all(np.degrees(f.theta6[meta]) <= attrs.meta_off_theta6 + 1e-9)
        assert np.degrees(f.theta6[meta][-1]) == pytest.approx(attrs.meta_off_theta6, abs=1e-9)
        assert np.all(np.diff(f.theta6[meta]) >= -1e-12)
        heel_off = f.period == HEEL_OFF
        assert np.degrees(f.theta6[heel_off]) == pytest.approx(np.degrees(f.pitch[heel_off]), abs=1e-9)


def test_a_flat_foot_has_its_table_b1_points():
    foot = FlatFoot(_body(), 0.3)
    pose = foot.pose(np.zeros(1), math.radians(30))
    assert pose["ankle"][0] == pytest.approx([0.3, foot.body.l9])
    assert pose["heel"][0] == pytest.approx([0.3 - foot.body.l8, 0.0])
    assert pose["toe"][0, 1] == 0.0 and pose["metatarsal"][0, 1] == 0.0


def _body():
    from klaw_ocp.body import Body
    return Body(1.8, 80)


@pytest.mark.parametrize("walk_kind", ["5kmh", "2kmh-rest"])
def test_events_have_every_heel_strike_and_toe_off_of_both_legs(walk_kind):
    """events.csv's rows (results.foot_events): heel strikes alternate, the right leg first; each
    toe-off is t_ds after the other leg's heel strike; every stance has its foot-flat and heel-off
    between its heel strike and its toe-off; times in order."""
    from klaw_ocp.result_files.tables import events_csv
    from klaw_ocp.results import walk_summary
    walk = simulate_walk({"name": "e", "body": {"height": 1.8, "mass": 80}, "walk": WALKS[walk_kind]})
    rows = [line.split(",") for line in events_csv(walk_summary(walk)).splitlines()]
    assert rows[0] == ["time", "side", "event"]
    events = [(float(t), side, name) for t, side, name in rows[1:]]
    assert [t for t, _, _ in events] == sorted(t for t, _, _ in events)
    strikes = [(t, side) for t, side, name in events if name == "heel_strike"]
    rest = walk.spec.start_from_rest
    assert [side for _, side in strikes] == [("right", "left")[(i + rest) % 2] for i in range(len(strikes))]
    assert len(strikes) == len(walk.steps) - rest
    for step in walk.steps:
        toe_off = [t for t, side, name in events if name == "toe_off"
                   and abs(t - step.t_start - step.plan.timings.t_ds) < 1e-12]
        assert len(toe_off) == 1
    for step in walk.steps[:-1]:         # stances that end inside the walk
        side = "right" if step.index % 2 == 0 else "left"
        t_end = step.t_start + step.plan.timings.t_step + walk.steps[step.index + 1].plan.timings.t_ds
        inside = [name for t, s, name in events if s == side and step.t_start - 1e-12 <= t <= t_end + 1e-12]
        assert inside[-1] == "toe_off" and "foot_flat" in inside and "heel_off" in inside
        assert inside.index("foot_flat") < inside.index("heel_off") < inside.index("toe_off")


def test_the_knee_keeps_its_schedule_once_the_heel_is_off(legs):
    """Once the heel is clear of its blend the stance knee is the schedule's (kinematics/pitch_rules.py):
    nearly straight in terminal stance, then flexing to toe_off_knee_flexion at toe-off; it is never
    straighter than the schedule while the heel is up."""
    walk, frames = legs
    feet = [walk.stance_foot(k) for k in range(len(walk.steps) - 1)]
    for foot, f in zip(feet, frames):
        schedule = foot.knee_schedule(f.t)
        up = f.pitch > 0
        assert np.all(f.theta4[up] >= schedule[up] - 1e-9)
        assert f.theta4[-1] == pytest.approx(foot.knee_toe_off, abs=1e-6)         # at toe-off
        knee = foot.knee_schedule(np.array([foot.t_knee, foot.t_toe_off]))
        # the floor in terminal stance, or the knee held where θ5's limit lifted the heel first
        assert knee[0] == pytest.approx(max(foot.knee_floor, foot.knee_hold), abs=0.05)
        assert knee[1] == pytest.approx(max(foot.knee_toe_off, foot.knee_hold))
