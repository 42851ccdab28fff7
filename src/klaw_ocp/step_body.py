"""A step's body frames on a window of the few steps they read (#38: the live playground hands
out each step with its frames as soon as the next step's stance half is solved; docs/serve.md).

The body at a frame reads its own step and the next: the stance leg is completed by the next
step's double support, the swing leg lands on the next stance foot. The landing is fixed by the
next step's plan and the heel strike before its stance is solved
(:meth:`klaw_ocp.step_loop.StepLoop.next_landing`), so all but the stance leg and what reads it (the
legs' angles, the arms) can be built while the page still shows the step before
(:func:`prepare_step_frames`), and :func:`step_frames` finishes it once that stance half is solved.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .body_motion.motion import BodyMotion, PreparedBody, Samples, body_motion_at, finish_body, prepare_body
from .body_motion.swing_legs import landing_pose
from .control.step import StanceStage
from .walk import Walk


def step_frames(walk: Walk, k: int, fps: float, ahead: StanceStage | None = None,
                prepared: PreparedStep | None = None) -> BodyMotion:
    """Step ``k``'s frames of ``walk``'s body, t = i/fps in [t_start_k, t_start_k+1) (the last step's up
    to the walk's end), equal to :func:`klaw_ocp.body_motion.body_motion`'s at those frames.

    The body at a frame reads its own step and the next (the stance leg completed by the next
    step's double support, the swing leg's landing on the next stance foot), so it is built on a
    window from step k (k - 1 for an odd k: the window keeps the steps' legs, right for even
    steps, left for odd) to step k + 1. Of step k + 1 it reads the stance half alone: ``ahead``,
    that half (:class:`~klaw_ocp.control.step.StanceStage`) where ``walk`` ends with step k and its
    swings are not solved yet. ``prepared``: the body of step k built before ``ahead`` was solved
    (:func:`prepare_step_frames`), finished here if the next step starts when and lands as it
    expected, else the frames are built whole: the same numbers either way."""
    steps = walk.steps if ahead is None else [*walk.steps, ahead]
    last = k == len(steps) - 1
    end = walk.duration if last else steps[k + 1].t_start      # (the last is never ``ahead``'s step)
    start = k - (k % 2)
    window = Walk(walk.spec, steps[start:k + 2])
    if prepared is not None and prepared.fits(k, steps[k + 1] if not last else None):
        return finish_body(window, prepared.body)
    return body_motion_at(window, _frames_of(steps[k], k - start, end, last, fps))


def _frames_of(step, local: int, end: float, last: bool, fps: float) -> Samples:
    """The frames of ``step``, step ``local`` of its window, which ends at ``end`` (``last``: the
    walk's last step, which keeps its last instant), as frame_times makes them."""
    i = np.arange(max(math.floor(step.t_start * fps) - 1, 0), math.floor(end * fps + 1e-9) + 2)
    if last:
        i = i[i <= math.floor(end * fps + 1e-9)]     # frame_times' last frame
    t = i / fps                                     # as frame_times makes them
    # each frame on its own side of the heel strikes, as locate_steps puts it
    t = t[(t >= step.t_start) & ((t < end) if not last else True)]
    return Samples(t, np.full(len(t), local), t - step.t_start)


@dataclass(frozen=True)
class PreparedStep:
    """A step's body built before the next step's stance half is solved (:func:`prepare_step_frames`)."""
    k: int
    next_start: float        # the next step's heel strike, where the step's frames end
    body: PreparedBody

    def fits(self, k: int, following) -> bool:
        """Whether step ``k``'s frames with ``following`` (the next step's stance half) after them
        are these: the same step, the next one starting when expected and its stance foot landed
        as the body read it (the plan may have been revised in between)."""
        return (k == self.k and following is not None and following.t_start == self.next_start
                and landing_pose(following.stance_foot) == self.body.landing)


def prepare_step_frames(walk: Walk, k: int, fps: float, landing, next_start: float) -> PreparedStep:
    """Step ``k``'s body, ``walk``'s last step, before the next step's stance half is solved: all
    but what that half completes (:func:`klaw_ocp.body_motion.motion.prepare_body`), with the next
    step's stance foot as its plan stands (``landing``: :meth:`StepLoop.next_landing`) starting at
    ``next_start``. :func:`step_frames` finishes it once that half is solved."""
    start = k - (k % 2)
    window = Walk(walk.spec, walk.steps[start:k + 1])
    return PreparedStep(k, next_start, prepare_body(window, _frames_of(walk.steps[k], k - start, next_start, False, fps),
                                                    landing))
