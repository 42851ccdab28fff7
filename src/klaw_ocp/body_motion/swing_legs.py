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
from ..kinematics.leg_geometry import clamp, foot_pieces, leg_fk, leg_ik, smoothstep
from ..kinematics.swing_foot import SCHEDULE_FIELDS, schedule_angles
from .swing_foot_guard import guard_grid, lifted_feet
from .walk_samples import swing_curves, swung_steps

#: the fraction of swing1 over which the body's swing leg blends from the virtual leg's toe-off
#: posture (the model's ankle reached from the leg's own hip) into the dynamic knee angle
TOE_OFF_BLEND = 0.5


#: the columns of a step's swing schedule that the blends read
_T_TOE_OFF, _T1, _T2, _T_HEEL_STRIKE = (SCHEDULE_FIELDS.index(name)
                                        for name in ("t_toe_off", "t1", "t2", "t_heel_strike"))


def _schedules(walk) -> np.ndarray:
    """(steps, len(SCHEDULE_FIELDS)): each step's swing foot's schedule, one row a step (read once
    for every pass that indexes it by step; :func:`.walk_samples.swung_steps`)."""
    return np.array([[getattr(s.swing_foot, name) for name in SCHEDULE_FIELDS] for s in swung_steps(walk)], float)


def _model_leg(body, swing, step, tau, simulated_hip):
    """The planar model's swing leg: (shank angle θ3 + θ4, ankle (n, 2)) from the simulated hip."""
    shank, _, ankle = leg_fk(body, simulated_hip, *swing(step, tau).T)
    return shank, ankle


def _body_leg(schedules, step, tau, model, simulated_hip, own_hip, toe_off, landing):
    """The body's swing leg before the foot's lift at samples of steps ``step`` and times ``tau``,
    the model's leg there ``model`` (:func:`_model_leg`): (the shank angle the scheduled foot is
    set on, the ankle (n, 2) in the leg's plane). ``toe_off`` and ``landing``: :func:`_end_offsets`
    at each step's toe-off and heel strike, blended out over the first TOE_OFF_BLEND of swing1 and
    in over swing3."""
    shank, ankle = model
    dynamic = np.hypot(*(ankle - simulated_hip).T)
    t_to, t1, t2, t_hs = schedules[step][:, [_T_TOE_OFF, _T1, _T2, _T_HEEL_STRIKE]].T
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


def _end_offsets(schedules, steps, t, model, ankles, pitches) -> tuple[np.ndarray, np.ndarray]:
    """How the body's swing leg differs from the model's where it meets a virtual leg, at times
    ``t`` of the steps ``steps`` (indices), the model's leg there ``model`` (:func:`_model_leg`):
    the virtual leg's ankles (k, 2) and foot pitches (k,) against the model's ankle and scheduled
    foot. Returns (the ankle offsets (k, 2), the turns (rad, k) of the shank the scheduled foot
    is set on that give the virtual foot's pitch)."""
    model_shank, model_ankle = model
    theta5 = schedule_angles(np.asarray(t, float), dict(zip(SCHEDULE_FIELDS, schedules[steps].T)), clamp)[0]
    # the scheduled foot's backward sole direction is π/2 - shank + θ5; the virtual foot's, π - pitch
    return ankles - model_ankle, (theta5 - np.pi / 2 + pitches) - model_shank


def _landing_feet(walk) -> tuple[np.ndarray, np.ndarray]:
    """The next stance's virtual leg at each step's heel strike: its ankle (steps - 1, 2) and foot
    pitch (steps - 1,) (:mod:`klaw_ocp.kinematics.landing`: its knee may be flexed, its foot then a
    little more toe-up about the same heel point). The walk's last step has no next stance."""
    lands = [walk.stance_foot(k) for k in range(1, len(walk.steps))]
    # each landing's one ankle on floats (FootPieces.ankle_float: FlatFoot.ankle_at's numbers, held
    # to them by tests/test_few_sample_paths.py), not an array pass per landing
    ankles = (np.array([foot_pieces(f.foot.body, f.meta_off_theta6).ankle_float(f.foot.ankle_x, float(f.rocker_pitch))
                        for f in lands]) if lands else np.zeros((0, 2)))
    return ankles, np.array([f.rocker_pitch for f in lands])


