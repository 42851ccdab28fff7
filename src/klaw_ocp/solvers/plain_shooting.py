"""Mode (b): plain shooting with bisection then secant, the paper's own method (section 4.1).

"The approximation of F is performed in two stages. First, the Bisection method computes a
reasonable approximation which is then refined by the Secant method." Each free unknown is paired
with one final condition (``spec.pairing``: F_theta1 with theta1, pa with w, ...). With one unknown
that is the paper's method as written; with two, the 1-D solves alternate (Gauss-Seidel sweeps)
until both conditions hold, because the paper does not say how it coupled them.

Forward integration uses the same RK4 interval as multiple shooting and watches the spec's
events (the stance leg's lock and unlock; :mod:`.events`). The recovery loop of swing2 is
``recovery_step``: while a path inequality (toe clearance) is violated, the unknown it names is
raised by increments and the free unknowns are solved again; the smallest sufficient number of
increments is found by doubling then bisection (:meth:`PlainShootingSolver._recover`). The
fallbacks beyond the paper's method (Broyden, the event-free start, the homotopy) are listed in
docs/solvers.md and reported in each solution's ``fallbacks``.
"""
from __future__ import annotations

import time

import numpy as np

from .. import choices

from .events import EventIntegrator
from .integrator import prepare_kernels, subphase_kernels
from .problem import SubphaseProblem, SubphaseSolution, fd_jacobian, path_bounds
from .recovery import recovery_loop


#: Gauss-Seidel sweeps that shrink the residual by less than this factor twice in a row are left
#: for Broyden's method: two coupled unknowns (swing1's and swing2's fall and mean) contract by
#: 0.6-0.9 a sweep, and thirty slow sweeps cost more shots than Broyden's whole solve.
SLOW_SWEEPS = 0.5
#: the fallback name of a root taken from the event-free start (:meth:`PlainShootingSolver._event_free_start`)
EVENT_FREE_ROOT = "event-free-root"


