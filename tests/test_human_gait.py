"""The human-likeness figures and the gait profile score (klaw_ocp.human_gait, docs/human-gait.md)."""
import math

import numpy as np
import pytest

from klaw_ocp.body import Body
from klaw_ocp.human_gait import (CYCLE_PERCENT, GPS_VARIABLES, dimensionless_speed, normative_curves,
                                 normative_table)


def test_the_normative_table_has_five_speed_classes_of_whole_cycles():
    table = normative_table()
    assert list(table) == ["VerySlow", "Slow", "Free", "Fast", "VeryFast"]
    speeds = [c["v_star"] for c in table.values()]
    assert speeds == sorted(speeds)
    for c in table.values():
        for column in ("pelvic_tilt", "hip_flexion", "knee_flexion", "ankle_dorsiflexion", "thigh"):
            assert c[column].shape == CYCLE_PERCENT.shape
        # a cycle is periodic: its ends agree within the subjects' spread
        assert abs(c["knee_flexion"][0] - c["knee_flexion"][-1]) < 2
        # the pattern of people: the knee nearly straight in terminal stance, 45-61° in swing (very slow to very fast)
        assert c["knee_flexion"][18:23].min() < 10 and 40 < c["knee_flexion"].max() < 65


def test_the_normative_curves_are_linear_in_the_dimensionless_speed_and_held_at_the_ends():
    table = normative_table()
    free, fast = table["Free"], table["Fast"]
    mid = normative_curves(0.5 * (free["v_star"] + fast["v_star"]))
    np.testing.assert_allclose(mid["knee"][0], 0.5 * (free["knee_flexion"] + fast["knee_flexion"]))
    np.testing.assert_allclose(normative_curves(5.0)["ankle"][0], table["VeryFast"]["ankle_dorsiflexion"])
    np.testing.assert_allclose(normative_curves(0.0)["thigh"][0],
                               table["VerySlow"]["hip_flexion"] - table["VerySlow"]["pelvic_tilt"])


def test_the_dimensionless_speed_of_the_natural_walk():
    body = Body(height=1.8, mass=80)
    assert dimensionless_speed(body, 5.0) == pytest.approx(5 / 3.6 / math.sqrt(body.g * (body.l1 + body.l9)))
    assert 0.43 < dimensionless_speed(body, 5.0) < 0.56          # between the free and fast classes


# -- the walk against people (issue #34's acceptance) ---------------------------------------------

from klaw_ocp.human_gait import FIGURES, human_figures          # noqa: E402
from klaw_ocp.body_motion import body_motion         # noqa: E402
from klaw_ocp.results import peak_swing_hip_torque              # noqa: E402
from klaw_ocp.walk import simulate_walk                          # noqa: E402

#: steps per walk: 2 of start and 4 more, so that each leg has steady cycles
STEPS = 6


def _walk(speed, height=1.8):
    """The walk and its body at 200 fps."""
    walk = simulate_walk({"name": "h", "body": {"height": height, "mass": 80},
                          "walk": {"speed": speed, "steps": STEPS}})
    assert walk.status == "ok"
    return walk, body_motion(walk, 200.0)


def _figures(speed, height=1.8, walked=None):
    walk, motion = walked or _walk(speed, height)
    figures = human_figures(walk, motion)
    assert len(figures.cycles) >= 2
    return figures


@pytest.fixture(scope="module")
def walks():
    """speed (km/h) -> (the natural walk (1.8 m) at that speed, its body at 200 fps)."""
    return {speed: _walk(speed) for speed in (3.0, 5.0, 6.0)}


@pytest.fixture(scope="module")
def people(walks):
    """speed (km/h) -> HumanFigures of the natural walk's body (1.8 m) at that speed."""
    return {speed: _figures(speed, walked=walks[speed]) for speed in walks}


