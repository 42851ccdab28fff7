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


def test_bad_ankle_x():
    with pytest.raises(ConfigError, match=r"^ankle_x: got nan"):
        step_constraints(BODY, 0.7, ankle_x=float("nan"))
