"""The walk solved step by step (#38 item 1): the same numbers as simulate_walk for the schedule it
exports, each step's frames as the whole walk's body has them, refusals that leave it walking."""
import numpy as np
import pytest

from klaw_ocp.body_motion import body_motion
from klaw_ocp.config import ExperimentConfig
from klaw_ocp.errors import ConfigError, GaitLimitError
from klaw_ocp.gait.envelope import check_step_changes
from klaw_ocp.result_files.bvh import bvh_text
from klaw_ocp.stepwise import StepwiseWalk
from klaw_ocp.walk import simulate_walk

METHODS = ["multiple-shooting", "plain-shooting"]


def config(method="multiple-shooting", **walk) -> ExperimentConfig:
    return ExperimentConfig.from_mapping({"name": "live", "body": {"height": 1.8, "mass": 80},
                                          "walk": {"speed": 5.0, "steps": 2, **walk},
                                          "solver": {"method": method}})


def drive(live: StepwiseWalk, actions: dict) -> list:
    """Hand out every step; ``actions[k]`` runs once step k has been handed out."""
    ready = []
    while (step := live.next_step()) is not None:
        ready.append(step)
        actions.get(step.index, lambda: None)()
    return ready


@pytest.fixture(scope="module", params=METHODS)
def session(request):
    live = StepwiseWalk(config(request.param, start_from_rest=True))
    ready = drive(live, {1: lambda: live.request(speed=3.0),
                         3: lambda: live.request({"pelvic_list": 9.0, "arm_swing_amplitude": 25.0}),
                         5: lambda: live.request(step_frequency=120),
                         7: lambda: live.request({"pelvic_rotation": 8.0, "toe_clearance": 0.025,
                                                  "pelvic_lateral_shift": 0.04}),
                         11: live.stop})
    return live, ready


def test_the_exported_schedule_solves_the_same_steps_to_the_bit(session):
    live, _ = session
    again = simulate_walk(live.reproducing_config())
    assert len(again.steps) == len(live.walk.steps)
    for a, b in zip(again.steps, live.walk.steps):
        assert a.plan == b.plan
        for sa, sb in zip(a.subphases, b.subphases):
            assert np.array_equal(sa.states, sb.states) and np.array_equal(sa.t, sb.t), (a.index, sa.name)


def test_the_bvh_of_the_session_is_the_bvh_of_its_config_byte_for_byte(session):
    live, _ = session
    cfg = live.reproducing_config()
    again = simulate_walk(cfg)
    fps = cfg.output.fps
    assert bvh_text(body_motion(again, fps), again.spec.body, fps) == \
        bvh_text(body_motion(live.walk, fps), live.walk.spec.body, fps)


def test_each_steps_frames_are_the_whole_walks_frames(session):
    live, ready = session
    whole = body_motion(live.walk, live.spec.fps)
    assert [r.index for r in ready] == list(range(len(live.walk.steps)))
    t = np.concatenate([r.frames.t for r in ready])
    assert np.array_equal(t, whole.t)       # every frame once, in order
    # the window's step coordinate u = k + tau/t_step rounds a few ulps differently; where the
    # closing step's foot comes down grazing the ground (its ankle within a millimetre of l9), the
    # ground guard's limits, a square root of the ankle's height above l9, make that 2e-8 rad
    angles = np.vstack([r.frames.angles for r in ready])
    np.testing.assert_allclose(angles[:-len(ready[-1].frames.t)], whole.angles[:-len(ready[-1].frames.t)], rtol=0, atol=1e-9)
    np.testing.assert_allclose(angles, whole.angles, rtol=0, atol=1e-7)
    np.testing.assert_allclose(np.vstack([r.frames.root for r in ready]), whole.root, rtol=0, atol=1e-9)


def test_changes_ramp_within_the_per_step_limits_and_reach_their_target(session):
    live, ready = session
    params = [s.plan.parameters for s in live.walk.steps[:-1]]      # the closing step aside
    check_step_changes(live.body, params, live.attributes)
    speeds = [p.speed_kmh for p in params]
    assert min(speeds) == pytest.approx(3.0)
    assert params[-1].step_frequency_spm == pytest.approx(120.0)
    assert ready[-1].closing and ready[-1].result.plan.parameters.step_length_m == 0.0


def test_attributes_asked_for_reach_the_second_step_after_the_one_on_screen_and_the_exported_schedule(session):
    live, _ = session
    steps = live.walk.steps
    lists = [s.plan.attributes.pelvic_list for s in steps]
    rotations = [s.plan.attributes.pelvic_rotation for s in steps]
    base = live.attributes
    # asked with step 3 on screen (step 4 solved, step 5 planned again): from step 5 on
    assert lists[:5] == [base.pelvic_list] * 5 and lists[5:] == [9.0] * (len(steps) - 5)
    assert rotations[:9] == [base.pelvic_rotation] * 9 and rotations[9:] == [8.0] * (len(steps) - 9)
    # the pelvis solved with them, turning on from the rotation the step before ended with
    assert steps[5].pelvis.list_peak == pytest.approx(np.radians(9.0))
    assert steps[9].pelvis.rotation_start == pytest.approx(np.radians(base.pelvic_rotation))
    assert steps[9].pelvis.rotation_end == pytest.approx(np.radians(8.0))
    assert steps[10].pelvis.rotation_start == pytest.approx(np.radians(8.0))
    schedule = live.reproducing_config().walk.schedule
    assert schedule[-1].attributes == {"pelvic_rotation": 8.0, "pelvic_list": 9.0, "pelvic_lateral_shift": 0.04,
                                       "arm_swing_amplitude": 25.0, "toe_clearance": 0.025}