def _swing_jumps(walk, motion, joint: str, around) -> float:
    """The largest frame-to-frame rate jump (deg/s) at 100 fps of the swing leg's ``joint`` over
    ``around(step)`` = (from, to) in walk time, in every step but the first two and the last."""
    from klaw_ocp.body_motion.skeleton import ANGLE_NAMES
    worst = 0.0
    for step in walk.steps[2:-1]:
        column = ANGLE_NAMES.index(f"{'l' if step.index % 2 == 0 else 'r'}_{joint}")
        start, end = around(step)
        t = np.arange(math.ceil(start * 100), math.floor(end * 100) + 1) / 100
        angle = np.interp(t, motion.t, np.degrees(motion.angles[:, column]))
        worst = max(worst, float(np.abs(np.diff(angle, 2)).max() * 100))
    return worst


@pytest.mark.parametrize("speed", [3.0, 5.0, 6.0])
def test_the_swing_ankle_relaxes_in_swing2_without_a_rate_jump(walks, speed):
    """Issue #36: at 100 fps no frame-to-frame rate jump of the swing ankle above 100 deg/s from
    t1 to t2, where it relaxes with the extending knee (kinematics/swing_foot.py: the cubic
    smoothstep of the knee's fraction; the quintic's curvature, times the knee's 500 deg/s
    squared, made 117 deg/s at 5 km/h)."""
    walk, motion = walks[speed]
    swing2 = lambda step: (step.t_start + float(step.subphase("swing2").t[0]),       # noqa: E731
                           step.t_start + float(step.subphase("swing2").t[-1]))
    assert _swing_jumps(walk, motion, "ankle_dorsiflexion", swing2) <= 100.0


@pytest.mark.parametrize("speed", [3.0, 5.0, 6.0])
def test_the_swing_knee_comes_into_swing3_without_a_rate_jump(walks, speed):
    """Issue #36: at 100 fps no frame-to-frame rate jump of the swing knee above 100 deg/s within
    50 ms of swing3's start, where the dynamics lock the straightened knee (eq. 5) and the body's
    leg bends into the next stance's landing posture: the distance blends in as the square of the
    smoothstep, so the knee (the square root of the distance's shortfall near straight) starts
    bending at rest (a smooth distance started it at a finite rate: 115-130 deg/s jumps)."""
    walk, motion = walks[speed]
    t2 = lambda step: step.t_start + float(step.subphase("swing3").t[0])        # noqa: E731
    assert _swing_jumps(walk, motion, "knee_flexion", lambda step: (t2(step) - 0.05, t2(step) + 0.05)) <= 100.0


def test_late_stance_at_5_kmh(people):
    """The knee nearly straight near 40 % of the cycle and 30-50° at toe-off; the trailing thigh
    at -10 to -20°; the hip's range 38-52°; the ankle plantarflexed 12-25° just after toe-off."""
    f = people[5.0]
    assert f.worst("knee_mid") < 10
    assert 30 <= f.worst("knee_to", high=False) and f.worst("knee_to") <= 50
    assert -20 <= f.worst("thigh_min", high=False) and f.worst("thigh_min") <= -10
    assert 38 <= f.worst("hip_range", high=False) and f.worst("hip_range") <= 52
    assert -25 <= f.worst("ankle_pf", high=False) and f.worst("ankle_pf") <= -12


@pytest.mark.parametrize("speed", [3.0, 5.0, 6.0])
def test_the_stance_leg_has_no_rate_jump(people, speed):
    """At 100 fps no frame-to-frame rate jump above 100 deg/s in the stance leg's hip, knee and
    ankle, from 30 ms after its heel strike to its toe-off: foot flat, heel-off, meta-off and the
    other leg's heel strike included. Measured 93 / 70 / 83 deg/s at 3 / 5 / 6 km/h, the largest at
    3 and 6 km/h the landing's foot still coming down 30-40 ms after heel strike (the paper's
    telescope shortens at once after impact, docs/body.md); 96-101 before the hip's lead."""
    assert people[speed].worst("stance_jump") <= 100.0


