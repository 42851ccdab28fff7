"""Section 3, eq. 2: state-phase timings in seconds, and the subphase boundaries."""
import math

import pytest
from hypothesis import given, settings, strategies as st

from klaw_ocp.errors import ConfigError, GaitLimitError
from klaw_ocp.gait import LocomotionAttributes, state_phase_timings
from klaw_ocp.gait.timings import SF_DS_ZERO


def test_natural_walk_timings():
    sf = 107.5828707279838  # 1.8 m at 5 km/h
    t = state_phase_timings(sf)
    assert t.t_cycle == pytest.approx(120 / sf)
    assert t.t_cycle == pytest.approx(1.115419, abs=1e-6)
    assert t.t_step == pytest.approx(0.557710, abs=1e-6)
    # t_ds / t_cycle = (-0.16·107.58 + 29.08) % = 11.867 %
    assert t.t_ds / t.t_cycle == pytest.approx(0.118667, abs=1e-6)
    assert t.t_ds == pytest.approx(0.132364, abs=1e-6)
    assert t.t_stance == pytest.approx(0.690074, abs=1e-6)
    assert t.t_swing == pytest.approx(0.425346, abs=1e-6)
    assert (t.t_swing1_end, t.t_swing2_end, t.t_theta1_off) == pytest.approx(
        (0.212673, 0.361544, 0.223084), abs=1e-6)


@settings(max_examples=100, deadline=None)
@given(sf=st.floats(10.0, 181.0))
def test_identities_of_eq2(sf):
    t = state_phase_timings(sf)
    assert t.t_cycle == pytest.approx(2 * t.t_step, rel=1e-14)
    assert t.t_stance == pytest.approx(t.t_step + t.t_ds, rel=1e-14)
    assert t.t_swing == pytest.approx(t.t_step - t.t_ds, rel=1e-14)
    assert t.t_swing1_end == pytest.approx(0.5 * t.t_swing, rel=1e-14)
    assert t.t_swing2_end == pytest.approx(0.85 * t.t_swing, rel=1e-14)
    assert t.t_theta1_off == pytest.approx(0.4 * t.t_step, rel=1e-14)
    assert 0 < t.t_swing1_end < t.t_swing2_end < t.t_swing < t.t_step < t.t_stance


def test_double_support_vanishes_at_181_75():
    assert SF_DS_ZERO == pytest.approx(181.75)
    previous = math.inf
    for sf in (150.0, 170.0, 180.0, 181.0, 181.5, 181.7, 181.749):
        t_ds = state_phase_timings(sf).t_ds
        assert 0 < t_ds < previous
        previous = t_ds
    assert state_phase_timings(181.7499999).t_ds == pytest.approx(0.0, abs=1e-9)
    assert state_phase_timings(181.7).t_swing == pytest.approx(state_phase_timings(181.7).t_step, rel=1e-3)


@pytest.mark.parametrize("sf", [181.75, 182.0, 200.0])
def test_no_double_support_is_a_gait_limit(sf):
    with pytest.raises(GaitLimitError, match=r"^walk.step_frequency: got .* allowed below 181.75 steps/min"):
        state_phase_timings(sf)


@pytest.mark.parametrize("sf", [0, -10, float("nan"), float("inf"), None, "100", True])
def test_malformed_sf(sf):
    with pytest.raises(ConfigError, match=r"^walk.step_frequency: got "):
        state_phase_timings(sf)


def test_fractions_come_from_attributes():
    attrs = LocomotionAttributes.defaults().with_overrides(
        {"swing1_end_fraction": 0.4, "swing2_end_fraction": 0.9, "theta1_torque_off_fraction": 0.3})
    t = state_phase_timings(100.0, attrs)
    assert (t.t_swing1_end, t.t_swing2_end, t.t_theta1_off) == pytest.approx(
        (0.4 * t.t_swing, 0.9 * t.t_swing, 0.3 * 0.6))


def test_as_dict_keys_are_seconds():
    d = state_phase_timings(100.0).as_dict()
    assert set(d) == {"t_cycle_s", "t_step_s", "t_ds_s", "t_stance_s", "t_swing_s",
                      "t_swing1_end_s", "t_swing2_end_s", "t_theta1_off_s"}
    assert d["t_step_s"] == pytest.approx(0.6)
