"""Plain shooting's recovery loop (§4.3): where swing2's toe would touch the ground, the hip
actuator is raised by increments until it clears (:class:`.plain_shooting.PlainShootingSolver`)."""
from __future__ import annotations

import numpy as np

from .problem import SubphaseProblem


def recovery_loop(solver, pb: SubphaseProblem, u: np.ndarray):
    """The paper's recovery loop of ``solver`` (a PlainShootingSolver): the smallest number k of
    ``recovery_step`` increments of the fixed unknowns (the swing2 hip actuator) after which, with
    the free unknowns solved again, the path inequality (toe clearance) holds.

    The paper raises the actuator one increment at a time. Clearance grows with the actuator,
    so the same smallest k is found by doubling k until the toe clears and then bisecting
    between the last k that did not clear and the first that did: about 2 log2(k) solves
    instead of k (k reached 300 in first steps from rest).
    Returns (u, residual, shots, k); k = 0 when no increment is needed.
    """
    step = np.asarray(pb.recovery_step, float)
    solved = {0: u}

    def attempt(k):
        nearest = solved[min(solved, key=lambda j: abs(j - k))]
        trial = nearest + (k - min(solved, key=lambda j: abs(j - k))) * step
        u_k, residual, n = solver._solve_free(pb, trial)      # noqa: SLF001 - the solver's own free solve
        times, states, _, _ = solver.simulate(pb, u_k)
        # (the solver's own convergence and path checks)
        ok = solver._converged(residual) and solver._margins(pb, states, u_k, times)[0] >= 0  # noqa: SLF001
        solved[k] = u_k
        return ok, residual, n + 1

    shots, lo, hi, result = 0, 0, 1, None
    while hi <= solver.max_recovery_steps:
        ok, residual, n = attempt(hi)
        shots += n
        if ok:
            result = (solved[hi], residual)
            break
        if hi == solver.max_recovery_steps:
            break
        lo, hi = hi, min(2 * hi, solver.max_recovery_steps)   # the last try is the cap itself
    if result is None:   # not cleared within max_recovery_steps: report the last attempt
        return solved[lo], residual, shots, lo
    while hi - lo > 1:
        mid = (lo + hi) // 2
        ok, residual, n = attempt(mid)
        shots += n
        if ok:
            hi, result = mid, (solved[mid], residual)
        else:
            lo = mid
    return result[0], result[1], shots, hi
