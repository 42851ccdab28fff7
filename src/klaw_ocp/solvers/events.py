"""Forward integration of a subphase with state events, for plain shooting (sections 4.2, 4.3).

The paper's stance "subphases are triggered by events" (the leg locks when it grows past l1
before it is vertical, and unlocks when it passes the vertical). Integration uses the RK4
interval shared with multiple shooting, node by node; a sign change of an armed event inside an
interval is located by the secant method on the partial interval, the event's switch (a lock
map) is applied there, and the integration goes on with the switched context.
"""
from __future__ import annotations

import numpy as np

from .integrator import subphase_kernels
from .problem import SubphaseProblem


class EventIntegrator:
    """RK4 with ``substeps`` steps per interval, watching the spec's events."""

    def __init__(self, substeps: int):
        self.substeps = int(substeps)

    def simulate(self, pb: SubphaseProblem, u: np.ndarray, armed: bool = True):
        """Integrate from x0 with parameters u; returns (times, states, context, event log).
        ``armed=False`` ignores the events (the smooth problem).

        The whole grid is first integrated in one call; only if an armed event changes sign on it
        does the integration go on node by node from the interval before that change.
        """
        spec = pb.spec
        n = pb.grid.size - 1
        kernels = subphase_kernels(spec, self.substeps, n)
        fast = kernels.sim(pb.x0, pb.grid[:-1], pb.h, u, pb.context)[0].reshape(n, spec.nx)
        states = np.vstack([pb.x0, fast])
        start = self._first_sign_change(kernels, pb, states, u) if armed and spec.events else None
        if start is None:
            return pb.grid.copy(), states, pb.context.copy(), []
        step = lambda x, t, h, u, c: kernels.step(x, t, h, u, c)[0]
        # the problem's mode, not heel strike's: a swing may start with the stance leg locked
        c, mode = pb.context.copy(), dict(pb.mode)
        x = states[start].copy()
        times, out, log = list(pb.grid[: start + 1]), list(states[: start + 1]), []
        for k in range(start, n):
            t0, t1 = pb.grid[k], pb.grid[k + 1]
            while True:
                x1 = step(x, t0, t1 - t0, u, c)
                hit = self._first_event(kernels, x, t0, x1, t1, u, c, mode)
                if hit is None:
                    break
                event, h = hit
                x = step(x, t0, h, u, c)
                t0 = t0 + h
                x, c, mode = event.apply(x, c, mode)
                times.append(t0)
                out.append(x.copy())
                log.append((event.name, float(t0)))
            x = x1
            times.append(t1)
            out.append(x.copy())
            if not np.all(np.isfinite(x)):
                break
        return np.array(times), np.array(out), c, log

    def _first_sign_change(self, kernels, pb, states, u):
        """Index of the first interval on which an event armed in the initial mode (``pb.mode``) fires."""
        values = kernels.samples(states, pb.grid, u, pb.context)[3]
        first = None
        for e, event in enumerate(kernels.spec.events):
            d = event.direction
            for k in range(len(states) - 1):
                if first is not None and k >= first:
                    break
                if values[k, e] * d < 0 <= values[k + 1, e] * d and event.guard(states[k], pb.grid[k], pb.context, pb.mode):
                    first = k
                    break
        return first

    def _first_event(self, kernels, x0, t0, x1, t1, u, c, mode):
        best = None
        g0_all, g1_all = kernels.events(x0, t0, u, c)[0], kernels.events(x1, t1, u, c)[0]
        for e, event in enumerate(kernels.spec.events):
            if not event.guard(x0, t0, c, mode):
                continue
            g0, g1 = float(g0_all[e]), float(g1_all[e])
            if not (g0 * event.direction < 0 <= g1 * event.direction):
                continue
            h = self._locate(kernels, e, x0, t0, t1 - t0, g0, g1, u, c)
            if best is None or h < best[1]:
                best = (event, h)
        return best

    def _locate(self, kernels, e, x0, t0, h, g0, g1, u, c):
        a, b, ga, gb = 0.0, h, g0, g1
        for _ in range(60):
            with np.errstate(invalid="ignore", divide="ignore"):   # a NaN trial falls back to bisection
                m = b - gb * (b - a) / (gb - ga) if gb != ga else 0.5 * (a + b)
            if not a < m < b:
                m = 0.5 * (a + b)
            gm = float(kernels.events(kernels.step(x0, t0, m, u, c)[0], t0 + m, u, c)[0][e])
            if abs(gm) < 1e-13 or b - a < 1e-14:
                return m
            if gm * ga < 0:
                b, gb = m, gm
            else:
                a, ga = m, gm
        return 0.5 * (a + b)