@pytest.mark.parametrize("speed", [3.0, 5.0, 6.0])
def test_the_gait_profile_score_is_a_healthy_adults(people, speed):
    """Sagittal GPS (Baker 2009) against Schwartz et al.'s curves at the walk's dimensionless
    speed: at most 6° (issue #36; people score about 5-6° against a reference group); each GVS at most 8°,
    the ankle's at most 9.5°: the pelvic list (the paper's timing, largest at mid-step) lowers the
    swing hip at t1, where the toe under the knee then needs 3-4° more dorsiflexion to clear the
    ground (15° at 6 km/h against people's 1-2°, docs/human-gait.md; issue #36's swing)."""
    f = people[speed]
    assert f.gps <= 6
    assert max(value for (_, variable), value in f.gvs.items() if variable != "ankle") <= 8
    assert max(value for (_, variable), value in f.gvs.items() if variable == "ankle") <= 9.5


def test_the_pattern_holds_at_3_and_6_kmh_with_peoples_trends(people):
    """The same pattern at 3 and 6 km/h: the knee nearly straight near 40 % and 30-50° at toe-off,
    the ankle plantarflexed just after toe-off, at least 10° at 6 km/h and 5° at 3 km/h (people:
    about 11°): there the swing-side hip, lowered by the pelvic list at toe-off, leaves the foot
    less pitch for the knee's 40°, and the swing ankle rises early to its t1 dorsiflexion
    (docs/human-gait.md); more hip range when faster."""
    for speed, least_plantarflexion in ((3.0, 5.0), (6.0, 10.0)):
        f = people[speed]
        assert f.worst("knee_mid") < 10, speed
        assert 30 <= f.worst("knee_to", high=False) and f.worst("knee_to") <= 50, speed
        assert f.worst("ankle_pf") <= -least_plantarflexion, speed
    assert people[3.0].mean("hip_range") < people[5.0].mean("hip_range") < people[6.0].mean("hip_range")
    assert people[3.0].mean("thigh_min") > people[5.0].mean("thigh_min") > people[6.0].mean("thigh_min")


@pytest.mark.parametrize("height", [1.5, 2.0])
def test_the_pattern_holds_on_short_and_tall_bodies(height):
    """Bodies of 1.5 and 2.0 m at 5 km/h: the knee nearly straight near 40 % (under 11°) and 30-50°
    at toe-off, the GPS at most 8° at their own dimensionless speed."""
    f = _figures(5.0, height)
    assert f.worst("knee_mid") < 11
    assert 30 <= f.worst("knee_to", high=False) and f.worst("knee_to") <= 50
    assert f.gps <= 8


def test_the_late_stance_ankle_dorsiflexes_as_people_s(people):
    """Issue #34: the ankle's dorsiflexion at 35-55 % of the cycle peaks at 8-15° at 5 km/h
    (people: 10-15°), at most 16° at 3 and 6 km/h. It was 16-24° when eq. 3 put the hip half-way
    along the step at heel strike, so low over the trailing foot that every knee flexion left the
    ankle at least 17° dorsiflexed; ``heel_strike_hip_lead`` moves it ahead of mid-step, as
    people's is (docs/human-gait.md)."""
    assert 8 <= people[5.0].worst("ankle_df", high=False) and people[5.0].worst("ankle_df") <= 15
    for speed in (3.0, 6.0):
        assert people[speed].worst("ankle_df") <= 16, speed


def test_the_arms_swing_as_people_s_and_more_when_faster(people):
    """Shoulder flexion range 30-40° at 5 km/h (Murray et al. 1967), growing with speed."""
    assert 30 <= people[5.0].worst("shoulder_range", high=False) and people[5.0].worst("shoulder_range") <= 40
    assert people[3.0].mean("shoulder_range") < people[5.0].mean("shoulder_range") < people[6.0].mean("shoulder_range")


@pytest.mark.parametrize("speed", [3.0, 5.0, 6.0])
def test_the_swing_knee_peaks_as_people_s(people, speed):
    """Issue #36: the swing knee peaks at 55-70° at 67-77 % of the cycle (people: 60-65° at
    70-73 % at 5 km/h), the thigh at its peak at t1 and the knee extending softly after it."""
    f = people[speed]
    assert 55 <= f.worst("knee_swing", high=False) and f.worst("knee_swing") <= 70
    assert 67 <= f.worst("knee_swing_at", high=False) and f.worst("knee_swing_at") <= 77


