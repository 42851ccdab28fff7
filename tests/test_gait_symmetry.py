"""Section 3, eq. 3: the heel-strike final conditions and their geometric closure."""
import math

import pytest
from hypothesis import given, settings, strategies as st

from klaw_ocp.body import Body
from klaw_ocp.errors import ConfigError, GaitLimitError
from klaw_ocp.gait import LocomotionAttributes, complete_parameters, landing_heel, step_constraints

BODY = Body(1.8, 80)


def test_natural_step_values():
    c = step_constraints(BODY, 0.7746)
    assert c.w == pytest.approx(0.896, abs=1e-3)
    assert c.w > BODY.l1  # the foot lifts the hip: the telescopic leg is longer than l1
    assert c.theta1 == pytest.approx(0.447, abs=1e-3)
    assert c.theta3 == pytest.approx(-0.4205, abs=1e-3)
    assert abs(c.theta3) < c.theta1  # the foot makes |θ3| smaller than θ1
    assert (c.ankle_x, c.ankle_y) == (0.0, pytest.approx(BODY.l9))
    assert c.hip_x == pytest.approx(0.7746 / 2)
    assert c.heel_x == pytest.approx(0.7746 - BODY.l8)
    assert c.next_ankle_x == pytest.approx(0.7746)


def _check_closure(body, c, sl, x_a):
    heel = landing_heel(body, c)
    assert heel[0] == pytest.approx(x_a + sl - body.l8, abs=1e-12)
    assert heel[1] == pytest.approx(0.0, abs=1e-12)
    # the stance leg of length w at angle θ1 from ankle1 reaches the same hip
    assert c.ankle_x + c.w * math.sin(c.theta1) == pytest.approx(c.hip_x, abs=1e-12)
    assert c.ankle_y + c.w * math.cos(c.theta1) == pytest.approx(c.hip_y, abs=1e-12)
    # the landing ankle is l1 from the hip and l11 from the heel
    ax = c.hip_x - body.l1 * math.sin(c.theta3)
    ay = c.hip_y - body.l1 * math.cos(c.theta3)
    assert math.hypot(ax - heel[0], ay - heel[1]) == pytest.approx(body.l11, abs=1e-12)


def test_natural_step_closes():
    c = step_constraints(BODY, 0.7746, ankle_x=2.5)
    _check_closure(BODY, c, 0.7746, 2.5)


@settings(max_examples=80, deadline=None)
@given(height=st.floats(1.2, 2.2), rel=st.floats(0.2, 1.4), x_a=st.floats(-5, 50),
       theta5=st.floats(75, 110))
def test_eq3_closes_for_any_body_step_and_ankle_angle(height, rel, x_a, theta5):
    body = Body(height, 75)
    sl = rel * body.l1
    attrs = LocomotionAttributes.defaults().with_overrides({"theta5_impact": theta5})
    c = step_constraints(body, sl, attrs, ankle_x=x_a)
    _check_closure(body, c, sl, x_a)
    assert c.theta1 > 0 > c.theta3
    assert c.next_ankle_x == pytest.approx(x_a + sl)


@settings(max_examples=60, deadline=None)
@given(height=st.floats(1.2, 2.2), v=st.floats(0.5, 7.0))
def test_w_exceeds_l1_for_natural_steps(height, v):
    body = Body(height, 75)
    p = complete_parameters(body, speed_kmh=v)
    c = step_constraints(body, p.step_length_m)
    assert c.w > body.l1


def test_sign_convention_against_the_compass_gait():
    # A symmetric compass gait has θ3 = -θ1 (ERRATA 6); the foot makes |θ3| smaller (section 3).
    c = step_constraints(BODY, 0.7746)
    assert -c.theta1 < c.theta3 < 0


def test_a_smaller_ankle_angle_lowers_the_hip_below_w_eq_l1():
    # ERRATA open choice: the other reading of θ5 makes the interior angle θ5 + ω8 about 90°,
    # and a small interior angle gives w < l1, against the text's w > l1. Even the lowest allowed
    # θ5 (60°, interior angle 112°) already does; our reading (90°, 142°) gives w > l1.
    low = LocomotionAttributes.defaults().with_overrides({"theta5_impact": 60})
    assert step_constraints(BODY, 0.7746, low).w < BODY.l1 < step_constraints(BODY, 0.7746).w


@pytest.mark.parametrize("sl", [0, -0.5, float("nan"), float("inf"), None, "0.7"])
def test_bad_step_length(sl):
    with pytest.raises(ConfigError, match=r"^walk.step_length: got "):
        step_constraints(BODY, sl)


def test_unreachable_step_is_a_gait_limit():
    with pytest.raises(GaitLimitError, match=r"^walk.step_length: got 2.5 m, allowed below 1.9\d* m"):
        step_constraints(BODY, 2.5)


