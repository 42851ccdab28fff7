"""Mode (a): CasADi multiple shooting, solved by ``rootfinder`` (square) or IPOPT (inequalities).

Decision vector, for N intervals and a spec with nx states and nu free parameters:

    z = [X_1, ..., X_N, u_free]        (X_k in R^nx are the node states; X_0 = x0 is a parameter)

Equations: the continuity defects ``X_{k+1} - Phi(X_k, t_k, h_k, u, c)`` for k = 0..N-1 and the
final conditions ``g(X_N, c)``; Phi is the shared RK4 interval (:mod:`.integrator`). The parameter
vector ``P = [x0, t_0..t_N, c, u_all]`` carries everything that changes from step to step, so each
solver is built once per (spec, N, substeps, set of free unknowns) and reused with new P.

- Square problems (as many free unknowns as final conditions) go to ``rootfinder('newton')``.
- Problems with path inequalities ``h(X_k, t_k, u, c) >= lower_k`` go to IPOPT: the unknowns held
  fixed in the square problem (e.g. the swing2 hip position actuator) become free, and the
  objective keeps them as close as possible to their nominal values. This is the OCP form of the
  paper's recovery loop: instead of raising the actuator in increments until the toe clears, it
  finds the smallest change that makes it clear.
- A spec with least-squares residuals (the stance's hip-height tracking) is optimised instead:
  the objective is the mean of their squares over the nodes, every unknown is free (pa over the
  grid), and IPOPT gets the Gauss-Newton Hessian 2 J^T J of the residuals: the exact Hessian of
  the Lagrangian costs 80 ms per evaluation here (second derivatives through 80 RK4 stages),
  while the constraint curvature it adds buys few iterations near a small-residual optimum.
- Bounds that depend on the motion (the stance lock rule applies while theta1 < 0) are evaluated
  on the starting trajectory, then on each solution, and the NLP is re-solved from the last
  solution until the set of active nodes no longer changes.
"""
from __future__ import annotations

import time
from functools import lru_cache

import casadi as ca
import numpy as np

from .integrator import interval_function, trajectory_function
from .problem import (SubphaseProblem, SubphaseSolution, SubphaseSpec, mapped, path_bounds, path_margin,
                      plausibility_margin)


def _unknowns(spec: SubphaseSpec, u_all: ca.SX, u_free: ca.SX, free_mask: tuple) -> ca.SX:
    parts, j = [], 0
    for i, free in enumerate(free_mask):
        if free:
            parts.append(u_free[j])
            j += 1
        else:
            parts.append(u_all[i])
    return ca.vertcat(*parts)


@lru_cache(maxsize=None)
def _transcription(spec: SubphaseSpec, intervals: int, substeps: int, free_mask: tuple):
    """Symbols and expressions of the multiple-shooting transcription (built once)."""
    n, nx = intervals, spec.nx
    n_free = sum(free_mask)
    z = ca.SX.sym("z", n * nx + n_free)
    x0, tn = ca.SX.sym("x0", nx), ca.SX.sym("t", n + 1)
    c, u_all = ca.SX.sym("c", spec.nc), ca.SX.sym("u_all", spec.nu)
    # shift of the final conditions: zero, except along the homotopy of a cold start
    shift = ca.SX.sym("shift", spec.final.size1_out(0))
    params = ca.vertcat(x0, tn, c, u_all, shift)
    states = ca.reshape(z[: n * nx], nx, n)
    u = _unknowns(spec, u_all, z[n * nx:], free_mask)
    previous = ca.horzcat(x0, states[:, : n - 1])
    step = interval_function(spec, substeps).map(n)
    propagated = step(previous, tn[:n].T, (tn[1:] - tn[:n]).T, ca.repmat(u, 1, n), ca.repmat(c, 1, n))
    defects = ca.vec(states - propagated)
    final = spec.final(states[:, n - 1], c) - shift
    all_states = ca.horzcat(x0, states)
    path = None
    if spec.path is not None:
        path_map = spec.path.map(n + 1)
        path = ca.vec(path_map(all_states, tn.T, ca.repmat(u, 1, n + 1), ca.repmat(c, 1, n + 1)).T)
    return dict(z=z, params=params, defects=defects, final=final, path=path, u=u, u_all=u_all,
                states=all_states, times=tn, context=c)