def test_the_swing_hip_torque_is_a_person_s():
    """Issue #36: at most 1.5 N m/kg of swing hip torque after the first step of the natural walk
    (it was 3.5: the thigh swung past its target at t1 and was pulled back)."""
    walk = simulate_walk({"name": "h", "body": {"height": 1.8, "mass": 80}, "walk": {"speed": 5.0, "steps": STEPS}})
    peaks = [peak_swing_hip_torque(step, 80.0)["peak_swing_hip_torque_per_kg"] for step in walk.steps[1:]]
    assert max(peaks) <= 1.5


@pytest.mark.parametrize("method", ["multiple-shooting", "plain-shooting"])
def test_the_closing_step_s_swing_hip_torque_is_a_person_s(method):
    """Issue #36: also the step that ends a walk at rest, at most 1.5 N m/kg (it was 2.3 at 5 km/h:
    its knee's braking threw the vertical thigh forward in swing2 and swing3's one moment pulled
    it back). Its swing2 ends with the thigh on its reference and moving with it
    (swing_law.closing_swing2_final), so swing3's moment is small: 1.44 N m/kg in both modes."""
    walk = simulate_walk({"name": "h", "body": {"height": 1.8, "mass": 80},
                          "walk": {"speed": 5.0, "steps": 4, "end_at_rest": True}, "solver": {"method": method}})
    closing = walk.steps[-1]
    assert closing.plan.constraints.closing
    peaks = [peak_swing_hip_torque(step, 80.0)["peak_swing_hip_torque_per_kg"] for step in walk.steps[1:]]
    assert max(peaks) <= 1.5 and peaks[-1] > 0.5
    # swing3's moment only helps the hold bring the thigh upright (37 N m; it was 68 N m)
    assert abs(closing.subphase("swing3").parameters["F_theta3_moment"]) < 50.0
    assert set(closing.subphase("swing2").parameters) == {"F_theta4_fall", "F_theta3_linear", "F_theta4_mean",
                                                          "F_theta3_quadratic"}


@pytest.mark.parametrize("speed", [3.0, 5.0, 6.0])
def test_no_leg_or_arm_angle_jumps_in_rate_away_from_heel_strikes(people, speed):
    """Issue #36: at 100 fps no frame-to-frame rate jump above 100 deg/s in any angle of the legs
    and arms (hip, knee, ankle, toe, shoulder, elbow; both sides) in the steady steps, but within
    45 ms after a heel strike (human_gait.limb_rate_jumps). Measured 89 / 96 / 93 deg/s at 3 / 5 /
    6 km/h: the swing1 ankle on two bounded accelerations (kinematics/swing_foot.py), the swing2
    ankle relaxing with the knee, the knee leaving t1 at `knee_rate_at_t1` (0.65: 104-119 deg/s).
    Within the window, the stance ankle's foot coming down 30-35 ms after heel strike reaches 120
    at 6 km/h."""
    jump = people[speed].worst("limb_jump")
    assert 50 < jump <= 100.0, people[speed].values["limb_jump_where"]


def test_the_hip_surge_is_the_stance_hip_s_forward_speed(walks, people):
    """Issue #36 item 7 asks to report the hip's surge (human_gait.hip_surge; docs/human-gait.md):
    the stance hip's forward speed, here checked against the finite differences of the hip's
    position over the finest grid of a steady step, and its range at 5 km/h (0.84 m/s; people
    about 0.36) and its least acceleration after heel strike (-13.6 m/s²; people above -3.4)."""
    from klaw_ocp.dynamics import stance_hips
    walk, _ = walks[5.0]
    step = walk.steps[3]
    sub = step.subphase("swing2")            # the stance re-simulated on swing2's grid
    hips, speeds = stance_hips(walk.spec.body, sub.states[:, :6], np.zeros(2))
    mid = 0.5 * (speeds[1:, 0] + speeds[:-1, 0])
    assert np.diff(hips[:, 0]) / np.diff(sub.t) == pytest.approx(mid, abs=2e-3)
    surge, decel = people[5.0].mean("hip_surge"), people[5.0].mean("hip_decel")
    assert 0.7 < surge < 0.95 and -15.0 < decel < -10.0
