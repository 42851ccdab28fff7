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
dynamic distance and the scheduled foot over the first TOE_OFF_BLEND (:mod:`.swing_kernel`) of swing1; over swing3 it
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

from ..kinematics.leg_geometry import foot_pieces
from ..kinematics.swing_foot import SCHEDULE_FIELDS
from .swing_foot_guard import guard_grid, guarded_frames
from .swing_kernel import FOOT_COLUMNS, LEG_COLUMNS, NODE, feet_at, legs_at
from .swing_kernel import constants as swing_constants
from .walk_samples import swing_curves, swung_steps

#: where _leg_rows and swing_legs write each part of the kernel's rows
_U = LEG_COLUMNS.index("u")
_NODE0, _NODE1 = ([LEG_COLUMNS.index(f"{name}_{end}") for name in NODE] for end in "01")
_MODEL_HIP = [LEG_COLUMNS.index("model_hip_x"), LEG_COLUMNS.index("model_hip_y")]
_OWN_HIP = [LEG_COLUMNS.index("own_x"), LEG_COLUMNS.index("own_y")]
_TAU, _SCHEDULE = LEG_COLUMNS.index("tau"), [LEG_COLUMNS.index(name) for name in SCHEDULE_FIELDS]
_OFFSETS = [LEG_COLUMNS.index(name) for name in ("toe_off_dx", "toe_off_dy", "toe_off_turn",
                                                 "landing_dx", "landing_dy", "landing_turn")]
_FOOT_TAU, _FOOT_SCHEDULE = FOOT_COLUMNS.index("tau"), [FOOT_COLUMNS.index(name) for name in SCHEDULE_FIELDS]
_FOOT_REST = [FOOT_COLUMNS.index(name) for name in ("knee", "turn", "lift", "shank", "ankle_x", "ankle_y", "own_x", "own_y")]


def _schedules(walk) -> np.ndarray:
    """(steps, len(SCHEDULE_FIELDS)): each step's swing foot's schedule, one row a step (read once
    for every pass that indexes it by step; :func:`.walk_samples.swung_steps`)."""
    return np.array([[getattr(s.swing_foot, name) for name in SCHEDULE_FIELDS] for s in swung_steps(walk)], float)


def _leg_rows(curves, schedules, step, tau, model_hips, own_hips) -> np.ndarray:
    """:mod:`.swing_kernel`'s leg rows of samples of steps ``step`` (indices into the walk's swung
    steps) at times ``tau``: the swing's curves ``curves`` (walk_samples.StepCurves) at their
    intervals, the model's swing hips and the legs' own hips (n, 2), the steps' schedules
    (:func:`_schedules`); the offsets at toe-off and heel strike zero (:func:`_end_offsets` gives
    them: the caller writes them)."""
    rows = np.zeros((len(tau), len(LEG_COLUMNS)))
    u, interval = curves.locate(step, tau)
    nodes = np.column_stack([curves.u, curves.values, curves.rates])
    rows[:, _U], rows[:, _NODE0], rows[:, _NODE1] = u, nodes[interval], nodes[interval + 1]
    rows[:, _MODEL_HIP], rows[:, _OWN_HIP], rows[:, _TAU] = model_hips, own_hips, tau
    rows[:, _SCHEDULE] = schedules[step]
    return rows


