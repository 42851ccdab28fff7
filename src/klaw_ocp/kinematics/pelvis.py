"""The pelvis's second hip (§4.2, the determinants of gait; §2.4): pelvic rotation and list turn
the pelvis about the stance hip, the simulated one, and carry the swing leg's hip with them.

"By introducing a pelvis, the kinematics of the determinants basically add a second hip to the
locomotion model and must therefore be applied after the stance phase simulation but before the
simulation of the swing leg which uses the new position of this hip." The rotation is largest at
heel strike and least at mid-step, the list least at heel strike and largest at mid-step (§4.2).

**Timing.** The paper interpolates linearly between the boundary values. The swing leg's equations
of motion read the hip's acceleration (A.2), and a piecewise-linear angle has a velocity kink
there, an impulse in the swing model's hip acceleration at mid-step and at heel strike. We
interpolate with half cosines between the same boundary values instead (docs/paper-map.md): with
s = t/t_step,

    rotation(s) = ψ0·c(s) − ψ1·(1 − c(s)),   c(s) = (1 + cos πs)/2
    list(s)     = φ·sin²(πs)

``rotation`` is the stance side's hip forward of the swing side's (ψ0 at this step's heel strike,
−ψ1 at the next: the swing side forward), ``list`` the swing side down. Both have zero rate at
heel strike, so the hips' velocities are continuous where the legs trade roles.

**The second hip.** The pelvis is the skeleton's (``Rz(tilt) Rx(list) Ry(rotation)``, hips l0
apart on its lateral axis; tilt 0), turned about the stance hip, so the swing-side hip is the
stance hip plus::

    Δx = −l0 sin(rotation),   Δy = −l0 cos(rotation) sin(list)

At heel strike (list 0) the landing leg's hip is l0·sin ψ1 ahead of the stance hip; the next
stance starts from it (:func:`klaw_ocp.dynamics.heel_strike_state`'s ``hip_shift``), so each hip
moves continuously while the one-hip stance model's hip passes from one hip of the pelvis to the
other. Eq. 3 (:func:`klaw_ocp.gait.symmetry.step_constraints`) splits the step length accordingly:
each leg spans (sl − l0 sin ψ)/2, the first determinant of gait (the pelvis's rotation lengthens
the step without lowering the hip).

The functions take ``ops`` (numpy, or casadi for the swing models' symbolic hip) so that the body
(:mod:`klaw_ocp.body_motion`), the step's stages and the swing models use one formula.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PelvisSchedule:
    """One step's pelvis: ``width`` l0 (m); ``rotation_start`` ψ0 and ``rotation_end`` ψ1 (rad,
    at this step's heel strike and at the next; 0 where the walk starts or ends at rest, the feet
    side by side); ``list_peak`` φ (rad, at mid-step); ``t_step`` (s).

    Its fields may also be arrays (n,), one schedule per sample (:meth:`per_sample`): every
    formula is elementwise, so a walk's samples of many steps take one evaluation."""
    width: float
    rotation_start: float
    rotation_end: float
    list_peak: float
    t_step: float

    @classmethod
    def per_sample(cls, schedules, step) -> "PelvisSchedule":
        """The schedules ``schedules[step[i]]`` of samples i, as one schedule of arrays (n,)."""
        table = np.array([[p.width, p.rotation_start, p.rotation_end, p.list_peak, p.t_step] for p in schedules])
        return cls(*table[np.asarray(step, int)].T)

    @property
    def landing_shift(self) -> float:
        """How far (m) the landing leg's hip is ahead of the stance hip at the next heel strike."""
        return self.width * math.sin(self.rotation_end)

    def angles(self, t, ops=np):
        """(rotation, list) (rad) at step times ``t``: the stance side's hip forward, the swing side down."""
        return pelvis_angles(self.rotation_start, self.rotation_end, self.list_peak, self.t_step, t, ops)

    def swing_hip_offset(self, t, ops=np):
        """The swing-side hip minus the stance hip (x, y) and its first and second time derivatives."""
        return swing_hip_offset(self.width, self.rotation_start, self.rotation_end, self.list_peak,
                                self.t_step, t, ops)

    def swing_side_hips(self, t, hips, hip_vels=None):
        """The pelvis's other hip (n, 2) at step times ``t`` from the stance hips ``hips`` (n, 2)
        there; with the stance hips' velocities ``hip_vels``, (hips, velocities)."""
        (dx, dy), *rates = swing_hip_offset(self.width, self.rotation_start, self.rotation_end, self.list_peak,
                                            self.t_step, np.asarray(t, float), order=0 if hip_vels is None else 1)
        # the sums written into their columns (np.column_stack's wrapper cost more than them)
        other = np.array(hips, float)
        other[..., 0] += dx
        other[..., 1] += dy
        if hip_vels is None:
            return other
        vels = np.array(hip_vels, float)
        vels[..., 0] += rates[0][0]
        vels[..., 1] += rates[0][1]
        return other, vels


def _angles_and_rates(rotation_start, rotation_end, list_peak, t_step, t, ops, order: int = 2):
    """(rotation, list) at step times ``t`` and their time derivatives up to ``order``, each a
    tuple of order + 1 terms: rotation = span (1 + cos a)/2 − ψ1 and list = φ sin² a =
    φ (1 − cos 2a)/2, a = π t/t_step. The body asks for the angles alone and the hips for their
    rates: the terms they would drop were most of the pelvis's numpy calls."""
    k = math.pi / t_step   # a float, an array (one schedule per sample) or a CasADi symbol
    a = k * t
    span = rotation_start + rotation_end
    cos_a, sin_a = ops.cos(a), ops.sin(a)
    rotation, lowered = [span * (1 + cos_a) / 2 - rotation_end], [list_peak * sin_a ** 2]
    if order >= 1:
        rotation.append(-span * k * sin_a / 2)
        lowered.append(list_peak * k * ops.sin(2 * a))
    if order >= 2:
        rotation.append(-span * k * k * cos_a / 2)
        lowered.append(2 * list_peak * k * k * ops.cos(2 * a))
    return tuple(rotation), tuple(lowered)


def pelvis_angles(rotation_start, rotation_end, list_peak, t_step, t, ops=np):
    """(rotation, list) (rad) at step times ``t`` (see the module's docstring)."""
    rotation, lowered = _angles_and_rates(rotation_start, rotation_end, list_peak, t_step, t, ops, order=0)
    return rotation[0], lowered[0]


def swing_hip_offset(width, rotation_start, rotation_end, list_peak, t_step, t, ops=np, order: int = 2):
    """((Δx, Δy), (Δx', Δy'), (Δx'', Δy'')): the swing-side hip minus the stance hip in the sagittal
    plane and its time derivatives at step times ``t``, up to ``order`` (the tuple that long)."""
    (r, *rr), (q, *qq) = _angles_and_rates(rotation_start, rotation_end, list_peak, t_step, t, ops, order)
    sr, cr, sq = ops.sin(r), ops.cos(r), ops.sin(q)
    # dx = -l0 sin r, dy = -l0 cos r sin q
    out = [(-width * sr, -width * cr * sq)]
    if order >= 1:
        (r1, *_), (q1, *_), cq = rr, qq, ops.cos(q)
        out.append((-width * cr * r1, width * (sr * r1 * sq - cr * cq * q1)))
    if order >= 2:
        r2, q2 = rr[1], qq[1]
        out.append((width * (sr * r1 * r1 - cr * r2),
                    width * (cr * r1 * r1 * sq + sr * r2 * sq + 2 * sr * r1 * cq * q1
                             + cr * sq * q1 * q1 - cr * cq * q2)))
    return tuple(out)