def swing_samples(walk, swinging: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The samples (steps (k,), step-local times (k,)) at which :func:`swing_legs` asks for the
    hips when the steps ``swinging`` (unique, increasing) swing at its frames: every step's toe-off,
    every heel strike but the last step's (it has no next stance) and each swinging step's guard
    grid, in that order."""
    return _swing_samples(walk, swinging)[:2]


def _swing_samples(walk, swinging: np.ndarray) -> tuple[np.ndarray, np.ndarray, list]:
    """:func:`swing_samples`, and the guard grids."""
    steps, swung = walk.steps, swung_steps(walk)
    grids = [guard_grid(steps[k].swing_foot) for k in swinging]
    m = len(swung)
    return (np.concatenate([np.arange(m), np.arange(len(steps) - 1), np.repeat(swinging, [len(g) for g in grids])]),
            np.concatenate([[s.swing_foot.t_toe_off for s in swung], [s.swing_foot.t_heel_strike for s in steps[:-1]]]
                           + grids), grids)


def swing_legs(walk, step: np.ndarray, tau: np.ndarray, hips_at, toe_off_feet, hips=None, sampled=None) -> dict:
    """The swing leg in its plane at samples of steps ``step`` (n,) and step-local times ``tau``
    (n,), all after their step's toe-off: its points (n, 2), "hip" .. "toe".
    ``hips_at(step, tau)`` gives the simulated hip and the swinging leg's own hip in its plane,
    (n, 2) each, at any such samples (the frames', and each step's guard grid);
    ``toe_off_feet``: the ankle (steps, 2) and the foot's pitch (steps,) of each step's virtual leg
    at its toe-off as the body shows it (:func:`.motion.toe_off_feet`), which the swing leg
    starts from; ``hips``: ``hips_at(step, tau)`` when the caller has it already; ``sampled``:
    (the swinging steps, ``hips_at`` of their :func:`swing_samples`) when the caller has those.

    The model's leg is evaluated once for every sample the body asks for (each step's toe-off and
    heel strike, each swinging step's guard grid and the frames), and the body's leg once for the
    grids and the frames: each pass costs mostly numpy's fixed overheads, not its samples."""
    body, steps = walk.spec.body, walk.steps
    swing, schedules = swing_curves(walk), _schedules(walk)
    # the swing foot's ground guard asks for each step's leg on its own grid: every step's grid in
    # one pass (a pass per step costs mostly numpy's fixed overheads)
    swinging, counts = np.unique(step, return_counts=True)
    at_step, at_t, grids = _swing_samples(walk, swinging)
    if sampled is not None and np.array_equal(sampled[0], swinging):
        at_simulated, at_own = sampled[1]
    else:
        at_simulated, at_own = hips_at(at_step, at_t)
    simulated, own = hips_at(step, tau) if hips is None else hips
    # each swung step's toe-off, and the heel strike of each step before the last (a last step that
    # is only its stance half is where the one before it lands: :func:`.walk_samples.swung_steps`)
    m, landings = len(swung_steps(walk)), len(steps) - 1
    ends = m + landings
    end_step, end_t, grid_step, grid_t = at_step[:ends], at_t[:ends], at_step[ends:], at_t[ends:]
    g = len(grid_t)
    legs_step, legs_tau = np.concatenate([grid_step, step]), np.concatenate([grid_t, tau])
    shank, ankle = _model_leg(body, swing, np.concatenate([end_step, legs_step]), np.concatenate([end_t, legs_tau]),
                              np.concatenate([at_simulated, simulated]))
    landing_ankles, landing_pitches = _landing_feet(walk)
    ankle_offset, shank_offset = _end_offsets(schedules, end_step, end_t, (shank[:ends], ankle[:ends]),
                                              np.concatenate([toe_off_feet[0][:m], landing_ankles]),
                                              np.concatenate([toe_off_feet[1][:m], landing_pitches]))
    # at the toe-offs, and at the heel strikes (a walk's last step's none: zero)
    toe_off = (ankle_offset[:m], shank_offset[:m])
    landing = (np.concatenate([ankle_offset[m:], np.zeros((m - landings, 2))]),
               np.concatenate([shank_offset[m:], np.zeros(m - landings)]))
    legs_own = np.concatenate([at_own[ends:], own])
    legs_shank, legs_ankle = _body_leg(schedules, legs_step, legs_tau, (shank[ends:], ankle[ends:]),
                                       np.concatenate([at_simulated[ends:], simulated]), legs_own, toe_off, landing)
    order = np.argsort(step, kind="stable")          # the samples step by step, each step's in order
    theta5, theta6, lift = np.empty(len(tau)), np.empty(len(tau)), np.empty(len(tau))
    theta5[order], theta6[order], lift[order] = lifted_feet(
        body, [steps[k].swing_foot for k in swinging], np.split(tau[order], np.cumsum(counts)[:-1]), grids,
        legs_own[:g], legs_ankle[:g], legs_shank[:g])
    shank, ankle = legs_shank[g:], legs_ankle[g:]
    heel, metatarsal, toe = foot_points_arrays(ankle, shank, theta5, theta6, body.l8, body.l9, body.l12, body.l13)
    up = np.zeros((len(tau), 2))
    up[:, 1] = lift                                  # the foot carried up with the lifted ankle
    ankle, heel, metatarsal, toe = ankle + up, heel + up, metatarsal + up, toe + up
    _, _, knee = leg_ik(body, own, ankle)
    return {"hip": own, "knee": knee, "ankle": ankle, "heel": heel, "metatarsal": metatarsal, "toe": toe}