class PlainShootingSolver:
    """Forward shooting; see the module docstring. ``max_iterations`` bounds the shots per 1-D solve."""

    name = choices.PLAIN_SHOOTING
    #: no scan of the unknowns' space: its own fallbacks (the sweeps' pairings, Broyden, the
    #: event-free start, the homotopy) are its last resort
    scans = False

    def __init__(self, intervals: int = choices.DEFAULT_INTERVALS, substeps: int = choices.SUBSTEPS,
                 tolerance: float = choices.DEFAULT_TOLERANCE,
                 max_iterations: int = 60, bisection_steps: int = 4, max_sweeps: int = 40,
                 max_recovery_steps: int = 400):
        self.intervals, self.substeps = int(intervals), int(substeps)
        self.tolerance, self.max_iterations = float(tolerance), int(max_iterations)
        self.bisection_steps, self.max_sweeps = int(bisection_steps), int(max_sweeps)
        self.max_recovery_steps = int(max_recovery_steps)
        self.shots = 0
        self._integrator = EventIntegrator(self.substeps)
        self._fallbacks: list = []
        #: False while the event-free start solves the smooth problem (see :meth:`_solve_free`)
        self._events_armed = True
        #: spec -> the Jacobian Broyden's method ended with on that subphase's last solve: the next
        #: step's same subphase, a problem close to it, starts Broyden from it rather than from
        #: finite differences and sweeps that did not contract (a walk's own solver: per walk)
        self._coupled: dict = {}

    def prepare(self, specs) -> None:
        """Compile or load the kernels of ``specs`` now, in parallel (the first run on a machine)."""
        prepare_kernels(specs, self.substeps, self.intervals)

    # -- forward integration ----------------------------------------------------------------
    def simulate(self, pb: SubphaseProblem, u: np.ndarray):
        """Integrate from x0 with parameters u (:class:`.events.EventIntegrator`); returns (times,
        states, context, event log). The events are disarmed during the event-free start."""
        self.shots += 1
        return self._integrator.simulate(pb, u, armed=self._events_armed)

    def _final(self, pb, u):
        times, states, c, log = self.simulate(pb, u)
        if not np.all(np.isfinite(states[-1])):
            return np.full(pb.spec.final.size1_out(0), np.inf), (times, states, c, log)
        return self._kernels(pb).final(states[-1], c)[0], (times, states, c, log)

    def _kernels(self, pb):
        return subphase_kernels(pb.spec, self.substeps, pb.grid.size - 1)

    def _margins(self, pb, states, u, times, c=None):
        """(smallest path margin, plausible) of a trajectory (event samples included)."""
        _, path, plausible, _ = self._kernels(pb).samples(states, times, u, pb.context if c is None else c)
        lower = path_bounds(pb, times, states)
        path_min = float(np.min(path - lower)) if lower is not None else float("inf")
        return path_min, bool(np.all(np.isfinite(plausible)) and np.all(plausible >= 0))

    # -- bisection, then secant -------------------------------------------------------------
    def _solve_1d(self, f, x0: float, scale: float, tol: float, probe: float):
        """Root of a scalar f near x0: bracket, a few bisections, then the secant method.

        ``probe`` is the first trial step (the size of the last change of this unknown, so that
        later sweeps bracket tightly around a root they already nearly have).
        """
        shots = 0
        f0 = f(x0); shots += 1
        if abs(f0) <= tol:
            return x0, f0, shots
        delta = probe or abs(scale) * 0.05 or 1.0
        f1 = f(x0 + delta); shots += 1
        slope = (f1 - f0) / delta
        direction = -np.sign(f0 * slope) if np.isfinite(slope) and slope != 0 else 1.0
        # Expand a bracket on both sides of x0, doubling the step, the slope's side first: the
        # first sign change met is the root nearest the guess (a far one can be a different
        # motion, e.g. the leg swinging round). A shot that blew up halves that side's step.
        steps = {direction: delta, -direction: delta}
        last = {direction: (x0, f0), -direction: (x0, f0)}
        a = b = None
        reach = 100.0 * (abs(scale) or 1.0)   # a root further away is another motion entirely
        while shots < self.max_iterations and a is None and min(steps.values()) <= reach:
            for side in (direction, -direction):
                if steps[side] > reach:
                    continue
                xa, fa_side = last[side]
                xb = xa + side * steps[side]
                fb_side = f(xb); shots += 1
                if not np.isfinite(fb_side):
                    steps[side] *= 0.5
                    continue
                if fa_side * fb_side <= 0:
                    a, fa, b, fb = xa, fa_side, xb, fb_side
                    break
                last[side] = (xb, fb_side)
                steps[side] *= 2.0
        if a is None:
            best = min(last.values(), key=lambda p: abs(p[1]))
            return best[0], best[1], shots
        # bisection only until the bracket is a "reasonable approximation" (2 % of the scale)
        for _ in range(self.bisection_steps):
            if abs(b - a) <= 0.02 * abs(scale):
                break
            m = 0.5 * (a + b); fm = f(m); shots += 1
            if fa * fm <= 0:
                b, fb = m, fm
            else:
                a, fa = m, fm
        # secant, kept inside the bracket (a bisection step whenever it would leave it)
        x_prev, f_prev, x, fx = a, fa, b, fb
        while abs(fx) > tol and shots < self.max_iterations:
            x_new = x - fx * (x - x_prev) / (fx - f_prev) if fx != f_prev else 0.5 * (a + b)
            lo, hi = min(a, b), max(a, b)
            if not lo < x_new < hi:
                x_new = 0.5 * (a + b)
            f_new = f(x_new); shots += 1
            if fa * f_new <= 0:
                b, fb = x_new, f_new
            else:
                a, fa = x_new, f_new
            x_prev, f_prev, x, fx = x, fx, x_new, f_new
            if abs(b - a) < 1e-15 * max(1.0, abs(x)):
                break
        return x, fx, shots

    def _solve_free(self, pb: SubphaseProblem, u: np.ndarray):
        """Gauss-Seidel sweeps of 1-D solves; from a far guess, along a homotopy. A subphase with
        several coupled unknowns whose last solve ended in Broyden's method starts there, from
        that solve's Jacobian (``_coupled``), and sweeps only if that does not converge.

        When the sweeps fail from the guess u0 (a cold start far from the root, e.g. the first
        stance of a slow walk), they are repeated on the shifted problems
        g(u) - (1 - lam) g(u0) = 0 for lam = 1/16, 2/16, ..., 1, each started from the last root:
        every stage starts close to its root, which is where bisection and secant are reliable.
        """
        start = u.copy()
        several = sum(not f for f in pb.fixed) > 1
        if several and pb.spec in self._coupled:     # (ordinary here, so not noted as a fallback)
            u0, residual0, shots0 = self._broyden(pb, start.copy(), self._coupled[pb.spec])
            if self._converged(residual0):
                return u0, residual0, shots0
        else:
            shots0 = 0
        u1, residual, shots = self._sweeps(pb, u.copy(), None)
        shots += shots0
        if self._converged(residual):
            return u1, residual, shots
        if several:
            self._note("broyden")
            u2, residual2, n = self._broyden(pb, start.copy())
            shots += n
            if self._converged(residual2):
                return u2, residual2, shots
        if pb.spec.events:
            u3, residual3, n = self._event_free_start(pb, start.copy())
            shots += n
            if self._converged(residual3):
                return u3, residual3, shots
        offset0 = self._final(pb, start)[0]
        shots += 1
        if not np.all(np.isfinite(offset0)):
            return u1, residual, shots
        u = start
        self._note("homotopy")
        for lam in np.linspace(1 / 16, 1.0, 16):
            u, residual, n = self._sweeps(pb, u, (1 - lam) * offset0)
            shots += n
            if not np.all(np.isfinite(residual)):
                break
        return u, residual, shots

    def _event_free_start(self, pb: SubphaseProblem, u: np.ndarray):
        """Solve with the events disarmed, then again with them from that root.

        Far from the root a lock event can fire (the stance leg locks at w = l1 before it is
        vertical), and while it does w(t_step) no longer depends on pa: the map from the unknowns
        to the final conditions is flat or discontinuous there, and the 1-D and secant solves stall.
        Without events the same problem is smooth (multiple shooting never integrates events
        while it iterates either); its root is the answer when no event fires there, and a start
        next to it otherwise.
        """
        self._note("event-free-start")
        self._events_armed = False
        try:   # several unknowns: the secant method in several unknowns from the guess; one: 1-D
            several = sum(not f for f in pb.fixed) > 1
            u, residual, shots = self._broyden(pb, u) if several else self._sweeps(pb, u, None)
            free = (u.copy(), residual) if pb.spec.path_holds_events and self._converged(residual) else None
            if free is not None:   # its trajectory's path margins at the nodes, without the events
                times, states, _, _ = self.simulate(pb, u)
                path_min, plausible = self._margins(pb, states, u, times)
                free = free if path_min >= -1e-7 and plausible else None
        finally:
            self._events_armed = True
        u_evented, residual_evented, n = self._sweeps(pb, u, None)
        if self._converged(residual_evented) or free is None:
            return u_evented, residual_evented, shots + n
        # No root with the events, where the smooth problem's root keeps the path constraints (the
        # lock rule) at every node: an event fires only between nodes, a graze of micrometres that
        # the latch holds until the vertical, and the final conditions jump across it with no root
        # on either side (slow walks, whose telescope hovers at l1). Multiple shooting keeps the
        # rule at the nodes and takes that root; so does plain shooting then, with the events
        # disarmed for this solve (:data:`EVENT_FREE_ROOT`; the swings that re-simulate this stance
        # disarm them too, control/step.py).
        self._note(EVENT_FREE_ROOT)
        return free[0], free[1], shots + n

    def _converged(self, residual) -> bool:
        return bool(np.all(np.isfinite(residual)) and np.max(np.abs(residual)) <= self.tolerance)

    def _sweeps(self, pb: SubphaseProblem, u: np.ndarray, offset):
        """Gauss-Seidel sweeps of 1-D solves over the (unknown, condition) pairs, for the final
        conditions minus ``offset`` (None: the real problem). Returns the unshifted residual."""
        shift = np.zeros(pb.spec.final.size1_out(0)) if offset is None else offset
        final = lambda trial: self._final(pb, trial)[0] - shift
        shots = 0
        pairs = [(i, j) for i, j in pb.spec.pairing if not pb.fixed[i]]
        residual = final(u)
        shots += 1
        if len(pairs) == 2 and np.all(np.isfinite(residual)):
            pairs, n = self._choose_pairing(pb, u, residual, pairs, final)
            shots += n
        probes = {i: 0.0 for i, _ in pairs}
        history = []
        for _ in range(self.max_sweeps):
            worst = float(np.max(np.abs(residual)))
            if not np.isfinite(worst) or worst <= self.tolerance:
                break
            history.append(worst)
            if len(history) > 3 and history[-1] > 0.95 * history[-4]:
                break   # not contracting: leave it to the homotopy (or report the failure)
            if (len(pairs) > 1 and len(history) > 2 and history[-1] > SLOW_SWEEPS * history[-2]
                    and history[-2] > SLOW_SWEEPS * history[-3]):
                break   # contracting slowly: Broyden's method is cheaper (SLOW_SWEEPS)
            # inexact sweeps: each 1-D solve only needs to beat the current coupling error
            tol = max(self.tolerance, 0.01 * worst) if len(pairs) > 1 else self.tolerance
            for i, j in pairs:
                def f(value, i=i, j=j):
                    trial = u.copy(); trial[i] = value
                    return float(final(trial)[j])
                old = u[i]
                u[i], value, n = self._solve_1d(f, u[i], pb.scale[i], tol, min(2 * probes[i], 0.05 * abs(pb.scale[i])))
                if not np.isfinite(value):
                    u[i] = old
                probes[i] = abs(u[i] - old) or 1e-6 * abs(pb.scale[i])
                shots += n
            residual = final(u)
            shots += 1
        return u, residual + shift, shots

    def _broyden(self, pb, u, jac=None):
        """The secant method in several unknowns (Broyden's update of a finite-difference
        Jacobian, or of ``jac``, backtracking on |residual|): when the one-at-a-time sweeps do not
        contract. The Jacobian it ends with is kept for the spec's next solve (``_coupled``)."""
        free = [i for i, f in enumerate(pb.fixed) if not f]
        rows = [j for i, j in pb.spec.pairing if not pb.fixed[i]]
        final = lambda trial: self._final(pb, trial)[0]
        res = final(u)[rows]
        shots = 1
        if not np.all(np.isfinite(res)):
            return u, final(u), shots
        def jacobian(u, res):
            return fd_jacobian(lambda trial: final(trial)[rows], u, res, free, pb.scale)

        if jac is None:
            jac, fresh = jacobian(u, res), True
            shots += len(free)
        else:
            jac, fresh = jac.copy(), False     # a stale start: refreshed once if it stops helping
        for _ in range(self.max_iterations):
            if np.max(np.abs(res)) <= self.tolerance:
                break
            try:
                step = np.linalg.solve(jac, -res)
            except np.linalg.LinAlgError:
                step = None
            accepted = False
            if step is not None:
                for damping in (1.0, 0.5, 0.25, 0.125, 0.0625):
                    trial = u.copy(); trial[free] += damping * step
                    new = final(trial)[rows]
                    shots += 1
                    if np.all(np.isfinite(new)) and np.linalg.norm(new) < np.linalg.norm(res):
                        accepted = True
                        break
            if not accepted:
                if fresh:
                    break
                # Broyden's update drifted: refresh the Jacobian by finite differences once
                jac, fresh = jacobian(u, res), True
                shots += len(free)
                continue
            ds, dr = damping * step, new - res
            jac += np.outer(dr - jac @ ds, ds) / (ds @ ds)
            u, res, fresh = trial, new, False
        if np.max(np.abs(res)) <= self.tolerance:
            self._coupled[pb.spec] = jac
        return u, final(u), shots + 1

    def _choose_pairing(self, pb, u, residual, pairs, final):
        """Pair each unknown with the condition it moves most, relative to the other pairing.

        Gauss-Seidel sweeps contract by |J12 J21 / (J11 J22)| per sweep; when that exceeds 1 for
        the spec's pairing (it can, at slow walks), the swapped pairing contracts instead.
        """
        (i0, j0), (i1, j1) = pairs
        jac = fd_jacobian(lambda trial: final(trial)[[j0, j1]], u, residual[[j0, j1]], (i0, i1), pb.scale)
        direct, swapped = abs(jac[0, 0] * jac[1, 1]), abs(jac[0, 1] * jac[1, 0])
        if np.isfinite(direct + swapped) and swapped > direct:
            self._note("swapped-pairing")
            return [(i0, j1), (i1, j0)], 2
        return pairs, 2

    def _note(self, fallback: str) -> None:
        if fallback not in self._fallbacks:
            self._fallbacks.append(fallback)

    def _recover(self, pb: SubphaseProblem, u: np.ndarray):
        """The paper's recovery loop (:func:`.recovery.recovery_loop`)."""
        return recovery_loop(self, pb, u)

    def solve(self, pb: SubphaseProblem) -> SubphaseSolution:
        wall0 = time.perf_counter()
        self._fallbacks = []
        u = pb.guess.copy()
        u, residual, shots = self._solve_free(pb, u)
        recovery = 0
        if pb.recovery_step is not None and pb.path_lower is not None:
            times, states, _, _ = self.simulate(pb, u)
            shots += 1
            if self._margins(pb, states, u, times)[0] < 0:
                self._note("recovery-loop")
                u, residual, n, recovery = self._recover(pb, u)
                shots += n
        self._events_armed = EVENT_FREE_ROOT not in self._fallbacks
        try:
            times, states, c, log = self.simulate(pb, u)
        finally:
            self._events_armed = True
        residual = self._kernels(pb).final(states[-1], c)[0]
        res = float(np.max(np.abs(residual))) if np.all(np.isfinite(residual)) else float("inf")
        # forces with the context the trajectory ends in (a lock event switches it), as before
        forces = self._kernels(pb).samples(states, times, u, c)[0]
        path_min, plausible = self._margins(pb, states, u, times)
        ok = res <= max(10 * self.tolerance, 1e-9) and path_min >= -1e-7 and plausible
        msg = "" if ok else (f"residual {res:.3g}" + (f", path constraint violated by {-path_min:.3g}"
                                                       if path_min < -1e-7 else "")
                             + ("" if plausible else ", implausible motion (a root far from any walk)"))
        if recovery:
            msg = (msg + "; " if msg else "") + f"recovery loop: {recovery} increments"
        return SubphaseSolution(pb.spec.solution_name, self.name, dict(zip(pb.spec.unknown_names, map(float, u))),
                                times, states, forces, res, shots, bool(ok), time.perf_counter() - wall0,
                                msg if not ok or recovery else "", path_min, log, choices.BISECTION_SECANT,
                                fallbacks=list(self._fallbacks))