@pytest.mark.parametrize("values, field", [({"pelvic_list": 50.0}, "attributes.pelvic_list"),
                                           ({"sf_max": 100.0}, "attributes.sf_max"),
                                           ({"toe_clearance": "high"}, "attributes.toe_clearance")])
def test_attributes_out_of_range_or_not_per_step_are_refused_in_one_line(values, field):
    live = StepwiseWalk(config())
    live.next_step()
    with pytest.raises(ConfigError) as err:
        live.request(values, speed=4.0)     # refused whole: the speed is not taken either
    message = str(err.value)
    assert "\n" not in message and message.startswith(field) and "allowed" in message
    live.stop()
    drive(live, {})
    assert all(s.plan.attributes == live.attributes for s in live.walk.steps)
    assert all(s.plan.parameters.speed_kmh in (5.0, 0.0) for s in live.walk.steps)


@pytest.mark.parametrize("method", METHODS)
def test_a_change_or_a_stop_shows_from_the_second_step_after_the_one_on_screen(method):
    live = StepwiseWalk(config(method))
    ready = drive(live, {0: lambda: live.request(speed=4.0), 3: live.stop})
    speeds = [r.result.plan.parameters.speed_kmh for r in ready]
    # step 0 on screen, step 1 solved, step 2 planned: step 2 is planned again before it is
    # solved, with the change; the stop asked with step 3 on screen closes the walk at step 5
    assert speeds[:2] == [5.0, 5.0] and speeds[2:5] == pytest.approx([4.0] * 3)
    assert [r.closing for r in ready] == [False] * 5 + [True] and speeds[5] == 0.0
    # and the walk is the one its exported schedule solves, its frames the whole walk's
    again = simulate_walk(live.reproducing_config())
    for a, b in zip(again.steps, live.walk.steps, strict=True):
        for sa, sb in zip(a.subphases, b.subphases):
            assert np.array_equal(sa.states, sb.states), (a.index, sa.name)
    fps = live.spec.fps
    assert bvh_text(body_motion(again, fps), again.spec.body, fps) == bvh_text(body_motion(live.walk, fps), live.body, fps)
    whole = body_motion(live.walk, fps)
    np.testing.assert_allclose(np.vstack([r.frames.angles for r in ready]), whole.angles, rtol=0, atol=1e-9)


def test_a_plan_asked_again_without_a_change_is_the_plan_made_before():
    live = StepwiseWalk(config())
    live.next_step()
    planned = live.last_planned
    live.request(speed=5.0)             # the walk's own speed: nothing to change
    live.next_step()                    # (step 2's stance half solved with it: its frames read it)
    live.finish_ahead()
    assert live.walk.steps[2].plan is planned


@pytest.mark.parametrize("values, field", [({"speed": 30.0}, "walk.speed"), ({"step_length": 2.0}, "walk.step"),
                                           ({"speed": -1.0}, "walk.speed"), ({"cadence": 100}, "cadence"),
                                           ({"speed": "fast"}, "walk.speed")])
def test_out_of_envelope_requests_are_refused_in_one_line_and_the_walk_goes_on(values, field):
    live = StepwiseWalk(config())
    live.next_step()
    with pytest.raises(ConfigError) as err:
        live.request(**values)
    message = str(err.value)
    assert "\n" not in message and message.startswith(field) and "allowed" in message
    live.stop()
    assert len(drive(live, {})) >= 1 and live.ended
    assert all(s.plan.parameters.speed_kmh in (5.0, 0.0) for s in live.walk.steps)


def test_a_gait_limit_is_a_gait_limit_error():
    live = StepwiseWalk(config())
    with pytest.raises(GaitLimitError):
        live.request(speed=30.0)


