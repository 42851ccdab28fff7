"""The body's swing leg (§4.3, principle 2): the dynamics' thigh and knee, hung from the leg's own
hip in its plane, with the kinematic swing foot (:mod:`klaw_ocp.kinematics.swing_foot`) and its
ground guard (:mod:`.swing_foot_guard`).

The planar model's swing leg hangs from the simulated hip; the body's swing leg hangs from its own
hip in its own plane (:class:`.motion.LegPlanes`), which the lateral displacement puts up to
a few millimetres away from it. Near a straight knee a millimetre of hip-to-ankle distance is
degrees of knee, so the body keeps the dynamics' hip-to-ankle *distance* (the dynamic knee
angle), pointed from its own hip at the model's ankle: the ankle then moves by that millimetre
along the leg, and the knee the body shows is the dynamic one. At both ends the leg meets a
virtual leg (:func:`_end_offsets`), whose knee is the inverse kinematics of the leg's own hip and
the planted foot: at toe-off the body's leg starts at the virtual leg's ankle and foot pitch as
the body shows them (:func:`.motion.toe_off_feet`) and blends into the model's ankle, the
dynamic distance and the scheduled foot over the first TOE_OFF_BLEND of swing1; over swing3 it
blends into the next stance's heel-strike posture (its knee flexed where
:mod:`klaw_ocp.kinematics.landing` says, its foot then a little more toe-up), the heel on the
planned point (the two hips coincide there: no lateral displacement). Smoothsteps both, so no
angle jumps.

The foot (:func:`.swing_foot_guard.lifted_foot`; every step's in one pass,
:func:`.swing_foot_guard.lifted_feet`): the schedule, turned where it would enter the ground and,
where the leg is too low for any foot, lifted with the ankle by a bend of the knee. The guard sees the body's own leg on its grid, so
what it keeps above the ground is what the skeleton shows.
"""
from __future__ import annotations

import numpy as np

from ..dynamics.points import foot_points_arrays
from ..kinematics.leg_geometry import clamp, leg_fk, leg_ik, smoothstep
from ..kinematics.swing_foot import SCHEDULE_FIELDS, schedule_angles
from .swing_foot_guard import guard_grid, lifted_feet
from .walk_samples import swing_curves

#: the fraction of swing1 over which the body's swing leg blends from the virtual leg's toe-off
#: posture (the model's ankle reached from the leg's own hip) into the dynamic knee angle
TOE_OFF_BLEND = 0.5


def _model_leg(body, swing, step, tau, simulated_hip):
    """The planar model's swing leg: (shank angle θ3 + θ4, ankle (n, 2)) from the simulated hip."""
    shank, _, ankle = leg_fk(body, simulated_hip, *swing(step, tau).T)
    return shank, ankle


def _body_leg(body, walk, swing, step, tau, simulated_hip, own_hip, toe_off, landing):
    """The body's swing leg before the foot's lift at samples of steps ``step`` and times ``tau``:
    (the shank angle the scheduled foot is set on, the ankle (n, 2) in the leg's plane).
    ``toe_off`` and ``landing``: :func:`_end_offsets` at each step's toe-off and heel strike, blended
    out over the first TOE_OFF_BLEND of swing1 and in over swing3."""
    shank, ankle = _model_leg(body, swing, step, tau, simulated_hip)
    dynamic = np.hypot(*(ankle - simulated_hip).T)
    feet = [s.swing_foot for s in walk.steps]
    t_to, t1, t2, t_hs = (np.array([getattr(f, name) for f in feet])[step]
                          for name in ("t_toe_off", "t1", "t2", "t_heel_strike"))
    leaves = 1 - smoothstep((tau - t_to) / (TOE_OFF_BLEND * (t1 - t_to)))     # (smoothstep clamps to [0, 1])
    lands = smoothstep((tau - t2) / np.maximum(t_hs - t2, 1e-12))
    towards = ankle + leaves[:, None] * toe_off[0][step] + lands[:, None] * landing[0][step] - own_hip
    reached = np.hypot(*towards.T)
    # swing3's leg comes in straight (eq. 5's lock), where the knee goes as the square root of the
    # distance's shortfall: the distance blends in as lands², so the knee starts bending at rest
    # (as lands, a smooth distance started the knee at a finite rate: a 70-110 deg/s jump at t2)
    distance = dynamic + np.maximum(leaves, lands * lands) * (reached - dynamic)
    turn = leaves * toe_off[1][step] + lands * landing[1][step]
    return shank + turn, own_hip + towards * (distance / np.maximum(reached, 1e-12))[:, None]


