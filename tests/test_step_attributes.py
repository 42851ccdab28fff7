"""Attributes that change from step to step (gait.attributes.STEP_ATTRIBUTES; #38 item 1): a
schedule's entries set them as they set the locomotion parameters, every step plans, solves and
moves the body with its own, and where they change no body angle or rate jumps more than in the
walks that keep either value."""
import numpy as np
import pytest

from klaw_ocp.body_motion import body_motion
from klaw_ocp.body_motion.motion import ANGLE_NAMES
from klaw_ocp.body_motion.upper_body import step_amplitudes
from klaw_ocp.config import ExperimentConfig
from klaw_ocp.errors import ConfigError
from klaw_ocp.gait.attributes import ATTRIBUTES, STEP_ATTRIBUTES
from klaw_ocp.walk import simulate_walk

LOW = {"pelvic_list": 1.0, "pelvic_rotation": 1.0, "arm_swing_amplitude": 5.0, "pelvic_lateral_shift": 0.0,
       "toe_clearance": 0.02}
HIGH = {"pelvic_list": 10.0, "pelvic_rotation": 9.0, "arm_swing_amplitude": 30.0, "pelvic_lateral_shift": 0.05,
        "toe_clearance": 0.03}
#: the body's angles the changing attributes move
WATCHED = [i for i, name in enumerate(ANGLE_NAMES)
           if name.startswith(("pelvis_", "r_shoulder", "l_shoulder", "r_elbow", "l_elbow", "trunk_", "head_"))]


def config(schedule=(), attributes=None, steps=8, method="multiple-shooting") -> ExperimentConfig:
    return ExperimentConfig.from_mapping({"name": "per-step", "body": {"height": 1.8, "mass": 80},
                                          "walk": {"speed": 5.0, "steps": steps, "start_from_rest": True,
                                                   "end_at_rest": True, "schedule": list(schedule)},
                                          "attributes": attributes or {}, "solver": {"method": method}})


def test_every_step_attribute_is_a_registered_one_and_not_a_limit():
    assert set(STEP_ATTRIBUTES) <= set(ATTRIBUTES)
    assert all(ATTRIBUTES[name].group in ("determinants", "swing") for name in STEP_ATTRIBUTES)


def test_schedule_attributes_are_keyed_like_the_parameters():
    plans = config([{"step": 2, "attributes": {"pelvic_list": 2.0}},
                    {"step": 4, "speed": 4.0, "attributes": {"pelvic_list": 8.0, "toe_clearance": 0.03}}]).plan()
    assert [p.attributes.pelvic_list for p in plans] == [5.0, 5.0, 2.0, 5.0, 8.0, 8.0, 8.0, 8.0]
    assert [p.attributes.toe_clearance for p in plans[:5]] == [0.015] * 4 + [0.03]
    # an entry with attributes only is no keyframe of the locomotion parameters
    assert [p.parameters.speed_kmh for p in plans[:5]] == [5.0, 5.0, 5.0, 5.0, 4.0]
    assert all(p.attributes.sf_max == 182.0 for p in plans)


@pytest.mark.parametrize("entry, message", [
    ({"step": 1, "attributes": {"sf_max": 100}}, "walk.schedule[0].attributes.sf_max: got 100"),
    ({"step": 1, "attributes": {"pelvic_list": 45}}, "walk.schedule[0].attributes.pelvic_list: got 45"),
    ({"step": 1, "attributes": {}}, "walk.schedule[0]: got {step: 1} with no parameter"),
    ({"step": 20, "attributes": {"pelvic_list": 3}}, "walk.schedule[0].step: got 20"),
])
def test_bad_schedule_attributes_are_refused_in_one_line(entry, message):
    with pytest.raises(ConfigError) as err:
        config([entry])
    assert str(err.value).startswith(message) and "\n" not in str(err.value) and "allowed" in str(err.value)


def test_step_amplitudes_reach_each_steps_value_at_its_heel_strike_with_zero_rate():
    values, t_step = np.array([1.0, 3.0, 3.0, 0.5]), np.array([0.5, 0.6, 0.5, 0.5])
    tau = np.linspace(0.0, 0.5, 11)
    for k in range(3):
        a = step_amplitudes(values, np.full(11, k), tau * t_step[k] / 0.5, t_step)
        assert a[0] == values[k] and a[-1] == pytest.approx(values[k + 1])
        assert abs(a[1] - a[0]) < 0.05 * abs(values[k + 1] - values[k]) + 1e-12     # leaves with zero rate
    assert np.all(step_amplitudes(values, np.full(11, 3), tau, t_step) == 0.5)     # the last step keeps its own


def _rate_jumps(walk) -> np.ndarray:
    """The largest change of rate between frames at 100 fps (deg/s) of each watched angle."""
    motion = body_motion(walk, 100.0)
    angles = np.degrees(motion.angles[:, WATCHED])
    rates = np.diff(angles, axis=0) * 100.0
    return np.abs(np.diff(rates, axis=0)).max(axis=0)


@pytest.mark.parametrize("method", ["multiple-shooting", "plain-shooting"])
def test_a_walk_whose_determinants_change_moves_as_smoothly_as_the_walks_that_keep_them(method):
    changing = simulate_walk(config([{"step": 2, "attributes": LOW}, {"step": 4, "attributes": HIGH},
                                     {"step": 6, "attributes": LOW}], method=method))
    steps = changing.steps
    assert [s.plan.attributes.pelvic_list for s in steps[:7]] == [5.0, 5.0, 1.0, 5.5, 10.0, 5.5, 1.0]
    # the pelvis turns on from the rotation the step before ended with
    for before, after in zip(steps, steps[1:]):
        assert after.pelvis.rotation_start == before.pelvis.rotation_end
    low, high = (simulate_walk(config(attributes=a, method=method)) for a in (LOW, HIGH))
    allowed = np.maximum(_rate_jumps(low), _rate_jumps(high))
    jumps = _rate_jumps(changing)
    worse = {ANGLE_NAMES[WATCHED[i]]: (round(j, 1), round(a, 1)) for i, (j, a) in enumerate(zip(jumps, allowed))
             if j > a + 1.0}
    assert not worse, worse