@pytest.mark.parametrize("lead", [0.0, 0.045, 0.1])
@pytest.mark.parametrize("rotation", [0.0, 4.0])
def test_the_step_length_limit_is_where_the_hip_reaches_ankle_height(lead, rotation):
    """The limit the message names is exact: a hair below it the landing leg reaches the ground
    with the hip above the stance ankle, a hair above it not."""
    shift = BODY.l0 * math.sin(math.radians(rotation))
    with pytest.raises(GaitLimitError) as err:
        step_constraints(BODY, 3.0, hip_shift=shift, hip_lead=lead)
    limit = float(str(err.value).split("allowed below ")[1].split(" m")[0])
    c = step_constraints(BODY, limit * (1 - 1e-3), hip_shift=shift, hip_lead=lead)
    assert c.hip_y == pytest.approx(BODY.l9, abs=0.05)
    with pytest.raises(GaitLimitError):
        step_constraints(BODY, limit * (1 + 1e-3), hip_shift=shift, hip_lead=lead)


@settings(max_examples=60, deadline=None)
@given(height=st.floats(1.4, 2.1), rel=st.floats(0.3, 1.2), lead=st.floats(0.0, 0.1), rotation=st.floats(0.0, 8.0))
def test_the_hip_lead_moves_the_hip_ahead_and_up_and_the_next_stance_starts_from_it(height, rel, lead, rotation):
    """The hip is lead·sl ahead of where eq. 3 puts it, higher (the landing leg spans less), the
    landing heel where eq. 3 puts it; the next stance starts at the landing hip seen from its own
    ankle (what the heel-strike map gives), the mirror of this stance's end only without a lead."""
    body = Body(height, 75)
    sl = rel * body.l1
    shift = body.l0 * math.sin(math.radians(rotation))
    paper = step_constraints(body, sl, ankle_x=1.0, hip_shift=shift)
    c = step_constraints(body, sl, ankle_x=1.0, hip_shift=shift, hip_lead=lead)
    assert c.hip_lead == pytest.approx(lead * sl, abs=1e-15)
    assert c.hip_x == pytest.approx(paper.hip_x + lead * sl, abs=1e-12)
    assert c.hip_y >= paper.hip_y - 1e-12 and c.w >= paper.w - 1e-12
    if shift == 0:      # (the closure check reads the one-hip model's landing hip)
        _check_closure(body, c, sl, 1.0)
    hip = (c.landing_hip_x - c.next_ankle_x, c.hip_y - c.ankle_y)
    assert c.landing_w == pytest.approx(math.hypot(*hip), abs=1e-12)
    assert c.landing_theta1 == pytest.approx(math.atan2(*hip), abs=1e-12)
    assert paper.landing_w == pytest.approx(paper.w, abs=1e-12)
    assert paper.landing_theta1 == pytest.approx(-paper.theta1, abs=1e-12)
    if lead > 1e-3:
        assert c.landing_w < c.w and abs(c.landing_theta1) < c.theta1


@pytest.mark.parametrize("lead", [0.5, float("nan"), "0.1"])
def test_bad_hip_lead(lead):
    with pytest.raises(ConfigError, match=r"^hip_lead: got "):
        step_constraints(BODY, 0.7, hip_lead=lead)


def test_the_plan_leads_by_the_attribute_from_free_speed_and_in_proportion_below():
    """heel_strike_hip_lead whole from a dimensionless speed of 0.45 (5 km/h at 1.8 m), in
    proportion to it below, none in a closing step."""
    from klaw_ocp.gait.plan import HIP_LEAD_FULL_SPEED, closing_step, heel_strike_hip_lead, plan_steps
    attrs = LocomotionAttributes.defaults()
    full = attrs.heel_strike_hip_lead
    v_full = HIP_LEAD_FULL_SPEED * math.sqrt(BODY.g * (BODY.l1 + BODY.l9)) * 3.6
    assert 4.9 < v_full < 5.1
    assert heel_strike_hip_lead(BODY, attrs, 6.0) == full
    assert heel_strike_hip_lead(BODY, attrs, v_full / 2) == pytest.approx(full / 2, rel=1e-12)
    plans = plan_steps(BODY, {"speed": 3.0}, n_steps=2, attributes=attrs)
    assert plans[1].constraints.hip_lead == pytest.approx(full * 3.0 / v_full * plans[1].constraints.step_length)
    assert closing_step(BODY, attrs, plans[-1]).constraints.hip_lead == 0.0


def test_bad_ankle_x():
    with pytest.raises(ConfigError, match=r"^ankle_x: got nan"):
        step_constraints(BODY, 0.7, ankle_x=float("nan"))