def _end_offsets(walk, ends: dict, toe_off_feet, m: int, landing=None) -> tuple[tuple, tuple]:
    """How the body's swing leg differs from the model's where it meets a virtual leg, at each
    swung step's toe-off and at the heel strikes that have a next stance (:func:`landing_feet`;
    the model's leg there ``ends``, :func:`.swing_kernel.leg_function`'s outputs): the ankle
    offsets (k, 2) and the turns (rad, k) of the shank the scheduled foot is set on that give the
    virtual foot's pitch, as (toe-off offsets, landing offsets), the landings' padded with zeros to
    the m swung steps (a walk's last step has no next stance)."""
    landing_ankles, landing_pitches = _landing_feet(walk, landing)
    ankles = np.concatenate([toe_off_feet[0][:m], landing_ankles])
    pitches = np.concatenate([toe_off_feet[1][:m], landing_pitches])
    # the scheduled foot's backward sole direction is π/2 - shank + θ5; the virtual foot's, π - pitch
    ankle_offset = ankles - ends["model_ankle"]
    shank_offset = (ends["timed_theta5"] - np.pi / 2 + pitches) - ends["model_shank"]
    landings = len(landing_pitches)
    return ((ankle_offset[:m], shank_offset[:m]),
            (np.concatenate([ankle_offset[m:], np.zeros((m - landings, 2))]),
             np.concatenate([shank_offset[m:], np.zeros(m - landings)])))


def landing_feet(walk, landing=None) -> list:
    """The feet the steps' swing legs land on: each next stance's foot (the walk's last step has
    none), and ``landing`` (a :class:`~klaw_ocp.kinematics.virtual_leg.StanceFoot`) where the
    walk's last step's next stance is planned but not solved yet (:func:`.motion.prepare_body`)."""
    return [walk.stance_foot(k) for k in range(1, len(walk.steps))] + ([] if landing is None else [landing])


def landing_pose(foot) -> tuple:
    """All the swing leg reads of the foot it lands on (its heel-strike pose): the body, the
    meta-off limit, the ankle's x and the heel-strike pitch."""
    return foot.foot.body, foot.meta_off_theta6, foot.foot.ankle_x, float(foot.rocker_pitch)


def _landing_feet(walk, landing=None) -> tuple[np.ndarray, np.ndarray]:
    """The next stance's virtual leg at each heel strike that has one (:func:`landing_feet`): its
    ankle (k, 2) and foot pitch (k,) (:mod:`klaw_ocp.kinematics.landing`: its knee may be flexed,
    its foot then a little more toe-up about the same heel point)."""
    poses = [landing_pose(f) for f in landing_feet(walk, landing)]
    # each landing's one ankle on floats (FootPieces.ankle_float: FlatFoot.ankle_at's numbers, held
    # to them by tests/test_few_sample_paths.py), not an array pass per landing
    ankles = (np.array([foot_pieces(body, meta_off).ankle_float(ankle_x, pitch) for body, meta_off, ankle_x, pitch in poses])
              if poses else np.zeros((0, 2)))
    return ankles, np.array([pitch for *_, pitch in poses])


def swing_samples(walk, swinging: np.ndarray, landing=None) -> tuple[np.ndarray, np.ndarray, list]:
    """The samples (steps (k,), step-local times (k,)) at which :func:`swing_legs` asks for the
    hips when the steps ``swinging`` (unique, increasing) swing at its frames: every step's toe-off,
    every heel strike that has a next stance (:func:`landing_feet`; ``landing`` as there) and each
    swinging step's guard grid, in that order; and the guard grids."""
    steps, swung = walk.steps, swung_steps(walk)
    grids = [guard_grid(steps[k].swing_foot) for k in swinging]
    m, landings = len(swung), len(steps) - (landing is None)
    return (np.concatenate([np.arange(m), np.arange(landings), np.repeat(swinging, [len(g) for g in grids])]),
            np.concatenate([[s.swing_foot.t_toe_off for s in swung], [s.swing_foot.t_heel_strike for s in steps[:landings]]]
                           + grids), grids)


