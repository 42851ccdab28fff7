"""A step's body built before the next step's stance half is solved (#38, the ask's speed): the
live walk builds all of step k's body that steps <= k fix while the page shows step k - 1
(:func:`klaw_ocp.step_body.prepare_step_frames`), with the next step's stance foot as its plan
stands (:meth:`klaw_ocp.step_loop.StepLoop.next_landing`), and finishes it once that stance half is
solved; where the next step does not land as expected it builds the frames whole. The frames are
the same numbers, to the bit, either way."""
from dataclasses import replace

import numpy as np
import pytest

import klaw_ocp.stepwise as stepwise
from klaw_ocp.body_motion.swing_legs import landing_pose
from klaw_ocp.config import ExperimentConfig
from klaw_ocp.body_motion.motion import finish_body
from klaw_ocp.step_body import prepare_step_frames, step_frames
from klaw_ocp.stepwise import StepwiseWalk
from klaw_ocp.walk import Walk

METHODS = ["multiple-shooting", "plain-shooting"]


def config(method="multiple-shooting", **walk) -> ExperimentConfig:
    return ExperimentConfig.from_mapping({"name": "live", "body": {"height": 1.8, "mass": 80},
                                          "walk": {"speed": 5.0, "steps": 2, **walk}, "solver": {"method": method}})


def same_frames(a, b) -> bool:
    return (np.array_equal(a.t, b.t) and np.array_equal(a.root, b.root) and np.array_equal(a.angles, b.angles)
            and np.array_equal(a.pelvis_angles, b.pelvis_angles))


@pytest.mark.parametrize("method", METHODS)
def test_each_step_finished_from_its_prepared_body_is_the_step_built_whole(method, monkeypatch):
    # a walk from rest, its speed and cadence changed, per-step attributes changed, stopped at rest
    live = StepwiseWalk(config(method, start_from_rest=True))
    finished, built = [], stepwise.step_frames

    def recorded(walk, k, fps, ahead=None, prepared=None):
        frames = built(walk, k, fps, ahead, prepared)
        following = ahead if ahead is not None else (walk.steps[k + 1] if k + 1 < len(walk.steps) else None)
        finished.append(prepared is not None and prepared.fits(k, following))
        assert same_frames(frames, built(walk, k, fps, ahead)), k        # the whole build, at the same moment
        return frames
    monkeypatch.setattr(stepwise, "step_frames", recorded)
    actions = {1: lambda: live.request(speed=8.0), 3: lambda: live.request({"pelvic_list": 9.0, "arm_swing_amplitude": 25.0}),
               5: lambda: live.request(step_frequency=90), 7: lambda: live.request({"pelvic_rotation": 8.0}),
               9: live.stop}
    ready = []
    while (step := live.next_step()) is not None:
        ready.append(step)
        actions.get(step.index, lambda: None)()
        live.finish_ahead()                     # as the server does once it has sent a step
    assert len(ready) == len(live.walk.steps) >= 11
    # every step but the last (the walk ends with it: nothing is left for a next step to complete)
    assert finished == [True] * (len(ready) - 1) + [False]
    # and the frames handed out are the whole walk's steps' frames
    for r in ready:
        assert same_frames(r.frames, built(live.walk, r.index, live.spec.fps)), r.index


@pytest.mark.parametrize("speed", [0.5, 5.0, 9.0])
def test_the_next_landing_is_the_foot_the_next_stance_half_lands_on(speed):
    # 9 km/h lands with a flexed knee (kinematics/landing.py), 0.5 and 5 km/h straight
    live = StepwiseWalk(config(speed=speed))
    poses = []
    for _ in range(6):
        live.next_step()
        live.finish_ahead()
        expected = live._loop.next_landing()             # noqa: SLF001 - the plan as it stands
        live.next_step()                                 # the next stance half solved with that plan
        landed = live._ahead.landing_foot                # noqa: SLF001
        assert landing_pose(expected) == landing_pose(landed)
        assert (expected.landing_knee, expected.rocker_rate) == (landed.landing_knee, landed.rocker_rate)
        poses.append(expected.landing_knee)
    assert (max(poses) > 0) == (speed == 9.0)


def test_a_body_prepared_for_another_landing_or_start_is_built_again_whole():
    live = StepwiseWalk(config())
    for _ in range(3):
        live.next_step()
    live.finish_ahead()
    k, fps, walk = live._shown, live.spec.fps, live.walk            # noqa: SLF001
    prepared = live._prepared                                       # noqa: SLF001
    landing = live._loop.next_landing()                             # noqa: SLF001
    live._prepared = None                                           # noqa: SLF001
    live.next_step()
    ahead = live._ahead                                             # noqa: SLF001
    whole = step_frames(walk, k, fps, ahead)
    assert prepared.fits(k, ahead) and same_frames(step_frames(walk, k, fps, ahead, prepared), whole)
    # the swing leg lands on another pitch: that body is not the step's, and it is not used
    tilted = prepare_step_frames(walk, k, fps, replace(landing, rocker_pitch=landing.rocker_pitch + 0.05),
                                 prepared.next_start)
    assert not tilted.fits(k, ahead)
    assert not same_frames(finish_body(Walk(walk.spec, [*walk.steps[k - k % 2:], ahead]), tilted.body), whole)
    assert same_frames(step_frames(walk, k, fps, ahead, tilted), whole)
    # another step, or a next step that starts elsewhere, neither
    assert not prepared.fits(k + 1, ahead)
    assert not replace(prepared, next_start=prepared.next_start + 1e-3).fits(k, ahead)
    assert not prepared.fits(k, None)