@lru_cache(maxsize=None)
def _rootfinder(spec: SubphaseSpec, intervals: int, substeps: int, free_mask: tuple, tol: float, max_iter: int):
    tr = _transcription(spec, intervals, substeps, free_mask)
    residual = ca.Function(f"{spec.name}_ms_residual", [tr["z"], tr["params"]],
                           [ca.vertcat(tr["defects"], tr["final"])])
    return ca.rootfinder(f"{spec.name}_ms_rf", "newton", residual,
                         {"abstol": tol, "abstolStep": tol * 1e-3, "max_iter": max_iter,
                          "error_on_fail": False,
                          # a NaN trial step is handled (the solve fails, a fallback follows);
                          # CasADi's warning for each would only bury the one-line report
                          "show_eval_warnings": False})


@lru_cache(maxsize=None)
def _ipopt(spec: SubphaseSpec, intervals: int, substeps: int, tol: float, max_iter: int):
    free_mask = tuple(True for _ in range(spec.nu))
    tr = _transcription(spec, intervals, substeps, free_mask)
    n_u = spec.nu
    u_nominal, u_scale = ca.SX.sym("u_nominal", n_u), ca.SX.sym("u_scale", n_u)
    weights = ca.SX.sym("w", n_u)   # 1 for unknowns held fixed in the square problem
    deviation = (tr["u"] - u_nominal) / u_scale
    residuals = [weights * deviation, 1e-4 * deviation]
    if spec.residuals is not None:
        nodes = intervals + 1
        running = spec.residuals.map(nodes)(tr["states"], tr["times"].T, ca.repmat(tr["u"], 1, nodes),
                                            ca.repmat(tr["context"], 1, nodes))
        residuals.append(ca.vec(running) / np.sqrt(nodes))
    residuals = ca.vertcat(*residuals)
    objective = ca.sumsqr(residuals)
    g = ca.vertcat(tr["defects"], tr["final"], tr["path"] if tr["path"] is not None else ca.SX(0, 1))
    p = ca.vertcat(tr["params"], u_nominal, u_scale, weights)
    nlp = {"x": tr["z"], "p": p, "f": objective, "g": g}
    opts = {"ipopt.tol": tol, "ipopt.constr_viol_tol": tol, "ipopt.max_iter": max_iter * 10,
            "ipopt.print_level": 0, "print_time": False, "expand": True,
            "ipopt.sb": "yes", "error_on_fail": False, "show_eval_warnings": False}
    if spec.residuals is not None:
        jac = ca.jacobian(residuals, tr["z"])
        lam_f, lam_g = ca.SX.sym("lam_f"), ca.SX.sym("lam_g", g.numel())
        opts["hess_lag"] = ca.Function("gauss_newton", [tr["z"], p, lam_f, lam_g],
                                       [ca.triu(2 * lam_f * ca.mtimes(jac.T, jac))],
                                       ["x", "p", "lam_f", "lam_g"], ["hess_gamma_x_x"])
    return ca.nlpsol(f"{spec.name}_ms_ipopt", "ipopt", nlp, opts)


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


