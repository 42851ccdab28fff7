"""Mode (a): CasADi multiple shooting: Newton on the square system, IPOPT with inequalities.

Unknowns, for N intervals and a spec with nx states and nu free parameters: the node states
X_1..X_N (X_0 = x0 is given) and the free parameters. Equations: the continuity defects
``X_{k+1} - Phi(X_k, t_k, h_k, u, c)`` for k = 0..N-1 and the final conditions ``g(X_N, c)``;
Phi is the shared RK4 interval (:mod:`.integrator`). Everything that changes from step to step
(x0, the grid, the context c, the fixed unknowns) is a parameter, so the compiled functions of
each spec are built once per machine (:mod:`klaw_ocp.kernels`) and reused with new numbers.

- Square problems (as many free unknowns as final conditions) are solved by Newton's method on
  the multiple-shooting system, exploiting its block structure: per-interval Jacobians from one
  compiled call, condensed to a system the size of u, and chord steps that reuse the last
  Jacobian while the residual contracts (:mod:`.newton`). ``nlp: rootfinder`` names this solver.
- Problems with path inequalities ``h(X_k, t_k, u, c) >= lower_k`` go to IPOPT (:mod:`.ipopt_nlp`):
  the unknowns held fixed in the square problem (e.g. the swing2 hip position actuator) become
  free, and the objective keeps them as close as possible to their nominal values. This is the
  OCP form of the paper's recovery loop: instead of raising the actuator in increments until the
  toe clears, it finds the smallest change that makes it clear.
- A spec with least-squares residuals (the stance's hip-height tracking) is optimised instead:
  the objective is the mean of their squares over the nodes, every unknown is free (pa over the
  grid), and IPOPT gets the Gauss-Newton Hessian 2 J^T J of the residuals.
- Bounds that depend on the motion (the stance lock rule applies while theta1 < 0) are evaluated
  on the starting trajectory, then on each solution, and the NLP is re-solved from the last
  solution until the set of active nodes no longer changes.
"""
from __future__ import annotations

import time

import numpy as np

from .. import choices
from .integrator import prepare_kernels, subphase_kernels
from .ipopt_nlp import ipopt_solver
from .multiple_shooting_starts import SCAN_MAX_FREE, ColdStarts
from .newton import CONTRACTION, CondensedNewton
from .problem import IpoptPoint, SubphaseProblem, SubphaseSolution, fd_jacobian, path_bounds
from .thread_safety import IPOPT_LOCK


#: how near (relative) a problem's NLP parameters must be to those of the step before's IPOPT
#: solution for this one to start from it: a periodic walk's steps repeat to about 1e-9, a change
#: of plan, attribute or start moves them by 1e-3 or more
REPEAT_TOLERANCE = 1e-6


class _Call:
    """Book-keeping of one ``solve``: its start, the one-off build time and the fallbacks taken."""

    def __init__(self):
        self.wall0, self.build_s, self.fallbacks = time.perf_counter(), 0.0, []

    def built(self, factory, *args):
        """``factory(*args)`` (a cached solver build), its time kept out of the solve time."""
        t0 = time.perf_counter()
        solver = factory(*args)
        self.build_s += time.perf_counter() - t0
        return solver

    def note(self, fallback: str) -> None:
        if fallback not in self.fallbacks:
            self.fallbacks.append(fallback)


