"""The virtual legs (:mod:`klaw_ocp.kinematics.virtual_leg`) of many stances of one walk evaluated
together: the body (:mod:`.motion`) needs every stance of a walk at its frames, and one
:meth:`StanceFoot.frames` call per stance costs mostly its fixed overhead (about 0.7 ms, with a few
dozen frames each); all of them in one pass of numpy cost some 250 array operations, so the pass
is compiled (:mod:`.stance_kernel`).

:func:`ground_legs`: the legs while their feet are on the ground, every stance of a walk at the
frames in one pass; a window whose next step is not solved yet leaves its last stance foot's frames
open (:class:`OpenStance`): that step completes the foot's rules (:func:`open_points` then).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..gait.plan import stance_leg
from ..kinematics.leg_geometry import leg_ik
from ..kinematics.pitch_rules import RULE_FIELDS
from ..kinematics.virtual_leg import VirtualLegFrames, leg_periods
from .stance_kernel import COLUMNS, constants, stance_at

_RULES = [COLUMNS.index(name) for name in RULE_FIELDS] + [COLUMNS.index(name) for name in ("rocker_theta6", "ankle_x")]
_T, _HIPS, _DEFICIT = COLUMNS.index("t"), [COLUMNS.index("hip_x"), COLUMNS.index("hip_y")], COLUMNS.index("deficit")
#: a leg's points in the body's order (:class:`.pose.LegPoints`), and those of its foot
POINTS = ("hip", "knee", "ankle", "heel", "metatarsal", "toe")
_FOOT = ("ankle", "heel", "metatarsal", "toe")


def stance_frames(feet, which: np.ndarray, t: np.ndarray, hips: np.ndarray) -> VirtualLegFrames:
    """:meth:`StanceFoot.frames` of many stances of one body in one pass (the body's frames: one
    call instead of one per stance, whose fixed cost is most of it): sample i is the stance
    ``feet[which[i]]`` at its stance time ``t[i]`` with the hip ``hips[i]``. The foot's geometry
    does not depend on where it stands, so every sample is taken to its own foot's frame (ankle at
    x = 0) and back."""
    first = feet[0]
    shared = (first.foot.body, first.heel_off_theta5, first.meta_off_theta6)
    if any((f.foot.body, f.heel_off_theta5, f.meta_off_theta6) != shared for f in feet):
        raise ValueError("feet: the stances must share the body and the heel-off and meta-off limits")
    which, t = np.asarray(which), np.asarray(t, float)
    rows = np.empty((len(t), len(COLUMNS)))
    # each sample's stance: its rules, rocker toe angle and ankle x, one table row a stance
    rows[:, _RULES] = np.array([[getattr(f, name) for name in RULE_FIELDS] + [f.rocker_theta6, f.foot.ankle_x]
                                for f in feet], float)[which]
    rows[:, _T], rows[:, _HIPS] = t, hips
    # what single support adds to the rules' pitch so that the heel never comes down again
    # (StanceFoot.find_heel_off), at every sample of a stance that has it (the kernel adds it in
    # single support only)
    deficit = rows[:, _DEFICIT]
    deficit[:] = 0.0
    for k in np.unique(which):
        if feet[k].single_t and any(feet[k].single_deficit):
            mine = which == k
            deficit[mine] = np.interp(t[mine], feet[k].single_t, feet[k].single_deficit, right=0.0)
    legs = stance_at(rows, constants(first.foot.body, first.meta_off_theta6))
    pitch = legs["pitch"]
    return VirtualLegFrames(t, legs["hip"], legs["knee"], legs["ankle"], legs["heel"], legs["metatarsal"], legs["toe"],
                            legs["theta3"], legs["theta4"], legs["theta5"], legs["theta6"], pitch,
                            leg_periods(pitch, first.meta_off_theta6), legs["overreach"])


@dataclass(frozen=True)
class OpenStance:
    """The frames on a window's last stance foot where the window's next step is not solved yet:
    that step's double support completes the foot's rules (:meth:`klaw_ocp.walk.Walk.stance_foot`),
    so these frames wait for it (:func:`open_points`)."""
    step: int            # the window's last step, whose stance foot it is
    rows: np.ndarray     # (r,) the frames
    tau: np.ndarray      # (r,) their step-local times
    hips: np.ndarray     # (r, 2) the leg's own hip in its plane
    side: int            # the leg: its index in skeleton.SIDES


def ground_legs(walk, samples, hips: dict, toe_off_hips: np.ndarray | None = None, open_last: bool = False):
    """The legs while their feet are on the ground: the virtual leg (§4.2) of each stance, from its
    heel strike through the next step's double support to toe-off, evaluated on its own stance
    times (so that its foot stays planted) with its hips ``hips[side]`` (n, 2) in its plane.

    Returns (the points (side, point, frame, 2) in SIDES and POINTS order, filled on the rows they
    cover; the rows covered (side, frame) bool), and with ``toe_off_hips`` (steps, 2), each step's
    hind leg's own hip at its toe-off, also :func:`toe_off_feet` of them, evaluated in the same pass
    (each call of the virtual legs costs mostly its fixed overhead); with ``open_last``, also the
    frames on the walk's last stance foot, covered but not filled (:class:`OpenStance`), else None."""
    n = len(samples.t)
    t_ds = np.array([s.plan.timings.t_ds for s in walk.steps])
    in_double_support = samples.tau <= t_ds[samples.step]
    # each stance foot with the step it lands in (step 0's hind foot stood before the walk began):
    # foot f is step f - 1's stance foot; its side alternates as stance_leg's does
    feet = [walk.steps[0].hind_foot] + [walk.stance_foot(k) for k in range(len(walk.steps))]
    right = np.array([stance_leg(k) == "right" for k in range(-1, len(walk.steps))])
    # every frame is on its own step's stance foot, and in the double support also on the
    # previous step's: the rows of each foot in turn, its own step's first (as a stable sort of
    # the feet leaves them), each in order
    later = np.flatnonzero(in_double_support)
    on_foot = np.concatenate([samples.step + 1, samples.step[later]])
    order = np.argsort(on_foot, kind="stable")
    which, rows = on_foot[order], np.concatenate([np.arange(n), later])[order]
    own = order < n
    tau = samples.tau[rows]
    # the stance foot's own times: its step's tau, then t_step on in the next step's
    complete = np.array([f.complete for f in feet])
    t_step = np.array([f.t_step for f in feet])
    t_leg = np.where(own, _stance_times(complete[which], t_step[which], tau), t_step[which] + tau)
    leg_hips = np.where(right[which][:, None], hips["right"][rows], hips["left"][rows])
    side = np.where(right[which], 0, 1)
    on_ground = np.zeros((2, n), bool)
    on_ground[side, rows] = True
    opened = None
    if open_last:
        # (the last foot's frames are its own step's: a double support's are on the foot before)
        last = which == len(walk.steps)
        opened = OpenStance(len(walk.steps) - 1, rows[last], tau[last], leg_hips[last], int(not right[-1]))
        which, rows, t_leg, leg_hips, side = which[~last], rows[~last], t_leg[~last], leg_hips[~last], side[~last]
    r = len(rows)
    if toe_off_hips is not None:
        # step j's hind foot is feet[j] (step 0's stood before the walk, step j's is step j - 1's stance)
        which = np.concatenate([which, np.arange(len(walk.steps))])
        t_leg = np.concatenate([t_leg, [s.hind_foot.t_toe_off for s in walk.steps]])
        leg_hips = np.concatenate([leg_hips, toe_off_hips])
    legs = stance_frames(feet, which, t_leg, leg_hips)
    points = planted_points(walk.spec.body, legs)
    filled = np.full((2, len(POINTS), n, 2), np.nan)
    filled[side, :, rows] = points[:r]
    ankle = POINTS.index("ankle")
    toe_off = (points[r:, ankle], legs.pitch[r:]) if toe_off_hips is not None else None
    return filled, on_ground, toe_off, opened