@pytest.mark.parametrize("method", METHODS)
def test_a_walk_exported_mid_walk_is_the_walk_its_config_solves_to_the_bit(method):
    live = StepwiseWalk(config(method, start_from_rest=True))
    drive_until = {1: lambda: live.request(speed=4.0, step_length=0.7)}
    while (step := live.next_step()).index < 4:
        drive_until.get(step.index, lambda: None)()
    # steps 0-4 handed out, step 5 solved, step 6 planned: the walk so far is steps 0-4
    cfg = live.reproducing_config()
    assert cfg.walk.steps == 5 and not cfg.walk.end_at_rest and cfg.walk.schedule
    again, so_far = simulate_walk(cfg), live.walk_so_far()
    assert len(again.steps) == len(so_far.steps) == 5
    for a, b in zip(again.steps, so_far.steps, strict=True):
        assert a.plan == b.plan
        for sa, sb in zip(a.subphases, b.subphases):
            assert np.array_equal(sa.states, sb.states), (a.index, sa.name)
    fps = cfg.output.fps
    assert bvh_text(body_motion(again, fps), again.spec.body, fps) == bvh_text(body_motion(so_far, fps), live.body, fps)
    # the walk goes on after an export, and a stop ends it as it would have
    live.stop()
    drive(live, {})
    assert live.ended and live.reproducing_config().walk.end_at_rest


def test_an_export_holds_at_least_one_step_and_no_more_than_were_solved():
    live = StepwiseWalk(config())
    with pytest.raises(ConfigError, match="session.steps"):
        live.reproducing_config()           # nothing handed out yet
    live.next_step()
    with pytest.raises(ConfigError, match="session.steps: got 3"):
        live.walk_so_far(3)                 # steps 0 and 1 solved
    assert live.reproducing_config().walk.steps == 1


def test_a_walk_that_is_never_changed_exports_its_plain_request():
    live = StepwiseWalk(config())
    for _ in range(3):
        live.next_step()
    live.stop()
    drive(live, {})
    cfg = live.reproducing_config()
    assert cfg.walk.schedule == [] and cfg.walk.end_at_rest


def test_a_walk_from_rest_ramps_up_to_its_speed_and_reproduces():
    live = StepwiseWalk(config(speed=7.0, start_from_rest=True))
    drive(live, {6: live.stop})
    speeds = [s.plan.parameters.speed_kmh for s in live.walk.steps[:-1]]
    assert speeds[0] == 5.0 and speeds[-1] == pytest.approx(7.0)     # start_speed_max, then 1 km/h a step
    again = simulate_walk(live.reproducing_config())
    assert [s.plan for s in again.steps] == [s.plan for s in live.walk.steps]


def test_a_step_is_handed_out_with_the_next_steps_stance_half_only_and_the_same_frames():
    """A step's frames read the next step's stance half alone (the landing foot, the double support
    that completes the stance leg), so next_step leaves that step's swings for later
    (finish_ahead, which the server calls once the step is sent): the frames are the same whether
    the swings were solved before or not, and the walk the same as simulate_walk's."""
    eager, lazy = StepwiseWalk(config(steps=6)), StepwiseWalk(config(steps=6))
    for k in range(6):
        a, b = eager.next_step(), lazy.next_step()
        # handed out step k: its swings solved, the next step's stance half only
        assert len(lazy.walk.steps) == k + 1 and lazy._ahead is not None and lazy._ahead.index == k + 1
        with pytest.raises(ValueError, match="not solved yet"):
            lazy._ahead.subphase("swing1")
        eager.finish_ahead()
        assert np.array_equal(a.frames.angles, b.frames.angles) and np.array_equal(a.frames.root, b.frames.root)
        assert a.dynamics.keys() == b.dynamics.keys()
    lazy.finish_ahead()
    for a, b in zip(eager.walk.steps, lazy.walk.steps, strict=True):
        for sa, sb in zip(a.subphases, b.subphases, strict=True):
            assert np.array_equal(sa.states, sb.states)
    whole = simulate_walk(config(steps=7))
    for a, b in zip(whole.steps, lazy.walk.steps, strict=True):
        assert [s.name for s in a.subphases] == [s.name for s in b.subphases] == ["stance", "swing1", "swing2", "swing3"]
        for sa, sb in zip(a.subphases, b.subphases):
            assert np.array_equal(sa.states, sb.states), (a.index, sa.name)


def test_the_step_loop_finishes_a_step_before_beginning_or_revising_another():
    live = StepwiseWalk(config())
    live.next_step()                    # step 0 whole, step 1's stance half
    loop = live._loop
    assert loop.pending is not None and loop.pending[0].index == 1
    with pytest.raises(ValueError, match="swings are not solved"):
        loop.begin_next()
    with pytest.raises(ValueError, match="a step begun"):
        loop.revise_next((live.last_planned, False))
    live.finish_ahead()
    assert loop.pending is None and live.walk.steps[-1].index == 1 and live.finish_ahead() is None


def test_a_step_that_fails_ends_the_walk_and_nothing_more_is_handed_out(fail_at_step):
    """The step after a failed one's predecessor is never handed out as a last step it is not."""
    from klaw_ocp.errors import ConvergenceError
    fail_at_step(3, "swing2", 1e-3)
    live = StepwiseWalk(config())
    assert [live.next_step().index for _ in range(2)] == [0, 1]
    with pytest.raises(ConvergenceError, match="step 3"):
        live.next_step()                # step 2's frames need step 3's stance half
    assert live.ended and isinstance(live.failed, ConvergenceError)
    assert live.next_step() is None and live.finish_ahead() is None
    assert [s.index for s in live.walk.steps] == [0, 1, 2]