def swing_legs(walk, step: np.ndarray, tau: np.ndarray, hips_at, toe_off_feet, hips=None, sampled=None,
               landing=None) -> dict:
    """The swing leg in its plane at samples of steps ``step`` (n,) and step-local times ``tau``
    (n,), all after their step's toe-off: its points (n, 2), "hip" .. "toe".
    ``hips_at(step, tau)`` gives the planar model's swing hip and the swinging leg's own hip in its
    plane, (n, 2) each, at any such samples (the frames', and each step's guard grid);
    ``toe_off_feet``: the ankle (steps, 2) and the foot's pitch (steps,) of each step's virtual leg
    at its toe-off as the body shows it (:func:`.motion.toe_off_feet`), which the swing leg
    starts from; ``hips``: ``hips_at(step, tau)`` when the caller has it already; ``sampled``:
    (the swinging steps, their :func:`swing_samples`, ``hips_at`` of those) when the caller has them;
    ``landing``: the foot the walk's last step lands on where its next step is not solved yet
    (:func:`landing_feet`).

    Compiled (:mod:`.swing_kernel`) on either side of the ground guard's smooth turns: the model's
    leg and the timed foot at each step's toe-off and heel strike (the ends), then the body's leg,
    its foot's schedule and the ground's window on the guard grids and at the frames, one call;
    the guard's turn and lift on the grids (numpy, :func:`.swing_foot_guard.guarded_frames`); the
    foot and the knee at the frames, one call."""
    body, steps = walk.spec.body, walk.steps
    swing, schedules, shared = swing_curves(walk), _schedules(walk), swing_constants(body)
    swinging, counts = np.unique(step, return_counts=True)
    if sampled is not None and np.array_equal(sampled[0], swinging):
        (at_step, at_t, grids), (at_model, at_own) = sampled[1:]
    else:
        at_step, at_t, grids = swing_samples(walk, swinging, landing)
        at_model, at_own = hips_at(at_step, at_t)
    model, own = hips_at(step, tau) if hips is None else hips
    # each swung step's toe-off, and each heel strike that has a next stance (a last step that is
    # only its stance half is where the one before it lands: :func:`.walk_samples.swung_steps`; a
    # ``landing`` where none is in the walk yet), then every step's guard grid and the frames: their rows at once, the ends' first (they give
    # the offsets the others' rows carry)
    m = len(swung_steps(walk))
    ends = m + len(steps) - (landing is None)
    rows = _leg_rows(swing, schedules, np.concatenate([at_step, step]), np.concatenate([at_t, tau]),
                     np.concatenate([at_model, model]), np.concatenate([at_own, own]))
    toe_off, lands = _end_offsets(walk, legs_at(rows[:ends], shared, ends=True), toe_off_feet, m, landing)
    legs_own, legs_step = rows[ends:, _OWN_HIP], np.concatenate([at_step[ends:], step])
    rows[ends:, _OFFSETS] = np.column_stack([*toe_off[0].T, toe_off[1], *lands[0].T, lands[1]])[legs_step]
    leg = legs_at(rows[ends:], shared)
    g = len(legs_step) - len(tau)
    grid = {name: value[:g] for name, value in leg.items()}
    window = (grid["lowest"], grid["highest"], grid["fits"] > 0.5, grid["level"])
    order = np.argsort(step, kind="stable")          # the samples step by step, each step's in order
    guarded = guarded_frames(body, np.split(tau[order], np.cumsum(counts)[:-1]), grids, legs_own[:g], grid["ankle"],
                             grid["shank"], grid["theta5"], grid["theta6"], window, grid["required"], grid["knee"])
    turn, lift, knee = (np.empty(len(tau)) for _ in range(3))
    turn[order], lift[order], knee[order] = guarded
    foot_rows = np.empty((len(tau), len(FOOT_COLUMNS)))
    foot_rows[:, _FOOT_TAU], foot_rows[:, _FOOT_SCHEDULE] = tau, schedules[step]
    foot_rows[:, _FOOT_REST] = np.column_stack([knee, turn, lift, leg["shank"][g:], leg["ankle"][g:], own])
    foot = feet_at(foot_rows, shared)
    return {"hip": own, "knee": foot["knee"], "ankle": foot["ankle"], "heel": foot["heel"],
            "metatarsal": foot["metatarsal"], "toe": foot["toe"]}
