"""Multiple shooting's starts where Newton from the guess fails (docs/solvers.md, the fallbacks):
the one-parameter bracket, the continuation on the final conditions and the scan of the
single-shooting residual on two or three unknowns. Methods of
:class:`~klaw_ocp.solvers.multiple_shooting.MultipleShootingSolver`, kept apart from its Newton and
IPOPT paths; they use its ``_simulate``, ``_final`` and ``_finish``."""
from __future__ import annotations

import numpy as np

#: the ``scan`` fallback (:meth:`ColdStarts._scan`): problems with up to this many free unknowns,
#: each scanned to this many of its scales from the guess, Newton from this many best starts
SCAN_MAX_FREE, SCAN_REACH, SCAN_STARTS = 3, 64, 8


class ColdStarts:
    """The fallback starts of :class:`~klaw_ocp.solvers.multiple_shooting.MultipleShootingSolver`."""

    def _bracket_guess(self, pb, i, u, kernels, tol: float = 1e-4):
        """One free unknown whose single-shooting residual Newton could not reduce (a trajectory
        near a kinematic singularity): scan outwards for a sign change, then bisect it."""
        final = self._final(pb, kernels)

        def f(value):
            trial = u.copy(); trial[i] = value
            xs = self._simulate(pb, trial, kernels)
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

    def _scan(self, pb, newton, free, call, iterations: int, kernels):
        """The one-parameter ``bracket`` scan on two or three free unknowns: the single-shooting
        residual on a grid about the guess (each unknown at 0 and ±1, 2, 4 ... SCAN_REACH of its
        scale from it), and Newton from the SCAN_STARTS least of them.

        A first step's swing1 from the all-zero guess (5 km/h with 1.2 × the natural step, on the
        periodic orbit) starts where the final conditions hardly depend on one of its two
        unknowns: the damped steps, Newton and the continuation from there all stall, though the
        root (plain shooting's too) lies a few hundred scales away."""
        final = self._final(pb, kernels)
        levels = np.concatenate([[0.0], np.ravel([[s, -s] for s in 2.0 ** np.arange(int(np.log2(SCAN_REACH)) + 1)])])
        grid = np.stack(np.meshgrid(*[levels] * len(free), indexing="ij"), axis=-1).reshape(-1, len(free))
        starts = []
        for offsets in grid:
            u = pb.guess.copy()
            u[free] += offsets * np.abs(pb.scale[free])
            xs = self._simulate(pb, u, kernels)
            res = final(xs)
            if np.isfinite(xs).all() and np.isfinite(res).all():
                starts.append((float(np.abs(res).max()), len(starts), u, xs))
        call.note("scan")
        for _, _, u, xs in sorted(starts, key=lambda s: s[:2])[:SCAN_STARTS]:
            sol = newton.solve(pb.x0, pb.grid, u, free, pb.context, xs, simulated=True)
            iterations += sol.iterations
            if sol.success:
                result = self._finish(pb, sol.states, sol.u, iterations, call, "", True, kernels, residual=sol.residual)
                if result.success:
                    return result
        return None

    def _homotopy(self, pb, newton, u0, free, call, iterations: int, kernels, stages: int = 8):
        """Newton along g(X_N) - (1 - lam) g0 = 0, lam = 1/stages ... 1, from the simulation of
        the guess (an exact solution at lam = 0: zero defects, final conditions g0).

        A cold start far from the root (the first stance of a 0.5 km/h walk from the all-zero
        guess: the body falls backwards and the telescope ends metres long) is beyond Newton's
        reach; every stage of the continuation starts next to its root. The same continuation as
        plain shooting's homotopy, on the multiple-shooting equations.
        """
        call.note("homotopy")
        xs = self._simulate(pb, u0, kernels)
        if not np.isfinite(xs).all():
            return None
        g0 = self._final(pb, kernels)(xs)
        u = u0
        for lam in np.linspace(1 / stages, 1.0, stages):
            sol = newton.solve(pb.x0, pb.grid, u, free, pb.context, xs, (1 - lam) * g0, simulated=lam == 1 / stages)
            iterations += sol.iterations
            if not sol.success:
                return None
            xs, u = sol.states, sol.u
        result = self._finish(pb, xs, u, iterations, call, "", True, kernels)
        return result if result.success else None
