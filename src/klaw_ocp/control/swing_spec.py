"""The three swing subphases as boundary-value problems (section 4.3).

- ``swing1`` (toe-off to 50 % of t_swing): unknowns F_theta3's fall and mean; theta3 reaches its
  peak at t1 (its eq. 3 value, or ``terminal_swing_retraction`` ahead of it, or further ahead
  where the swing ankle needs it: control/swing_clearance.py) with theta3d = 0 ("the hip angle
  reaches a maximum", §4.3).
- ``swing2`` (to 85 %): unknowns F_theta4's fall and mean and the hip position actuator of the
  recovery loop (held at 0 unless the toe would not clear the ground); the knee reaches full
  extension (theta4 = 0) at t2 with theta4d = 0, so that swing3's lock is not an impact. Path
  functions: toe height, kept above the toe-clearance attribute, and
  heel height, reported only (no lower bound: the straight leg of short steps cannot keep the
  scheduled heel up, docs/paper-map.md; the body's foot is lifted instead, body_motion/swing_foot_guard.py).
- ``swing2_closing``: a walk's closing step's swing2, whose leg comes down all but vertical
  beside the stance leg: the recovery actuator's place is taken by a torque a s + b s² added to
  the hold (two unknowns), and the thigh ends on its reference at t2, moving with it (two more
  final conditions), so that swing3 does not have to pull back a thigh the knee's braking threw
  forward. No toe-clearance bound: the foot lands in place, where the body's ground guard shows it.
- ``swing3`` (to 100 %): unknown constant hip moment; theta3 reaches its eq. 3 value exactly at
  t_swing, where the heel lands on the ground (eq. 3 geometry). Path function: the heel's
  height (reported as the step's heel clearance, not constrained: the one unknown is fixed by
  the landing).
"""
from __future__ import annotations

import casadi as ca

from .. import choices
from ..casadi_builds import built_once
from ..solvers.problem import SubphaseSpec
from . import swing_law as law
from .stance_law import STANCE_CONTEXT, stance_plausible
from .stance_spec import stance_lock_events

_NC = len(law.SWING_CONTEXT)
SWING2_PATH = ("toe_height", "heel_height")
SWING3_PATH = ("heel_height",)
SWING1_UNKNOWNS = ("F_theta3_fall", "F_theta3_mean")
#: the recovery actuator stays at index 1 (held fixed unless the toe would touch the ground)
SWING2_UNKNOWNS = ("F_theta4_fall", "hip_actuator", "F_theta4_mean")
#: a walk's closing step: the actuator's place taken by the torque a s + b s² added to the hold
#: (swing_law.closing_swing2_torques), with b last
CLOSING_SWING2_UNKNOWNS = ("F_theta4_fall", "F_theta3_linear", "F_theta4_mean", "F_theta3_quadratic")


def _spec(name, state, unknowns, rhs, forces, final, path=None, path_names=(), lock_rule=choices.DEFAULT_LOCK_RULE,
          pairing=((0, 0),), subphase=None):
    x, t = ca.SX.sym("x", len(state)), ca.SX.sym("t")
    u, c = ca.SX.sym("u", len(unknowns)), ca.SX.sym("c", _NC)
    args = [x, t, u, c]
    return SubphaseSpec(
        name=name, state_names=tuple(state), unknown_names=tuple(unknowns),
        context_names=law.SWING_CONTEXT.names,
        rhs=ca.Function(f"{name}_rhs", args, [rhs(*args)]),
        final=ca.Function(f"{name}_final", [x, c], [final(x, c)]),
        outputs=ca.Function(f"{name}_outputs", args, [forces(*args)]),
        output_names=law.SWING_FORCES,
        path=ca.Function(f"{name}_path", args, [path(*args)]) if path else None,
        path_names=tuple(path_names),
        events=stance_lock_events(len(state), len(unknowns), _NC, lock_rule),
        pairing=pairing,
        # the stance the swing re-simulates (assumption 4) must stay a walk's stance
        plausible=ca.Function(f"{name}_plausible", [x, c], [stance_plausible(x[:6], c[: len(STANCE_CONTEXT)])]),
        subphase=subphase,
    )


@built_once
def swing_specs(lock_rule: str = choices.DEFAULT_LOCK_RULE) -> dict:
    """``{"swing1": spec, "swing2": spec, "swing3": spec}``, built once per lock rule."""
    theta3_error = lambda x, c: x[6] - law.names(c).theta3_target
    peak_error = lambda x, c: x[6] - law.names(c).theta3_peak
    # the thigh at its peak and at rest at t1 (x[8] = theta3d); the knee straight and at rest at
    # t2 (x[7], x[9]). Plain shooting pairs each mean with the rate, each fall with the position
    # (control/torques.py: decaying_exponential_about_mean).
    return {
        "swing1": _spec("swing1", law.SWING1_STATE, SWING1_UNKNOWNS, law.swing1_rhs, law.swing1_forces,
                        lambda x, c: ca.vertcat(peak_error(x, c), x[8]), lock_rule=lock_rule,
                        pairing=((1, 1), (0, 0))),
        "swing2": _spec("swing2", law.SWING2_STATE, SWING2_UNKNOWNS, law.swing2_rhs, law.swing2_forces,
                        lambda x, c: ca.vertcat(x[7], x[9]), law.swing2_clearance, SWING2_PATH, lock_rule,
                        pairing=((2, 1), (0, 0))),
        "swing2_closing": _spec("swing2_closing", law.SWING2_STATE, CLOSING_SWING2_UNKNOWNS, law.closing_swing2_rhs,
                                law.closing_swing2_forces, law.closing_swing2_final, law.swing2_clearance,
                                SWING2_PATH, lock_rule, pairing=((2, 1), (0, 0), (1, 2), (3, 3)), subphase="swing2"),
        "swing3": _spec("swing3", law.SWING3_STATE, ("F_theta3_moment",), law.swing3_rhs,
                        law.swing3_forces, theta3_error, law.swing3_clearance, SWING3_PATH, lock_rule),
    }
