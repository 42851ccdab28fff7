"""The per-step plan of a walk: schedule interpolation, duration to steps, chained origins."""
import pytest

from klaw_ocp.body import Body
from klaw_ocp.errors import ConfigError, GaitLimitError
from klaw_ocp.gait import LocomotionParameters, complete_parameters, plan_steps

BODY = Body(1.8, 80)
REQUIRED_KEYS = {"speed_kmh", "step_length_m", "step_frequency_spm", "t_cycle_s", "t_step_s",
                 "t_ds_s", "t_stance_s", "t_swing_s", "w_m", "theta1_rad", "theta3_rad",
                 "hip_y_m", "t_swing1_end_s", "t_swing2_end_s", "t_theta1_off_s"}


def test_natural_walk_of_12_s_has_22_steps():
    plans = plan_steps(BODY, {"speed": 5.0}, duration=12.0)
    # t_step = 0.5577 s: 21 steps reach 11.71 s < 12 s, the 22nd reaches 12.27 s
    assert len(plans) == 22
    assert plans[-1].t_start < 12.0 <= plans[-1].t_start + plans[-1].timings.t_step
    assert all(p.parameters == plans[0].parameters for p in plans)
    assert REQUIRED_KEYS <= set(plans[0].as_dict())


def test_duration_of_an_exact_number_of_steps_adds_no_extra_step():
    plans = plan_steps(BODY, {"step_frequency": 100.0}, duration=3.0)  # t_step = 0.6 s
    assert len(plans) == 5


def test_short_duration_still_gives_one_step():
    assert len(plan_steps(BODY, {"speed": 5.0}, duration=0.01)) == 1


def test_steps_are_chained_in_space_and_time():
    plans = plan_steps(BODY, {"speed": 4.0}, n_steps=4)
    sl = plans[0].parameters.step_length_m
    for i, p in enumerate(plans):
        assert p.index == i
        assert p.constraints.ankle_x == pytest.approx(i * sl)
        assert p.t_start == pytest.approx(i * p.timings.t_step)
        if i:
            assert p.constraints.ankle_x == plans[i - 1].constraints.next_ankle_x


def test_schedule_interpolates_speed_and_step_length_per_step():
    schedule = [{"step": 2, "speed": 2.0}, {"step": 6, "speed": 5.0}]
    plans = plan_steps(BODY, {"speed": 3.0}, schedule, n_steps=9)
    p2 = complete_parameters(BODY, speed_kmh=2.0)
    p6 = complete_parameters(BODY, speed_kmh=5.0)
    base = complete_parameters(BODY, speed_kmh=3.0)
    assert plans[0].parameters == base and plans[1].parameters == base  # before the first entry
    assert plans[2].parameters == p2 and plans[6].parameters == p6
    assert plans[7].parameters == p6 and plans[8].parameters == p6  # after the last entry
    for i in (3, 4, 5):
        f = (i - 2) / 4
        p = plans[i].parameters
        assert p.speed_kmh == pytest.approx(2.0 + 3.0 * f)
        assert p.step_length_m == pytest.approx(p2.step_length_m + f * (p6.step_length_m - p2.step_length_m))
        assert p.step_frequency_spm == pytest.approx(p.speed_m_per_min / p.step_length_m)
    speeds = [p.parameters.speed_kmh for p in plans[2:7]]
    assert speeds == sorted(speeds)  # a smooth acceleration


def test_schedule_entry_with_step_length_and_frequency():
    schedule = [{"step": 0, "step_length": 0.6, "step_frequency": 100.0}]
    plans = plan_steps(BODY, None, schedule, n_steps=2)
    assert plans[1].parameters == LocomotionParameters(0.6 * 100 * 0.06, 0.6, 100.0)


def test_base_may_be_a_parameters_object():
    p = complete_parameters(BODY, speed_kmh=4.0)
    assert plan_steps(BODY, p, n_steps=1)[0].parameters == p


def test_accelerate_and_decelerate_schedule_is_symmetric():
    schedule = [{"step": 0, "speed": 2.0}, {"step": 4, "speed": 5.0}, {"step": 8, "speed": 2.0}]
    plans = plan_steps(BODY, {}, schedule, n_steps=9)
    v = [p.parameters.speed_kmh for p in plans]
    assert v == pytest.approx([2.0, 2.75, 3.5, 4.25, 5.0, 4.25, 3.5, 2.75, 2.0])


@pytest.mark.parametrize("kwargs, error, start", [
    ({"base_request": {"speed": 5}}, ConfigError, "walk: got 'steps=None, duration=None'"),
    ({"base_request": {"speed": 5}, "n_steps": 3, "duration": 2.0}, ConfigError, "walk: got"),
    ({"base_request": {"speed": 5}, "n_steps": 0}, ConfigError, "walk.steps: got 0"),
    ({"base_request": {"speed": 5}, "n_steps": 2.5}, ConfigError, "walk.steps: got 2.5"),
    ({"base_request": {"speed": 5}, "duration": -1}, ConfigError, "walk.duration: got -1"),
    ({"base_request": {"speed": 5}, "duration": float("nan")}, ConfigError, "walk.duration: got nan"),
    ({"base_request": {}, "n_steps": 2}, ConfigError, "walk: got 'no speed"),
    ({"base_request": {"speed": 5}, "schedule": [{"step": 1}], "n_steps": 2}, ConfigError,
     "walk.schedule[0]: got {'step': 1}, allowed at least one of"),
    ({"base_request": {"speed": 5}, "schedule": [{"step": -1, "speed": 3}], "n_steps": 2},
     ConfigError, "walk.schedule[0].step: got -1"),
    ({"base_request": {"speed": 5}, "schedule": [{"step": 1, "speed": 3}, {"step": 1, "speed": 4}],
      "n_steps": 2}, ConfigError, "walk.schedule[1].step: got 1, allowed a step not already"),
    ({"base_request": {"speed": 5}, "schedule": [{"step": 1, "speed": 3, "sped": 4}], "n_steps": 2},
     ConfigError, "walk.schedule[0].sped: got 4"),
    ({"base_request": {"speed": 5}, "schedule": [{"step": 1, "speed": 4}, {"step": 9, "speed": 3}],
      "n_steps": 4}, ConfigError, "walk.schedule[1].step: got 9, allowed 0 to 3 (the walk has 4 steps)"),
    ({"base_request": {"speed": 5}, "schedule": [{"step": 3, "speed": 3}, {"step": 1, "speed": 4}],
      "n_steps": 4}, ConfigError, "walk.schedule[1].step: got 1, allowed a step after 3 (walk.schedule[0].step)"),
    ({"base_request": {"speed": 5}, "schedule": [{"step": 1, "speed": 30}], "n_steps": 2},
     GaitLimitError, "walk.schedule[0].speed: got 30 km/h, allowed 0.5 to 9 km/h"),
    ({"base_request": {"speed": -5}, "n_steps": 2}, ConfigError, "walk.speed: got -5.0"),
    ({"base_request": {"step_length": 0.5, "step_frequency": 181.9}, "n_steps": 2}, GaitLimitError,
     "walk.step[0].step_frequency: got 181.9 steps/min, allowed below 181.75"),
])
def test_bad_plans(kwargs, error, start):
    with pytest.raises(error) as err:
        plan_steps(BODY, **kwargs)
    assert str(err.value).startswith(start), str(err.value)
    assert isinstance(err.value, (ConfigError, GaitLimitError))
