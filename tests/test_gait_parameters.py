"""Section 3, eq. 1: completing (v, sl, sf) and checking the anatomical limits."""
import math

import pytest
from hypothesis import given, settings, strategies as st

from klaw_ocp.body import Body
from klaw_ocp.errors import ConfigError, GaitLimitError
from klaw_ocp.gait import LocomotionAttributes, complete_parameters

BODY = Body(1.8, 80)
V5 = 5.0 * 1000 / 60  # 5 km/h in m/min


def test_fig10_natural_walk_from_speed_only():
    p = complete_parameters(BODY, speed_kmh=5.0)
    assert p.step_length_m == pytest.approx(0.7746, abs=1e-4)  # paper: sl ≈ 0.77 m
    assert p.step_frequency_spm == pytest.approx(107.58, abs=5e-3)  # paper: 107.5 (truncated)
    assert p.step_length_m / (p.step_frequency_spm * 1.8) == pytest.approx(0.004)
    assert p.speed_m_per_min == pytest.approx(V5)
    assert p.as_dict() == {"speed_kmh": 5.0, "step_length_m": p.step_length_m,
                           "step_frequency_spm": p.step_frequency_spm}


@pytest.mark.parametrize("sl, sf", [(0.50, 166.67), (1.05, 79.37)])
def test_fig10_short_and_long_steps(sl, sf):
    p = complete_parameters(BODY, speed_kmh=5.0, step_length=sl)
    assert p.step_frequency_spm == pytest.approx(sf, abs=5e-3)
    assert p.speed_kmh == pytest.approx(5.0)


SL_NAT = math.sqrt(0.004 * 1.8 * V5)
SF_NAT = V5 / SL_NAT


@pytest.mark.parametrize("given_, expected", [
    ({"speed_kmh": 5.0}, (5.0, SL_NAT, SF_NAT)),
    ({"step_length": 0.6}, (0.6 * 0.6 / (0.0072) * 0.06, 0.6, 0.6 / 0.0072)),
    ({"step_frequency": 100.0}, (0.72 * 100 * 0.06, 0.72, 100.0)),
    ({"speed_kmh": 5.0, "step_length": 0.7}, (5.0, 0.7, V5 / 0.7)),
    ({"speed_kmh": 5.0, "step_frequency": 110.0}, (5.0, V5 / 110, 110.0)),
    ({"step_length": 0.7, "step_frequency": 110.0}, (0.7 * 110 * 0.06, 0.7, 110.0)),
    ({"speed_kmh": 5.0, "step_length": 0.7746, "step_frequency": 107.58},
     (0.7746 * 107.58 * 0.06, 0.7746, 107.58)),
], ids=["v", "sl", "sf", "v+sl", "v+sf", "sl+sf", "all"])
def test_every_combination(given_, expected):
    p = complete_parameters(BODY, **given_)
    v, sl, sf = expected
    assert (p.speed_kmh, p.step_length_m, p.step_frequency_spm) == pytest.approx((v, sl, sf), rel=1e-12)
    assert p.speed_m_per_min == pytest.approx(p.step_length_m * p.step_frequency_spm, rel=1e-12)


def test_all_three_must_agree():
    with pytest.raises(GaitLimitError) as err:
        complete_parameters(BODY, speed_kmh=5.0, step_length=0.8, step_frequency=120)
    msg = str(err.value)
    assert "speed 5 km/h" in msg and "step_length 0.8 m" in msg and "step_frequency 120" in msg
    # within the tolerance the mismatch is accepted
    complete_parameters(BODY, speed_kmh=5.0, step_length=0.7746, step_frequency=107.0)
    loose = LocomotionAttributes.defaults().with_overrides({"parameter_consistency_tolerance": 0.2})
    p = complete_parameters(BODY, speed_kmh=5.0, step_length=0.8, step_frequency=120, attributes=loose)
    assert p.speed_kmh == pytest.approx(0.8 * 120 * 0.06)


@pytest.mark.parametrize("kwargs, field", [
    ({"speed_kmh": -1.0}, "walk.speed"), ({"speed_kmh": 0.0}, "walk.speed"),
    ({"speed_kmh": float("nan")}, "walk.speed"), ({"speed_kmh": float("inf")}, "walk.speed"),
    ({"speed_kmh": "5"}, "walk.speed"), ({"speed_kmh": True}, "walk.speed"),
    ({"step_length": -0.5}, "walk.step_length"), ({"step_length": float("nan")}, "walk.step_length"),
    ({"step_frequency": 0}, "walk.step_frequency"), ({"step_frequency": [100]}, "walk.step_frequency"),
    ({}, "walk"),
])
def test_malformed_values_are_config_errors(kwargs, field):
    with pytest.raises(ConfigError) as err:
        complete_parameters(BODY, **kwargs)
    assert str(err.value).startswith(f"{field}: got ")
    assert "allowed" in str(err.value)


@pytest.mark.parametrize("kwargs, start", [
    ({"step_frequency": 190}, "walk.step_frequency: got 190 steps/min, allowed 30 to 182 steps/min"),
    ({"step_frequency": 20}, "walk.step_frequency: got 20 steps/min, allowed 30 to 182"),
    ({"speed_kmh": 12}, "walk.speed: got 12 km/h, allowed 0.5 to 9 km/h"),
    ({"speed_kmh": 0.2}, "walk.speed: got 0.2 km/h, allowed 0.5 to 9 km/h"),
    ({"speed_kmh": 5, "step_length": 1.5}, "walk.step_length: got 1.5 m, allowed 0.1736 to 1.215 m"),
    ({"speed_kmh": 5, "step_length": 0.1}, "walk.step_length: got 0.1 m"),
    ({"step_length": 0.2, "step_frequency": 35}, "walk.speed: got 0.42 km/h (completed by eq. 1), allowed 0.5"),
])
def test_limits_are_gait_limit_errors(kwargs, start):
    with pytest.raises(GaitLimitError) as err:
        complete_parameters(BODY, **kwargs)
    assert str(err.value).startswith(start), str(err.value)


def test_derived_value_out_of_range_says_it_was_completed():
    # sf = 31 is allowed, but eq. 1 gives sl = 0.0072 · 31 = 0.2232 m and v = 0.415 km/h < 0.5 km/h
    with pytest.raises(GaitLimitError, match=r"^walk.speed: got 0.41\d* km/h \(completed by eq. 1\)"):
        complete_parameters(BODY, step_frequency=31)


def test_field_prefix_names_the_source():
    with pytest.raises(ConfigError, match=r"^walk.schedule\[2\].speed: got -1.0"):
        complete_parameters(BODY, speed_kmh=-1.0, field_prefix="walk.schedule[2]")


@settings(max_examples=60, deadline=None)
@given(height=st.floats(1.2, 2.2), v=st.floats(1.0, 7.0))
def test_speed_only_satisfies_eq1_for_any_body(height, v):
    p = complete_parameters(Body(height, 70), speed_kmh=v)
    assert p.step_length_m / (p.step_frequency_spm * height) == pytest.approx(0.004, rel=1e-12)
    assert p.speed_m_per_min == pytest.approx(p.step_length_m * p.step_frequency_spm, rel=1e-12)
