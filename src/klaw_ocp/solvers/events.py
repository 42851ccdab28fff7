"""Forward integration of a subphase with state events, for plain shooting (sections 4.2, 4.3).

The paper's stance "subphases are triggered by events" (the leg locks when it grows past l1
before it is vertical, and unlocks when it passes the vertical). Integration uses the RK4
interval shared with multiple shooting, node by node; a sign change of an armed event inside an
interval is located by the secant method on the partial interval, the event's switch (a lock
map) is applied there, and the integration goes on with the switched context.
"""
from __future__ import annotations


import numpy as np
from scipy.optimize import minimize_scalar

from .integrator import subphase_kernels
from .problem import SubphaseProblem

#: partial intervals on which an interval is looked into for a crossing that comes back
SUBSAMPLES = 8
#: an extremum between sub-samples is located to this fraction of the interval (its value is the
#: extremum's to second order)
_EXTREMUM_XTOL = 1e-4
#: the cubic Hermite basis (h00, h10, h01, h11) at the interior sub-samples s = 1/8 .. 7/8:
#: g(s) = h00 g0 + h10 h r0 + h01 g1 + h11 h r1
_HERMITE = tuple((2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2)
                 for s in (k / SUBSAMPLES for k in range(1, SUBSAMPLES)))


def hermite_crosses(g0: float, g1: float, r0: float, r1: float, h: float, direction: int) -> bool:
    """Whether the cubic Hermite interpolant of an interval (values g0, g1 and rates r0, r1 at its
    ends, length h) changes sign in ``direction`` between its sub-samples, the ends included."""
    previous = direction * g0
    for a, b, c, e in _HERMITE:
        value = direction * (a * g0 + b * h * r0 + c * g1 + e * h * r1)
        if previous < 0 <= value:
            return True
        previous = value
    return previous < 0 <= direction * g1


#: how far beyond its ends an interval's trajectory is taken to reach where it turns inside: twice
#: the most the cubic Hermite interpolant departs from the chord, 4/27 h (|r0 - c| + |r1 - c|)
#: (c the chord's slope), since the trajectory itself is no cubic
_TURN_REACH = 2 * 4 / 27


def may_cross(g0: float, g1: float, r0: float, r1: float, h: float, direction: int) -> bool:
    """Whether an interval may cross zero in ``direction``, its ends' sign change included: the
    cubic Hermite interpolant of its ends crosses, or the trajectory turns inside (a rate at an end
    against the chord's direction) near enough to zero (:data:`_TURN_REACH`). Plain floats: a walk
    asks ~10^4 times, an interval at a time, where numpy's fixed costs would dominate."""
    chord = (g1 - g0) / h
    nearest = min(abs(g0), abs(g1))
    if g0 * g1 > 0 and nearest > _TURN_REACH * h * (abs(r0 - chord) + abs(r1 - chord)):
        return False   # neither the cubic (at most half that far from the chord) nor a turn
    turns = r0 * chord < 0 or r1 * chord < 0
    return hermite_crosses(g0, g1, r0, r1, h, direction) or turns


class _Crossed(Exception):
    """Raised by the searched function to end :func:`_extremum` at the first value past zero."""

    def __init__(self, s: float, value: float):
        super().__init__(s, value)
        self.s, self.value = s, value


