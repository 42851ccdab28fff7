"""The body's swing leg (§4.3, principle 2): the dynamics' thigh and knee, hung from the leg's own
hip in its plane, with the kinematic swing foot (:mod:`.swing_foot`) and its ground guard.

The planar model's swing leg hangs from the simulated hip; the body's swing leg hangs from its own
hip in its own plane (:class:`.body_motion.LegPlanes`), which the lateral displacement puts up to
a few millimetres away from it. Near a straight knee a millimetre of hip-to-ankle distance is
degrees of knee, so the body keeps the dynamics' hip-to-ankle *distance* (the dynamic knee
angle), pointed from its own hip at the model's ankle: the ankle then moves by that millimetre
along the leg, and the knee the body shows is the dynamic one. At heel strike the two hips
coincide (no lateral displacement), and the heel lands on the planned point. At toe-off the leg
continues the virtual leg, whose knee is the inverse kinematics of the leg's own hip and the
planted foot: there the body's leg starts at the virtual leg's ankle as the body shows it
(:func:`.body_motion.toe_off_ankles`) and blends into the model's ankle and the dynamic distance
over the first TOE_OFF_BLEND of swing1 (a smoothstep), so no angle jumps.

The foot (:meth:`.swing_foot.SwingFoot.lifted_foot`; every step's in one pass, :mod:`.swing_feet`):
the schedule, turned where it would enter the ground and, where the leg is too low for any foot,
lifted with the ankle by a bend of the knee. The guard sees the body's own leg on its grid, so
what it keeps above the ground is what the skeleton shows.
"""
from __future__ import annotations

import numpy as np

from ..dynamics.kinematics import foot_points_arrays
from .leg_geometry import leg_ik, smoothstep
from .swing_feet import lifted_feet
from .walk_samples import swing_curves

#: the fraction of swing1 over which the body's swing leg blends from the virtual leg's toe-off
#: posture (the model's ankle reached from the leg's own hip) into the dynamic knee angle
TOE_OFF_BLEND = 0.5


def _model_leg(body, swing, step, tau, simulated_hip):
    """The planar model's swing leg: (shank angle θ3 + θ4, ankle (n, 2)) from the simulated hip."""
    theta3, theta4 = swing(step, tau).T
    shank = theta3 + theta4
    knee = simulated_hip - body.l3 * np.column_stack([np.sin(theta3), np.cos(theta3)])
    return shank, knee - body.l4 * np.column_stack([np.sin(shank), np.cos(shank)])


def _body_leg(body, walk, swing, step, tau, simulated_hip, own_hip, toe_off_offset):
    """The body's swing leg before the foot's lift at samples of steps ``step`` and times ``tau``:
    (the dynamic shank angle θ3 + θ4, the ankle (n, 2) in the leg's plane). ``toe_off_offset``
    (steps, 2): the body's virtual-leg ankle at each step's toe-off less the model's."""
    shank, ankle = _model_leg(body, swing, step, tau, simulated_hip)
    dynamic = np.hypot(*(ankle - simulated_hip).T)
    feet = [s.swing_foot for s in walk.steps]
    t_to = np.array([f.t_toe_off for f in feet])[step]
    t1 = np.array([f.t1 for f in feet])[step]
    virtual = 1 - smoothstep(np.clip((tau - t_to) / (TOE_OFF_BLEND * (t1 - t_to)), 0.0, 1.0))
    towards = ankle + virtual[:, None] * toe_off_offset[step] - own_hip
    reached = np.hypot(*towards.T)
    distance = dynamic + virtual * (reached - dynamic)
    return shank, own_hip + towards * (distance / np.maximum(reached, 1e-12))[:, None]


def swing_legs(walk, step: np.ndarray, tau: np.ndarray, hips_at, toe_off_ankles: np.ndarray) -> dict:
    """The swing leg in its plane at samples of steps ``step`` (n,) and step-local times ``tau``
    (n,), all after their step's toe-off: its points (n, 2), "hip" .. "toe".
    ``hips_at(step, tau)`` gives the simulated hip and the swinging leg's own hip in its plane,
    (n, 2) each, at any such samples (the frames', and each step's guard grid);
    ``toe_off_ankles`` (steps, 2) the ankle of each step's virtual leg at its toe-off as the body
    shows it, which the swing leg starts from."""
    body, steps = walk.spec.body, walk.steps
    swing = swing_curves(walk)
    every = np.arange(len(steps))
    t_to = np.array([s.swing_foot.t_toe_off for s in steps])
    offset = toe_off_ankles - _model_leg(body, swing, every, t_to, hips_at(every, t_to)[0])[1]
    simulated, own = hips_at(step, tau)
    shank, ankle = _body_leg(body, walk, swing, step, tau, simulated, own, offset)
    # the swing foot's ground guard asks for each step's leg on its own grid: every step's grid in
    # one pass (a pass per step costs mostly numpy's fixed overheads)
    swinging, counts = np.unique(step, return_counts=True)
    grids = [steps[k].swing_foot.guard_grid() for k in swinging]
    grid_step, grid_t = np.repeat(swinging, [len(g) for g in grids]), np.concatenate(grids)
    grid_simulated, grid_own = hips_at(grid_step, grid_t)
    grid_shank, grid_ankle = _body_leg(body, walk, swing, grid_step, grid_t, grid_simulated, grid_own, offset)
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