def _stance_times(complete: np.ndarray, t_step: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """A stance's own times at its step's ``tau``: the walk's last stance leg has no double support
    to complete its rules (not ``complete``), and the walk ends at the instant it would begin: that
    last instant keeps the single support's pitch (a round-off before t_step)."""
    return np.where(complete, tau, np.minimum(tau, np.nextafter(t_step, 0.0)))


def open_points(body, foot, opened: OpenStance) -> np.ndarray:
    """The points (r, point, 2) of the frames ``opened`` left on the stance foot ``foot``, now that
    the next step has completed its rules, as :func:`ground_legs` evaluates every other stance."""
    t = _stance_times(foot.complete, foot.t_step, opened.tau)
    return planted_points(body, stance_frames([foot], np.zeros(len(t), int), t, opened.hips))


def planted_points(body, legs: VirtualLegFrames) -> np.ndarray:
    """(n, point, 2): the legs' points as the body shows them (POINTS order): where a leg
    overreaches, its foot pulled towards the hip (:func:`_overreach_pull`) and the knee the inverse
    kinematics of the foot's ankle, as the foot hangs from it."""
    pull = _overreach_pull(legs)
    # (where no leg overreaches, np.where would pick every one of legs.knee: the inverse kinematics skipped)
    over = legs.overreach[:, None] > 0
    knee = np.where(over, leg_ik(body, legs.hip, legs.ankle + pull)[2], legs.knee) if over.any() else legs.knee
    return np.stack([(knee if name == "knee" else getattr(legs, name)) + (pull if name in _FOOT else 0.0)
                     for name in POINTS], axis=1)


def _overreach_pull(legs) -> np.ndarray:
    """(n, 2): where the hip is beyond the leg's reach of its foot (long steps, late in the double
    support), the straight leg ends short of the foot's ankle: the foot hangs from it, its toe off
    the ground a little early, rather than a shank stretched to the planted foot (the skeleton's
    segments are rigid) and a leg that jumps to the swing's posture at toe-off. The foot's points
    move by this."""
    toward_hip = legs.hip - legs.ankle
    return toward_hip * (legs.overreach / np.maximum(np.hypot(*toward_hip.T), 1e-12))[:, None]


def toe_off_feet(walk, hips_at) -> tuple[np.ndarray, np.ndarray]:
    """Each step's hind leg at its toe-off as the body shows it, its virtual leg on the leg's own
    hip in its plane (the swing leg of the step starts from it): the ankle (steps, 2) and the
    foot's pitch (steps,)."""
    feet = [s.hind_foot for s in walk.steps]
    every = np.arange(len(feet))
    _, own = hips_at(every, np.array([s.plan.timings.t_ds for s in walk.steps]))
    legs = stance_frames(feet, every, np.array([f.t_toe_off for f in feet]), own)
    return legs.ankle + _overreach_pull(legs), legs.pitch