def _extremum(f, a: float, b: float, sign: float, span: float) -> tuple[float, float]:
    """(s, f(s)) at the extremum of f on [a, b] (sign -1: the least, +1: the greatest) by Brent's
    method (scipy's bounded scalar minimisation), to ``span`` x :data:`_EXTREMUM_XTOL` in s; it
    stops at the first value on the other side of zero (f < 0 for the least, f >= 0 for the
    greatest): only whether and where the crossing is matters."""
    def objective(s):
        value = f(s)
        if (value < 0) if sign < 0 else (value >= 0):
            raise _Crossed(s, value)
        return -sign * value
    try:
        found = minimize_scalar(objective, bounds=(a, b), method="bounded",
                                options={"xatol": _EXTREMUM_XTOL * span, "maxiter": 40})
    except _Crossed as crossed:
        return crossed.s, crossed.value
    return float(found.x), -sign * float(found.fun)


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
        start, known = self._first_sign_change(kernels, pb, states, u) if armed and spec.events else (None, {})
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
                hit = self._first_event(kernels, x, t0, x1, t1, u, c, mode, known)
                known = {}   # the fast pass's brackets hold for the interval it started from only
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
        """Index of the first interval on which an event armed in the initial mode (``pb.mode``)
        fires: a sign change at its ends, or one :func:`may_cross` suspects inside and the
        interval's sub-samples confirm (:meth:`_hidden_bracket`). Returns (index or None, the
        brackets so confirmed on that interval, by event, for :meth:`_first_event` to reuse)."""
        values = kernels.samples(states, pb.grid, u, pb.context)[3]
        grid, first, confirmed = pb.grid.tolist(), None, {}
        for e, event in enumerate(kernels.spec.events):
            d, g = event.direction, values[:, e].tolist()
            r = None if event.rate is None else np.asarray(event.rate(states), float).tolist()
            for k in range(len(grid) - 1 if first is None else first):
                ends = d * g[k] < 0 <= d * g[k + 1]
                if not ends and (r is None or not may_cross(g[k], g[k + 1], r[k], r[k + 1], grid[k + 1] - grid[k], d)):
                    continue
                if not event.guard(states[k], grid[k], pb.context, pb.mode):
                    continue
                if not ends:
                    bracket = self._hidden_bracket(
                        kernels, e, d, states[k], grid[k], u, pb.context,
                        *self._subsamples(kernels, states[k], grid[k], grid[k + 1] - grid[k], u, pb.context,
                                          values[k], values[k + 1]))
                    if bracket is None:
                        continue   # a suspicion the trajectory does not bear out: no need to step node by node
                    confirmed.setdefault(k, {})[e] = bracket
                first = k
                break
        return first, confirmed.get(first, {})

    def _first_event(self, kernels, x0, t0, x1, t1, u, c, mode, known=None):
        """The event that fires first on the interval from (t0, x0) to (t1, x1) and its time after
        t0, or None; ``known``: brackets of hidden crossings already confirmed on it, by event."""
        best, known = None, known or {}
        g0_all, g1_all = kernels.events(x0, t0, u, c)[0], kernels.events(x1, t1, u, c)[0]
        sub = None   # the interval's sub-samples (times, event values), computed once if needed
        for e, event in enumerate(kernels.spec.events):
            if not event.guard(x0, t0, c, mode):
                continue
            g0, g1, d = float(g0_all[e]), float(g1_all[e]), event.direction
            if e in known:
                bracket = known[e]
            elif g0 * d < 0 <= g1 * d:
                bracket = (0.0, t1 - t0, g0, g1)
            elif event.rate is not None and self._may_cross(g0, g1, event, x0, x1, t1 - t0, d):
                if sub is None:
                    sub = self._subsamples(kernels, x0, t0, t1 - t0, u, c, g0_all, g1_all)
                bracket = self._hidden_bracket(kernels, e, d, x0, t0, u, c, *sub)
                if bracket is None:
                    continue   # a suspicion the RK4 trajectory does not bear out
            else:
                continue
            h = self._locate(kernels, e, x0, t0, *bracket, u, c)
            if best is None or h < best[1]:
                best = (event, h)
        return best

    @staticmethod
    def _may_cross(g0, g1, event, x0, x1, h, d) -> bool:
        """:func:`may_cross` of one interval from its end states."""
        r0, r1 = float(event.rate(x0[None, :])[0]), float(event.rate(x1[None, :])[0])
        return may_cross(g0, g1, r0, r1, h, d)

    @staticmethod
    def _hidden_bracket(kernels, e, d, x0, t0, u, c, times, values):
        """(a, b, g(a), g(b)) about event e's first crossing in direction d inside an interval,
        from its sub-samples (``times``, ``values``): their first sign change in d; where they
        show none, a dip of d·g below zero between the leading non-negative sub-samples, or a
        bump above it between the trailing negative ones, found as the extremum (:func:`_extremum`)
        next to the least (greatest) sub-sample. None if the RK4 trajectory does not cross."""
        g = d * values[:, e]
        j = np.flatnonzero((g[:-1] < 0) & (g[1:] >= 0))
        if j.size:
            j = int(j[0])
            return times[j], times[j + 1], values[j, e], values[j + 1, e]
        at = lambda s: d * float(kernels.events(kernels.step(x0, t0, s, u, c)[0], t0 + s, u, c)[0][e])
        negative = np.flatnonzero(g < 0)
        head = len(g) if negative.size == 0 else int(negative[0])
        if head >= 2:   # a dip inside the non-negative run
            k = int(np.argmin(g[:head]))
            s, f = _extremum(at, times[max(k - 1, 0)], times[min(k + 1, head - 1)], -1.0, times[-1])
            if f < 0:
                after = int(np.searchsorted(times, s, side="right"))
                return s, times[after], d * f, values[after, e]
        if len(g) - head >= 2:   # a bump inside the negative run (samples after it all negative)
            k = head + int(np.argmax(g[head:]))
            s, f = _extremum(at, times[max(k - 1, head)], times[min(k + 1, len(g) - 1)], 1.0, times[-1])
            if f >= 0:
                before = int(np.searchsorted(times, s, side="left")) - 1
                return times[before], s, values[before, e], d * f
        return None

    @staticmethod
    def _subsamples(kernels, x0, t0, h, u, c, g0, g1):
        """Event values at the :data:`SUBSAMPLES` partial intervals of an interval (the ends given)."""
        times = h * np.linspace(0.0, 1.0, SUBSAMPLES + 1)
        inner = [kernels.events(kernels.step(x0, t0, s, u, c)[0], t0 + s, u, c)[0] for s in times[1:-1]]
        return times, np.array([np.ravel(g0), *map(np.ravel, inner), np.ravel(g1)])

    def _locate(self, kernels, e, x0, t0, a, b, ga, gb, u, c):
        """The time after t0 in [a, b] (ga, gb of opposite signs there) where event e is zero: the
        secant method kept in its bracket (regula falsi) with the Illinois rule, which halves the
        value kept at an end the bracket keeps twice. Plain regula falsi stalls where one end's
        value is tiny against the other's (a leg that reaches l1 and dips back before it grows past
        it, in slow walks): it crept from that end by 0.3 % of the interval a step and, after 60,
        returned a time 28 ms late, the leg locked 0.085 mm past l1 (1 km/h, 1.72 m, 73 kg)."""
        kept = 0   # which end the last step kept: -1 a, +1 b
        for _ in range(100):
            with np.errstate(invalid="ignore", divide="ignore"):   # a NaN trial falls back to bisection
                m = b - gb * (b - a) / (gb - ga) if gb != ga else 0.5 * (a + b)
            if not a < m < b:
                m = 0.5 * (a + b)
            gm = float(kernels.events(kernels.step(x0, t0, m, u, c)[0], t0 + m, u, c)[0][e])
            if abs(gm) < 1e-13 or b - a < 1e-14:
                return m
            if np.sign(gm) * np.sign(ga) < 0:     # (signs: a diverging trial's gm * ga overflows)
                b, gb = m, gm
                if kept == -1:
                    ga *= 0.5
                kept = -1
            else:
                a, ga = m, gm
                if kept == 1:
                    gb *= 0.5
                kept = 1
        return 0.5 * (a + b)