class MultipleShootingSolver(ColdStarts):
    """Solve subphases by multiple shooting; see the module docstring for the formulation.

    ``nlp``: "auto" (Newton, then IPOPT only if a path inequality is violated), "rootfinder"
    (never IPOPT; a violated inequality is reported in the message) or "ipopt" (always).
    """

    name = choices.MULTIPLE_SHOOTING
    #: it honours a problem's ``scan`` (:meth:`ColdStarts._scan`)
    scans = True

    def __init__(self, intervals: int = choices.DEFAULT_INTERVALS, substeps: int = choices.SUBSTEPS,
                 tolerance: float = choices.DEFAULT_TOLERANCE, max_iterations: int = choices.DEFAULT_MAX_ITERATIONS,
                 nlp: str = choices.DEFAULT_NLP):
        self.intervals, self.substeps = int(intervals), int(substeps)
        self.tolerance, self.max_iterations, self.nlp = float(tolerance), int(max_iterations), nlp
        self._newton: dict = {}   # spec -> CondensedNewton (it keeps the last Jacobian for chord steps)
        #: (spec, free indices) -> the last single-shooting Jacobian of the initial guesses' steps
        self._guess_jacobians: dict = {}

    def prepare(self, specs) -> None:
        """Compile or load the kernels of ``specs`` now, in parallel (the first run on a machine)."""
        prepare_kernels(specs, self.substeps, self.intervals)

    # -- helpers -------------------------------------------------------------------------------
    def _kernels(self, pb: SubphaseProblem, call: _Call):
        kernels = subphase_kernels(pb.spec, self.substeps, self.intervals)
        call.built(kernels.load)   # the first use compiles or loads them; kept out of the solve time
        return kernels

    def _simulate(self, pb: SubphaseProblem, u: np.ndarray, kernels) -> np.ndarray:
        return kernels.sim(pb.x0, pb.grid[:-1], pb.h, u, pb.context)[0].reshape(self.intervals, -1)

    def _final(self, pb: SubphaseProblem, kernels):
        return lambda xs: kernels.final(xs[-1], pb.context)[0]

    def _initial_guess(self, pb: SubphaseProblem, free: list, call: _Call, kernels) -> tuple:
        """Free parameters, node states to start Newton from, and whether those nodes are the
        simulation of those parameters (then their continuity defects are zero).

        A simulation with the given guess initialises the nodes. When its final conditions are
        far off (a cold start, the walk's first steps), a few damped Newton steps on the
        single-shooting residual first bring the parameters near the root, so that the node states
        start on a trajectory that nearly satisfies them. Their Jacobian (finite differences, a
        simulation per free parameter) is kept, as Newton's is (:mod:`.newton`): the next guess
        of the subphase steps with it first (a chord step, one simulation), and renews it only
        when that step does not reduce the residual by CONTRACTION.
        """
        u = pb.guess.copy()
        if self._warm(pb):
            return u, np.asarray(pb.state_guess)[1:], False
        final = self._final(pb, kernels)
        xs = self._simulate(pb, u, kernels)
        res = final(xs)
        key = (pb.spec, tuple(free))
        jac, fresh = self._guess_jacobians.get(key), False
        steps = 0
        while steps < 8:
            largest = np.abs(res).max()
            if not np.isfinite(res).all() or largest < 1e-3 or len(free) != res.size:
                break
            if jac is None:
                jac = fd_jacobian(lambda trial: final(self._simulate(pb, trial, kernels)), u, res, free, pb.scale)
                fresh = True
                self._guess_jacobians[key] = jac
            try:
                step = np.linalg.solve(jac, -res)
            except np.linalg.LinAlgError:
                break
            for damping in (1.0, 0.5, 0.25, 0.125) if fresh else (1.0,):
                trial = u.copy(); trial[free] += damping * step
                xs_trial = self._simulate(pb, trial, kernels)
                res_trial = final(xs_trial)
                if np.isfinite(res_trial).all() and np.abs(res_trial).max() < largest:
                    u, xs, res = trial, xs_trial, res_trial
                    break
            else:
                if fresh:
                    break
                jac = None        # the kept Jacobian made no progress: renew it here
                continue
            steps += 1
            if np.abs(res).max() > CONTRACTION * largest:
                jac = None        # poor contraction: renew the Jacobian at the new point
            fresh = False
        if len(free) == 1 and res.size == 1 and not (np.isfinite(res[0]) and abs(res[0]) < 1e-3):
            call.note("bracket")
            u, xs = self._bracket_guess(pb, free[0], u, kernels)
        finite = bool(np.isfinite(xs).all())
        return u, (xs if finite else np.where(np.isfinite(xs), xs, np.tile(pb.x0, (self.intervals, 1)))), finite

    def _warm(self, pb: SubphaseProblem) -> bool:
        """Whether the problem carries node states to start from (the previous step's solution)."""
        return pb.state_guess is not None and np.shape(pb.state_guess) == (self.intervals + 1, pb.spec.nx)

    def _finish(self, pb, nodes, u, iterations, call: _Call, message, success_hint, kernels,
                nlp=choices.ROOTFINDER, residual=None) -> SubphaseSolution:
        """The solution from its node states 1..N, checked: residual and defects of the discrete
        trajectory returned (``residual``: Newton's own, of this very point), path margins,
        plausibility."""
        spec, n = pb.spec, self.intervals
        states = np.concatenate([pb.x0[None, :], np.asarray(nodes).reshape(n, spec.nx)])   # (np.vstack's numbers)
        if residual is None:
            t, h = pb.grid[:-1], pb.h
            final = float(np.abs(kernels.final(states[-1], pb.context)[0]).max())
            propagated = kernels.prop(states[:-1], t, h, u, pb.context)[0].reshape(n, spec.nx)
            residual = max(final, float(np.abs(propagated - states[1:]).max()))
        forces, path, plausible, _ = kernels.samples(states, pb.grid, u, pb.context)
        path_min = float("inf")
        lower = path_bounds(pb, pb.grid, states)
        if lower is not None:
            path_min = float((path - lower).min())
        plausible = bool(np.isfinite(plausible).all() and (plausible >= 0).all())
        ok = (success_hint and residual <= max(10 * self.tolerance, 1e-9)
              and np.isfinite(states).all() and plausible)
        msg = message or ("" if ok else f"residual {residual:.3g} (final conditions and continuity)"
                          + ("" if plausible else ", implausible motion (a root far from any walk)"))
        return SubphaseSolution(spec.solution_name, self.name, dict(zip(spec.unknown_names, map(float, u))), pb.grid.copy(),
                                states, forces, residual, iterations, bool(ok),
                                time.perf_counter() - call.wall0 - call.build_s, msg, path_min, nlp=nlp,
                                fallbacks=list(call.fallbacks), build_s=call.build_s)

    # -- the two NLP forms ---------------------------------------------------------------------
    def _newton_for(self, pb: SubphaseProblem, kernels) -> CondensedNewton:
        if pb.spec not in self._newton:
            self._newton[pb.spec] = CondensedNewton(kernels, self.tolerance, self.max_iterations)
        return self._newton[pb.spec]

    def _solve_square(self, pb: SubphaseProblem, call: _Call) -> SubphaseSolution:
        kernels = self._kernels(pb, call)
        free = [i for i, fixed in enumerate(pb.fixed) if not fixed]
        u0, xs0, simulated = self._initial_guess(pb, free, call, kernels)
        newton = self._newton_for(pb, kernels)
        sol = newton.solve(pb.x0, pb.grid, u0, free, pb.context, xs0, simulated=simulated)
        result = self._finish(pb, sol.states, sol.u, sol.iterations, call, "", sol.success, kernels,
                              residual=sol.residual)
        if not result.success and len(free) == 1:
            # Newton on the full system can stall where swing1's kinematic knee is near-singular;
            # a single-shooting root of the same discretisation has zero defects, so it solves
            # the same equations. Polish it by bisection on the one free parameter.
            u_ss, xs = self._bracket_guess(pb, free[0], u0, kernels, tol=self.tolerance)
            call.note("single-shooting-root")
            polished = self._finish(pb, xs, u_ss, result.iterations, call, "", True, kernels)
            if polished.success:
                polished.message = "Newton stalled; single-shooting root of the same equations"
                return polished
        if not result.success:
            homotopy = self._homotopy(pb, newton, u0, free, call, result.iterations, kernels)
            if homotopy is not None:
                return homotopy
        if not result.success and pb.scan and 2 <= len(free) <= SCAN_MAX_FREE:
            scanned = self._scan(pb, newton, free, call, result.iterations, kernels)
            if scanned is not None:
                return scanned
        return result

    @staticmethod
    def _ipopt_params(pb: SubphaseProblem) -> np.ndarray:
        """The NLP's parameters (:mod:`.ipopt_nlp`): x0, grid, context, nominal unknowns, scales and
        the weights that keep the unknowns the square problem holds fixed near their nominal
        values (none for an optimised formulation, judged by its cost alone)."""
        weights = np.array([1.0 if f and pb.spec.residuals is None else 0.0 for f in pb.fixed])
        return np.concatenate([pb.x0, pb.grid, pb.context, pb.guess, pb.scale, weights])

    def _same_problem_start(self, pb: SubphaseProblem) -> SubphaseSolution | None:
        """The problem's ``previous_solution`` when IPOPT found it for this very problem (its NLP
        parameters and path bounds within REPEAT_TOLERANCE: a periodic walk's next step), else None."""
        prev, spec, n = pb.previous_solution, pb.spec, self.intervals
        if prev is None or prev.ipopt is None or np.shape(prev.states) != (n + 1, spec.nx):
            return None
        if list(prev.parameters) != list(spec.unknown_names) or not np.isfinite(prev.states).all():
            return None
        return prev if prev.ipopt.repeated_by(self._problem_key(pb), REPEAT_TOLERANCE) else None

    @staticmethod
    def _problem_key(pb: SubphaseProblem) -> np.ndarray:
        """What makes two of a subphase's NLPs the same problem: their parameters and their path
        constraints' lower bounds where these are numbers (a rule of the states, such as the lock
        rule's, is the spec's; infinite bounds as +-1e300, so that they compare)."""
        params = MultipleShootingSolver._ipopt_params(pb)
        if not isinstance(pb.path_lower, np.ndarray):
            return params
        return np.concatenate([params, np.nan_to_num(pb.path_lower.ravel(), posinf=1e300, neginf=-1e300)])

    def _ipopt_from(self, pb: SubphaseProblem, call: _Call, start: SubphaseSolution | None) -> SubphaseSolution:
        """IPOPT from the step before's solution of the same problem when there is one, else (or
        should that fail: ``ipopt-restart``) from ``start`` (:meth:`_solve_ipopt`).

        A periodic walk's steps repeat: the step before's solution, its multipliers and active
        nodes with it, starts this one at its end (a 1 km/h stance's repair: 25 IPOPT iterations
        -> 3; a tracking stance's optimisation 13 -> 1). Only the same problem: the stance's fit of
        the hip to its sinusoid can have more than one local optimum, and a start from another
        problem's may reach another than the usual start would (0.5 km/h, 1.5 m: a cost 8 % higher)."""
        previous = self._same_problem_start(pb)
        if previous is not None:
            result = self._solve_ipopt(pb, call, None, previous)
            if result.success:
                return result
            call.note("ipopt-restart")
        return self._solve_ipopt(pb, call, start)

    def _solve_ipopt(self, pb: SubphaseProblem, call: _Call, start: SubphaseSolution | None,
                     previous: SubphaseSolution | None = None) -> SubphaseSolution:
        """IPOPT on the NLP from ``previous`` (the step before's solution, with its multipliers: the
        warm solver from its first pass), else from ``start`` (the square solution) or the
        problem's initial guess (a simulation, or the node states it carries)."""
        spec, n = pb.spec, self.intervals
        kernels = self._kernels(pb, call)
        solver = call.built(ipopt_solver, spec, n, self.substeps, self.tolerance, self.max_iterations)
        sol = None
        if previous is not None:
            u0, xs0 = np.array([previous.parameters[k] for k in spec.unknown_names]), previous.states[1:]
            sol = {"lam_g": previous.ipopt.lam_g, "lam_x": previous.ipopt.lam_x}
        elif start is not None and np.isfinite(start.states).all():
            u0, xs0 = np.array([start.parameters[k] for k in spec.unknown_names]), start.states[1:]
        else:
            u0, xs0, _ = self._initial_guess(pb, [], call, kernels)
        z0 = np.concatenate([xs0.ravel(), u0])
        params, problem = self._ipopt_params(pb), self._problem_key(pb)
        n_eq = n * spec.nx + spec.final.size1_out(0)
        iterations, active, result = 0, None, None
        for _ in range(4):
            lower = path_bounds(pb, pb.grid, np.vstack([pb.x0, z0[: n * spec.nx].reshape(n, spec.nx)]))
            if lower is None:
                lower = np.full((n + 1, len(spec.path_names)), -np.inf)
            if active is not None and np.array_equal(active, np.isfinite(lower)):
                break
            active = np.isfinite(lower)
            lbg, ubg = np.zeros(n_eq), np.zeros(n_eq)
            if spec.path is not None:
                lbg = np.concatenate([lbg, lower.T.ravel()])
                ubg = np.concatenate([ubg, np.full(lower.size, np.inf)])
            with IPOPT_LOCK:   # one IPOPT at a time, and these statistics this solve's (.thread_safety)
                if sol is not None:      # from a solution and its multipliers: a later pass, or a warm start
                    warm = call.built(ipopt_solver, spec, n, self.substeps, self.tolerance, self.max_iterations, True)
                    sol = warm(x0=z0, p=params, lbg=lbg, ubg=ubg, lam_g0=sol["lam_g"], lam_x0=sol["lam_x"])
                    stats = warm.stats()
                else:
                    sol = solver(x0=z0, p=params, lbg=lbg, ubg=ubg)
                    stats = solver.stats()
            iterations += int(stats.get("iter_count", 0))
            z0 = np.asarray(sol["x"]).ravel()
            result = self._finish(pb, z0[: n * spec.nx], z0[n * spec.nx:], iterations, call,
                                  "" if stats.get("success") else str(stats.get("return_status")),
                                  bool(stats.get("success")), kernels, choices.IPOPT)
            if not result.success:
                break
            result.ipopt = IpoptPoint(np.asarray(sol["lam_g"]).ravel(), np.asarray(sol["lam_x"]).ravel(), problem)
        if result.path_min < -1e-7:
            result.success = False
            # IPOPT's own status, when it stopped early, stays the message: it is the cause
            # (failure_cause names the violation from path_min as well)
            result.message = result.message or f"path constraint violated by {-result.path_min:.3g}"
        return result

    def solve(self, pb: SubphaseProblem) -> SubphaseSolution:
        call = _Call()
        if pb.grid.size != self.intervals + 1:
            raise ValueError(f"{pb.spec.name}: grid has {pb.grid.size - 1} intervals, solver {self.intervals}")
        has_path = pb.spec.path is not None and pb.path_lower is not None
        # straight to IPOPT: an optimisation with a warm start, or nlp="ipopt" on an inequality problem
        if (self._warm(pb) if pb.optimize else self.nlp == choices.IPOPT and has_path):
            return self._ipopt_from(pb, call, None)
        result = self._solve_square(pb, call)
        violated = has_path and result.path_min < 0
        # a cold optimisation, or a repair, starts from the square solution: a nearby trajectory
        if pb.optimize or (violated and self.nlp != choices.ROOTFINDER):
            if not pb.optimize:
                call.note("ipopt-repair")
            return self._ipopt_from(pb, call, result if result.success else None)
        if violated:
            result.message = f"path constraint violated by {-result.path_min:.3g} (nlp=rootfinder)"
        return result
