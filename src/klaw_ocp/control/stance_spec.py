"""The stance subphase as a boundary-value problem (section 4.2), with the paper's lock rules.

Unknowns: the F_theta1 step magnitude and the pa offset. Final conditions: theta1 and w reach
their eq. 3 values at t_step. Lock rules, as events of the forward integration:

- ``leg_too_long``: while theta1 < 0 the telescope may not grow past l1 ("if w > l1 occurs too early
  ... the stance leg is locked"): an upward crossing of w = l1 locks the leg (wd -> 0).
- ``leg_vertical``: the lock is removed "as soon as the event theta1 > 0 occurs".
- The lock "at the desired length towards the end" is the final condition itself: the boundary
  value solvers reach w = w(eq. 3) exactly at t_step, where the leg then locks (docs/solvers.md).

Multiple shooting does not enforce the lock rule yet (it needs the stance with pa free over
the grid, an IPOPT formulation still to come); a walk whose solution breaks the rule says so in
its step notes (``control.step.lock_rule_notes``). None of the paper's walks triggers it.
"""
from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np

from ..dynamics import impact_functions
from ..dynamics.parameters import N_BODY_PARAMETERS
from ..solvers.problem import Event, SubphaseSpec
from .stance_law import (STANCE_CONTEXT, STANCE_FORCES, STANCE_STATE, STANCE_UNKNOWNS, stance_final_conditions,
                         stance_forces, stance_rhs)

_LOCKED = STANCE_CONTEXT.index["locked"]
_L1 = STANCE_CONTEXT.index["l1"]



def _lock(rule: str):
    """The leg locks: wd -> 0 by the chosen lock rule (ERRATA "Velocities at a lock")."""
    def apply(x, c, mode):
        x = x.copy()
        if rule == "zero":
            x[3] = 0.0
        else:
            x[:6] = np.asarray(impact_functions()["stance_lock"](x[:6], c[:N_BODY_PARAMETERS])).ravel()
        c = c.copy()
        c[_LOCKED] = 1.0
        return x, c, {**mode, "locked": True, "early_lock": True}
    return apply


def _unlock(x, c, mode):
    c = c.copy()
    c[_LOCKED] = 0.0
    return x, c, {**mode, "locked": False}


def stance_lock_events(nx: int, nu: int, nc: int, lock_rule: str) -> tuple:
    """The lock rules as events on any state that starts with the stance state and any context
    that starts with :data:`STANCE_CONTEXT` (the swing subphases re-simulate the stance)."""
    x, t, u, c = ca.SX.sym("x", nx), ca.SX.sym("t"), ca.SX.sym("u", nu), ca.SX.sym("c", nc)
    args = [x, t, u, c]
    return (
        Event("leg_too_long", ca.Function("leg_too_long", args, [x[0] - c[_L1]]), +1,
              lambda x, t, c, mode: not mode.get("locked") and not mode.get("early_lock") and x[1] < 0,
              _lock(lock_rule)),
        Event("leg_vertical", ca.Function("leg_vertical", args, [x[1]]), +1,
              lambda x, t, c, mode: bool(mode.get("locked")), _unlock),
    )


@lru_cache(maxsize=None)
def stance_spec(lock_rule: str = "momentum", at_rest: bool = False) -> SubphaseSpec:
    """The stance :class:`SubphaseSpec` (built once per lock rule).

    ``at_rest``: the closing stance of a walk that ends standing: a third unknown, the F_theta1
    level after 0.4 t_step, brings theta1d to zero at t_step.
    """
    nu = 3 if at_rest else 2
    x, t = ca.SX.sym("x", 6), ca.SX.sym("t")
    u, c = ca.SX.sym("u", nu), ca.SX.sym("c", len(STANCE_CONTEXT))
    forces, pa = stance_forces(x, t, u, c)
    args = [x, t, u, c]
    # The closing stance ends standing with w = l1 while theta1 < 0: reaching l1 there is the goal,
    # not the early plantar flexion the lock rule guards against, so it has no lock events.
    events = () if at_rest else stance_lock_events(6, nu, len(STANCE_CONTEXT), lock_rule)
    return SubphaseSpec(
        name="stance",
        state_names=STANCE_STATE.names,
        unknown_names=STANCE_UNKNOWNS.names + (("F_theta1_brake",) if at_rest else ()),
        context_names=STANCE_CONTEXT.names,
        rhs=ca.Function("stance_rhs", args, [stance_rhs(*args)]),
        final=ca.Function("stance_final", [x, c], [stance_final_conditions(x, c, at_rest)]),
        outputs=ca.Function("stance_outputs", args, [ca.vertcat(forces, pa)]),
        output_names=STANCE_FORCES,
        events=events,
        pairing=((0, 0), (1, 1), (2, 2)) if at_rest else ((0, 0), (1, 1)),
    )