class MultipleShootingSolver:
    """Solve subphases by multiple shooting; see the module docstring for the formulation.

    ``nlp``: "auto" (rootfinder, then IPOPT only if a path inequality is violated), "rootfinder"
    (never IPOPT; a violated inequality is reported in the message) or "ipopt" (always).
    """

    name = "multiple-shooting"

    def __init__(self, intervals: int = 20, substeps: int = 4, tolerance: float = 1e-10,
                 max_iterations: int = 50, nlp: str = "auto"):
        self.intervals, self.substeps = int(intervals), int(substeps)
        self.tolerance, self.max_iterations, self.nlp = float(tolerance), int(max_iterations), nlp

    # -- helpers -------------------------------------------------------------------------------
    def _params(self, pb: SubphaseProblem, u_all, shift=None) -> np.ndarray:
        shift = np.zeros(pb.spec.final.size1_out(0)) if shift is None else shift
        return np.concatenate([pb.x0, pb.grid, pb.context, u_all, shift])

    def _simulate(self, pb: SubphaseProblem, u: np.ndarray) -> np.ndarray:
        traj = trajectory_function(pb.spec, self.substeps, self.intervals)
        xs = traj(pb.x0, pb.grid[:-1], np.diff(pb.grid), np.tile(u[:, None], (1, self.intervals)),
                  np.tile(pb.context[:, None], (1, self.intervals)))
        return np.asarray(xs).T

    def _initial_guess(self, pb: SubphaseProblem, free: list, call: _Call) -> tuple[np.ndarray, np.ndarray]:
        """Free parameters and node states to start Newton from.

        A simulation with the given guess initialises the nodes. When its final conditions are
        far off (a cold start), a few damped Newton steps on the single-shooting residual
        (finite differences) first bring the parameters near the root, so that the node states
        start on a trajectory that nearly satisfies them.
        """
        u = pb.guess.copy()
        if self._warm(pb):
            return u, np.asarray(pb.state_guess)[1:]
        final = lambda xs: np.asarray(pb.spec.final(xs[-1], pb.context)).ravel()
        xs = self._simulate(pb, u)
        res = final(xs)
        for _ in range(8):
            if not np.all(np.isfinite(res)) or np.max(np.abs(res)) < 1e-3 or len(free) != res.size:
                break
            jac = np.empty((res.size, len(free)))
            for j, i in enumerate(free):
                du = 1e-4 * abs(pb.scale[i]) or 1e-6
                trial = u.copy(); trial[i] += du
                jac[:, j] = (final(self._simulate(pb, trial)) - res) / du
            try:
                step = np.linalg.solve(jac, -res)
            except np.linalg.LinAlgError:
                break
            for damping in (1.0, 0.5, 0.25, 0.125):
                trial = u.copy(); trial[free] += damping * step
                xs_trial = self._simulate(pb, trial)
                res_trial = final(xs_trial)
                if np.all(np.isfinite(res_trial)) and np.max(np.abs(res_trial)) < np.max(np.abs(res)):
                    u, xs, res = trial, xs_trial, res_trial
                    break
            else:
                break
        if len(free) == 1 and res.size == 1 and not (np.isfinite(res[0]) and abs(res[0]) < 1e-3):
            call.note("bracket")
            u, xs = self._bracket_guess(pb, free[0], u, final)
        return u, np.where(np.isfinite(xs), xs, np.tile(pb.x0, (self.intervals, 1)))

    def _warm(self, pb: SubphaseProblem) -> bool:
        """Whether the problem carries node states to start from (the previous step's solution)."""
        return pb.state_guess is not None and np.shape(pb.state_guess) == (self.intervals + 1, pb.spec.nx)

    def _bracket_guess(self, pb, i, u, final, tol: float = 1e-4):
        """One free unknown whose single-shooting residual Newton could not reduce (a trajectory
        near a kinematic singularity): scan outwards for a sign change, then bisect it."""
        def f(value):
            trial = u.copy(); trial[i] = value
            xs = self._simulate(pb, trial)
            return float(final(xs)[0]), trial, xs
        f0, best_u, best_xs = f(u[i])
        if not np.isfinite(f0):
            return u, best_xs
        scale = abs(pb.scale[i]) or 1.0
        for k in range(12):
            for sign in (-1.0, 1.0):
                b = u[i] + sign * scale * 2.0 ** (k - 2)
                fb, trial, xs = f(b)
                if np.isfinite(fb) and fb * f0 <= 0:
                    a, fa = u[i], f0
                    for _ in range(200):
                        m = 0.5 * (a + b)
                        fm, trial, xs = f(m)
                        if abs(fm) < tol or abs(b - a) < 1e-15 * max(1.0, abs(m)):
                            break
                        if fm * fa <= 0:
                            b = m
                        else:
                            a, fa = m, fm
                    return trial, xs
        return best_u, best_xs

    def _finish(self, pb, z, u, iterations, call: _Call, message, success_hint, nlp="rootfinder") -> SubphaseSolution:
        spec, n = pb.spec, self.intervals
        states = np.vstack([pb.x0, np.asarray(z[: n * spec.nx]).reshape(n, spec.nx)])
        # The reported residual is that of the discrete trajectory the solver returns.
        residual = float(np.max(np.abs(np.asarray(spec.final(states[-1], pb.context)))))
        propagated = mapped(interval_function(spec, self.substeps), n)(
            states[:-1].T, pb.grid[:-1], np.diff(pb.grid), u, pb.context)
        defect = float(np.max(np.abs(np.asarray(propagated).T - states[1:])))
        forces = np.asarray(mapped(spec.outputs, n + 1)(states.T, pb.grid, u, pb.context)).T
        path_min = path_margin(pb, states, u)
        plausible = plausibility_margin(pb, states) >= 0
        ok = (success_hint and max(residual, defect) <= max(10 * self.tolerance, 1e-9)
              and np.all(np.isfinite(states)) and plausible)
        msg = message or ("" if ok else f"residual {residual:.3g}, defect {defect:.3g}"
                          + ("" if plausible else ", implausible motion (a root far from any walk)"))
        return SubphaseSolution(spec.name, self.name, dict(zip(spec.unknown_names, map(float, u))), pb.grid.copy(),
                                states, forces, max(residual, defect), iterations, bool(ok),
                                time.perf_counter() - call.wall0 - call.build_s, msg, path_min, nlp=nlp,
                                fallbacks=list(call.fallbacks), build_s=call.build_s)

    # -- the two NLP forms ---------------------------------------------------------------------
    def _solve_square(self, pb: SubphaseProblem, call: _Call) -> SubphaseSolution:
        spec, n = pb.spec, self.intervals
        free_mask = tuple(not f for f in pb.fixed)
        rf = call.built(_rootfinder, spec, n, self.substeps, free_mask, self.tolerance, self.max_iterations)
        free = [i for i, f in enumerate(free_mask) if f]
        u0, xs0 = self._initial_guess(pb, free, call)
        z0 = np.concatenate([xs0.ravel(), u0[free]])
        z = np.asarray(rf(z0, self._params(pb, pb.guess))).ravel()
        stats = rf.stats()
        u = pb.guess.copy()
        u[list(free_mask)] = z[n * spec.nx:]
        result = self._finish(pb, z, u, int(stats.get("iter_count", stats.get("n_iter", 0)) or 0), call,
                              "", bool(stats.get("success", True)))
        if not result.success and len(free) == 1:
            # Newton on the full system can stall where swing1's kinematic knee is near-singular;
            # a single-shooting root of the same discretisation has zero defects, so it solves
            # the same equations. Polish it by bisection on the one free parameter.
            final = lambda xs: np.asarray(spec.final(xs[-1], pb.context)).ravel()
            u_ss, xs = self._bracket_guess(pb, free[0], u0, final, tol=self.tolerance)
            z_ss = np.concatenate([xs.ravel(), u_ss[free]])
            call.note("single-shooting-root")
            polished = self._finish(pb, z_ss, u_ss, result.iterations, call, "", True)
            if polished.success:
                polished.message = "Newton stalled; single-shooting root of the same equations"
                return polished
        if not result.success:
            homotopy = self._homotopy(pb, rf, u0, free_mask, call, result.iterations)
            if homotopy is not None:
                return homotopy
        return result

    def _homotopy(self, pb, rf, u0, free_mask, call: _Call, iterations: int, stages: int = 8):
        """Newton along g(X_N) - (1 - lam) g0 = 0, lam = 1/stages ... 1, from the simulation of
        the guess (an exact solution at lam = 0: zero defects, final conditions g0).

        A cold start far from the root (the first stance of a 0.5 km/h walk from the all-zero
        guess: the body falls backwards and the telescope ends metres long) is beyond Newton's
        reach; every stage of the continuation starts next to its root. The same continuation as
        plain shooting's homotopy, on the multiple-shooting equations.
        """
        spec, n = pb.spec, self.intervals
        call.note("homotopy")
        xs = self._simulate(pb, u0)
        if not np.all(np.isfinite(xs)):
            return None
        g0 = np.asarray(spec.final(xs[-1], pb.context)).ravel()
        z = np.concatenate([xs.ravel(), u0[list(free_mask)]])
        for lam in np.linspace(1 / stages, 1.0, stages):
            z = np.asarray(rf(z, self._params(pb, pb.guess, (1 - lam) * g0))).ravel()
            stats = rf.stats()
            iterations += int(stats.get("iter_count", stats.get("n_iter", 0)) or 0)
            if not stats.get("success", True) or not np.all(np.isfinite(z)):
                return None
        u = pb.guess.copy()
        u[list(free_mask)] = z[n * spec.nx:]
        result = self._finish(pb, z, u, iterations, call, "", True)
        return result if result.success else None

    def _solve_ipopt(self, pb: SubphaseProblem, call: _Call, start: SubphaseSolution | None) -> SubphaseSolution:
        spec, n = pb.spec, self.intervals
        solver = call.built(_ipopt, spec, n, self.substeps, self.tolerance, self.max_iterations)
        if start is not None and np.all(np.isfinite(start.states)):
            u0, xs0 = np.array([start.parameters[k] for k in spec.unknown_names]), start.states[1:]
        else:
            u0, xs0 = self._initial_guess(pb, [], call)
        z0 = np.concatenate([xs0.ravel(), u0])
        # an optimised formulation is judged by its cost alone; otherwise stay near the nominal unknowns
        weights = np.array([1.0 if f and spec.residuals is None else 0.0 for f in pb.fixed])
        params = np.concatenate([self._params(pb, pb.guess), pb.guess, pb.scale, weights])
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
            sol = solver(x0=z0, p=params, lbg=lbg, ubg=ubg)
            stats = solver.stats()
            iterations += int(stats.get("iter_count", 0))
            z0 = np.asarray(sol["x"]).ravel()
            result = self._finish(pb, z0, z0[n * spec.nx:], iterations, call,
                                  "" if stats.get("success") else str(stats.get("return_status")),
                                  bool(stats.get("success")), "ipopt")
            if not result.success:
                break
        if result.path_min < -1e-7:
            result.success = False
            result.message = f"path constraint violated by {-result.path_min:.3g}"
        return result

    def solve(self, pb: SubphaseProblem) -> SubphaseSolution:
        call = _Call()
        if pb.grid.size != self.intervals + 1:
            raise ValueError(f"{pb.spec.name}: grid has {pb.grid.size - 1} intervals, solver {self.intervals}")
        has_path = pb.spec.path is not None and pb.path_lower is not None
        # straight to IPOPT: an optimisation with a warm start, or nlp="ipopt" on an inequality problem
        if (self._warm(pb) if pb.optimize else self.nlp == "ipopt" and has_path):
            return self._solve_ipopt(pb, call, None)
        result = self._solve_square(pb, call)
        violated = has_path and result.path_min < 0
        # a cold optimisation, or a repair, starts from the square solution: a nearby trajectory
        if pb.optimize or (violated and self.nlp != "rootfinder"):
            if not pb.optimize:
                call.note("ipopt-repair")
            return self._solve_ipopt(pb, call, result if result.success else None)
        if violated:
            result.message = f"path constraint violated by {-result.path_min:.3g} (nlp=rootfinder)"
        return result
