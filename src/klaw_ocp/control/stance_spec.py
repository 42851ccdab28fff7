"""The stance subphase as a boundary-value problem (section 4.2), with the paper's lock rules.

Two formulations of the same physics, differing in how pa is chosen:

- **monitored** (the paper's): unknowns the F_theta1 step magnitude and the pa offset; pa follows
  the hip-height sinusoid by feedback. Final conditions: theta1 and w reach their eq. 3 values at
  t_step. A square problem (rootfinder, or bisection and secant).
- **tracking** (the OCP form): pa is also free over the grid, as the knots of a piecewise-linear
  profile; IPOPT minimises the hip's distance from the sinusoid subject to the same final
  conditions, the lock rule and the hip floor (:func:`stance_path_bounds`).

The paper's lock rules:

- ``leg_too_long``: while theta1 < 0 the telescope may not grow past l1 ("if w > l1 occurs too early
  ... the stance leg is locked"). Plain shooting locks the leg at the upward crossing (an event,
  wd -> 0); multiple shooting keeps ``l1 - w >= 0`` on those nodes as a path constraint and, when
  the square solution breaks it, re-solves with pa free (docs/solvers.md compares the two).
- ``leg_vertical``: the lock is removed "as soon as the event theta1 > 0 occurs".
- The lock "at the desired length towards the end" is the final condition itself: the boundary
  value solvers reach w = w(eq. 3) exactly at t_step, where the leg then locks (docs/solvers.md).
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from .. import choices
from ..casadi_builds import built_once
from ..dynamics import impact_functions
from ..dynamics.parameters import N_BODY_PARAMETERS
from ..solvers.problem import Event, SubphaseSpec
from .stance_law import (PA_KNOTS, STANCE_CONTEXT, STANCE_FORCES, STANCE_PARAMETERS, STANCE_PATH, STANCE_STATE,
                         hip_height_function, stance_final_conditions, stance_forces, stance_path, stance_plausible,
                         stance_rhs, tracking_residuals)

_LOCKED = STANCE_CONTEXT.index["locked"]
_L1 = STANCE_CONTEXT.index["l1"]



def _lock(rule: str):
    """The leg locks: wd -> 0 by the chosen lock rule (ERRATA "Velocities at a lock")."""
    def apply(x, c, mode):
        x = x.copy()
        if rule == choices.ZERO:
            x[3] = 0.0
        else:
            x[:6] = np.asarray(impact_functions()["stance_lock"](x[:6], c[:N_BODY_PARAMETERS])).ravel()
        c = c.copy()
        c[_LOCKED] = 1.0
        return x, c, _MODE_AFTER["leg_too_long"](mode)
    return apply


def _unlock(x, c, mode):
    c = c.copy()
    c[_LOCKED] = 0.0
    return x, c, _MODE_AFTER["leg_vertical"](mode)


# The mode switches of the two events, apart from their state maps, so that a subphase's lock state
# at any time can be replayed from its event log (:func:`lock_mode`): the swing re-simulates the
# stance and must start in the lock state the stance (or the previous swing subphase) is in then.
# The leg locks early at most once per stance ("early_lock"), and unlocks at the vertical.
_MODE_AFTER = {
    "leg_too_long": lambda mode: {**mode, "locked": True, "early_lock": True},
    "leg_vertical": lambda mode: {**mode, "locked": False},
}
#: the mode of a subphase that re-simulates a stance without lock events (the closing stance of a
#: walk that ends at rest): the swings of that step disarm the events their spec shares with every
#: other step, instead of compiling a second set of swing kernels
NO_LOCK_EVENTS = {"locked": False, "lock_events": False}


def lock_mode(events, until: float = float("inf"), mode: dict | None = None) -> dict:
    """The lock mode after the events ``(name, t)`` with t <= ``until``, starting from ``mode``
    (default: heel strike's, unlocked and armed)."""
    mode = dict(mode or {})
    for name, t in sorted(events, key=lambda e: e[1]):
        if t <= until and name in _MODE_AFTER:
            mode = _MODE_AFTER[name](mode)
    return mode


def lock_context(c: np.ndarray, mode: dict) -> np.ndarray:
    """The context ``c`` (any that starts with :data:`STANCE_CONTEXT`) with its ``locked`` entry
    set as ``mode`` says: the stance model's rigid leg while the leg is locked."""
    c = np.array(c, float)
    c[_LOCKED] = 1.0 if mode.get("locked") else 0.0
    return c


def stance_lock_events(nx: int, nu: int, nc: int, lock_rule: str) -> tuple:
    """The lock rules as events on any state that starts with the stance state and any context
    that starts with :data:`STANCE_CONTEXT` (the swing subphases re-simulate the stance)."""
    x, t, u, c = ca.SX.sym("x", nx), ca.SX.sym("t"), ca.SX.sym("u", nu), ca.SX.sym("c", nc)
    args = [x, t, u, c]
    return (
        Event("leg_too_long", ca.Function("leg_too_long", args, [x[0] - c[_L1]]), +1,
              lambda x, t, c, mode: (mode.get("lock_events", True) and not mode.get("locked")
                                     and not mode.get("early_lock") and x[1] < 0),
              _lock(lock_rule), rate=lambda states: states[:, 3]),
        Event("leg_vertical", ca.Function("leg_vertical", args, [x[1]]), +1,
              lambda x, t, c, mode: bool(mode.get("locked")), _unlock, rate=lambda states: states[:, 4]),
    )


def stance_unknowns(at_rest: bool = False) -> tuple:
    """Names of the stance unknowns: every :data:`STANCE_PARAMETERS` entry except the braking level,
    which only the closing stance (``at_rest``) has."""
    return tuple(n for n in STANCE_PARAMETERS.names if at_rest or n != "F_theta1_brake")


def stance_fixed(at_rest: bool = False) -> tuple:
    """Which unknowns the square (monitored) problem holds at their guess: the pa profile."""
    return tuple(n in PA_KNOTS for n in stance_unknowns(at_rest))


@built_once
def stance_spec(lock_rule: str = choices.DEFAULT_LOCK_RULE, at_rest: bool = False) -> SubphaseSpec:
    """The stance :class:`SubphaseSpec` (built once per lock rule).

    ``at_rest``: the closing stance of a walk that ends standing: a third unknown, the F_theta1
    level after 0.4 t_step, brings theta1d to zero at t_step.
    """
    names = stance_unknowns(at_rest)
    nu = len(names)
    x, t = ca.SX.sym("x", 6), ca.SX.sym("t")
    u, c = ca.SX.sym("u", nu), ca.SX.sym("c", len(STANCE_CONTEXT))
    given = dict(zip(names, ca.vertsplit(u)))
    p = ca.vertcat(*[given.get(n, 0) for n in STANCE_PARAMETERS.names])
    forces, pa = stance_forces(x, t, p, c)
    args = [x, t, u, c]
    # The closing stance ends standing with w = l1 while theta1 < 0: reaching l1 there is the goal,
    # not the early plantar flexion the lock rule guards against, so it has no lock events.
    events = () if at_rest else stance_lock_events(6, nu, len(STANCE_CONTEXT), lock_rule)
    pairs = ((0, 0), (1, 1), (2, 2)) if at_rest else ((0, 0), (1, 1))
    return SubphaseSpec(
        name="stance",
        state_names=STANCE_STATE.names,
        unknown_names=names,
        context_names=STANCE_CONTEXT.names,
        rhs=ca.Function("stance_rhs", args, [stance_rhs(x, t, p, c)]),
        final=ca.Function("stance_final", [x, c], [stance_final_conditions(x, c, at_rest)]),
        outputs=ca.Function("stance_outputs", args, [ca.vertcat(forces, pa)]),
        output_names=STANCE_FORCES,
        path=ca.Function("stance_path", args, [stance_path(x, c)]),
        path_names=STANCE_PATH,
        residuals=ca.Function("stance_tracking_residuals", args, [tracking_residuals(x, t, p, c)]),
        events=events,
        path_holds_events=bool(events),     # the lock rule: l1 - w >= 0 on the rule's nodes
        pairing=pairs,
        plausible=ca.Function("stance_plausible", [x, c], [stance_plausible(x, c)]),
    )


def lock_rule_nodes(states: np.ndarray, l1: float) -> np.ndarray:
    """Where the lock rule applies: theta1 < 0, once the leg has first come down to l1 after heel
    strike (the foot raises the hip at impact, so w > l1 there is the eq. 3 geometry, not an
    early plantar flexion)."""
    w, theta1 = states[:, 0], states[:, 1]
    return np.logical_or.accumulate(w <= l1) & (theta1 < 0)


def stance_path_bounds(hip_floor: bool, at_rest: bool = False):
    """Per-node lower bounds of :func:`~.stance_law.stance_path`, from a trajectory (N+1, 6).

    Where each inequality applies depends on the motion, so the solver re-evaluates the bounds on
    its solution and re-solves until they agree:

    - the lock rule on :func:`lock_rule_nodes`; never in the closing stance, whose goal is
      w = l1 with theta1 < 0;
    - with ``hip_floor``, the floor on every node after the hip stops falling (a hip that arrives
      descending, from a step solved without the floor, cannot stop at once: velocities are
      continuous through the heel-strike map), and a non-negative vertical velocity at t_step.
    """
    def bounds(t: np.ndarray, states: np.ndarray, context: np.ndarray) -> np.ndarray:
        n = len(t)
        lower = np.full((n, len(STANCE_PATH)), -np.inf)
        if not at_rest:
            rule = lock_rule_nodes(states, context[STANCE_CONTEXT.index["l1"]])
            lower[1:, 0] = np.where(rule[1:], 0.0, -np.inf)
        if hip_floor:
            yd = np.asarray(hip_height_function(n)(states.T)[1]).ravel()
            rising = np.cumsum(yd >= 0) > 0
            lower[1:, 1] = np.where(rising[1:], 0.0, -np.inf)
            lower[-1, 2] = 0.0
        return lower
    return bounds