def _end_offsets(walk, swing, steps, t, simulated_hip, ankles, pitches) -> tuple[np.ndarray, np.ndarray]:
    """How the body's swing leg differs from the model's where it meets a virtual leg, at times
    ``t`` of the steps ``steps`` (indices), the simulated hip there ``simulated_hip`` (k, 2): the
    virtual leg's ankles (k, 2) and foot pitches (k,) against the model's ankle and scheduled
    foot. Returns (the ankle offsets (all steps, 2),
    the turns (rad, all steps) of the shank the scheduled foot is set on that give the virtual
    foot's pitch); zero for the steps not given."""
    body = walk.spec.body
    ankle_offset, shank_offset = np.zeros((len(walk.steps), 2)), np.zeros(len(walk.steps))
    if len(steps):
        model_shank, model_ankle = _model_leg(body, swing, steps, t, simulated_hip)
        feet = [walk.steps[k].swing_foot for k in steps]     # their schedules, in one pass
        theta5 = schedule_angles(np.asarray(t, float), {name: np.array([getattr(f, name) for f in feet])
                                                        for name in SCHEDULE_FIELDS}, clamp)[0]
        ankle_offset[steps] = ankles - model_ankle
        # the scheduled foot's backward sole direction is π/2 - shank + θ5; the virtual foot's, π - pitch
        shank_offset[steps] = (theta5 - np.pi / 2 + pitches) - model_shank
    return ankle_offset, shank_offset


def _landings(walk, swing, simulated_hip) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_end_offsets` at each step's heel strike (the simulated hips there (steps - 1, 2)):
    the swing leg lands as the next stance's virtual leg starts (:mod:`klaw_ocp.kinematics.landing`:
    its knee may be flexed, its foot then a little more toe-up about the same heel point). The
    walk's last step has no next stance."""
    steps = walk.steps
    lands = [walk.stance_foot(k) for k in range(1, len(steps))]
    ankles = np.vstack([f.foot.ankle_at([f.rocker_pitch], f.meta_off_theta6) for f in lands]) if lands else np.zeros((0, 2))
    return _end_offsets(walk, swing, np.arange(len(lands)), _heel_strikes(walk), simulated_hip, ankles,
                        np.array([f.rocker_pitch for f in lands]))


def _heel_strikes(walk) -> np.ndarray:
    """The step-local times of every step's heel strike but the last's (the next stance's start)."""
    return np.array([s.swing_foot.t_heel_strike for s in walk.steps[:-1]])


def swing_legs(walk, step: np.ndarray, tau: np.ndarray, hips_at, toe_off_feet, hips=None) -> dict:
    """The swing leg in its plane at samples of steps ``step`` (n,) and step-local times ``tau``
    (n,), all after their step's toe-off: its points (n, 2), "hip" .. "toe".
    ``hips_at(step, tau)`` gives the simulated hip and the swinging leg's own hip in its plane,
    (n, 2) each, at any such samples (the frames', and each step's guard grid);
    ``toe_off_feet``: the ankle (steps, 2) and the foot's pitch (steps,) of each step's virtual leg
    at its toe-off as the body shows it (:func:`.motion.toe_off_feet`), which the swing leg
    starts from; ``hips``: ``hips_at(step, tau)`` when the caller has it already."""
    body, steps = walk.spec.body, walk.steps
    swing = swing_curves(walk)
    # the swing foot's ground guard asks for each step's leg on its own grid: every step's grid in
    # one pass (a pass per step costs mostly numpy's fixed overheads)
    swinging, counts = np.unique(step, return_counts=True)
    grids = [guard_grid(steps[k].swing_foot) for k in swinging]
    grid_step, grid_t = np.repeat(swinging, [len(g) for g in grids]), np.concatenate(grids)
    # the hips at every toe-off, every heel strike and on the grids, in one pass
    every, t_to, t_hs = np.arange(len(steps)), np.array([s.swing_foot.t_toe_off for s in steps]), _heel_strikes(walk)
    at_step, at_t = np.r_[every, np.arange(len(t_hs)), grid_step], np.r_[t_to, t_hs, grid_t]
    at_simulated, at_own = hips_at(at_step, at_t)
    ends = len(every) + len(t_hs)
    toe_off = _end_offsets(walk, swing, every, t_to, at_simulated[:len(every)], *toe_off_feet)
    landing = _landings(walk, swing, at_simulated[len(every):ends])
    simulated, own = hips_at(step, tau) if hips is None else hips
    shank, ankle = _body_leg(body, walk, swing, step, tau, simulated, own, toe_off, landing)
    grid_simulated, grid_own = at_simulated[ends:], at_own[ends:]
    grid_shank, grid_ankle = _body_leg(body, walk, swing, grid_step, grid_t, grid_simulated, grid_own, toe_off, landing)
    order = np.argsort(step, kind="stable")          # the samples step by step, each step's in order
    theta5, theta6, lift = np.empty(len(tau)), np.empty(len(tau)), np.empty(len(tau))
    theta5[order], theta6[order], lift[order] = lifted_feet(
        body, [steps[k].swing_foot for k in swinging], np.split(tau[order], np.cumsum(counts)[:-1]), grids,
        grid_own, grid_ankle, grid_shank)
    heel, metatarsal, toe = foot_points_arrays(ankle, shank, theta5, theta6, body.l8, body.l9, body.l12, body.l13)
    up = np.column_stack([np.zeros(len(tau)), lift])   # the foot carried up with the lifted ankle
    ankle, heel, metatarsal, toe = ankle + up, heel + up, metatarsal + up, toe + up
    _, _, knee = leg_ik(body, own, ankle)
    return {"hip": own, "knee": knee, "ankle": ankle, "heel": heel, "metatarsal": metatarsal, "toe": toe}
