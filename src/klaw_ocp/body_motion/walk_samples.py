"""The simulated walk between its stored nodes: the stance and swing states at any walk times (the
body's frames, :mod:`.motion`), read from a :class:`~klaw_ocp.walk.Walk`'s steps.

The solvers store each subphase's states at its grid nodes only (20 intervals a subphase). Between
them the states are cubic Hermite interpolated with the stored rates (w, θ1, θ2 with ẇ, θ̇1, θ̇2;
θ3, θ4 with θ̇3, θ̇4), so positions and rates match the dynamics at every node and the curves are
C1 inside a subphase. Swing1 has no θ̇4 state (its knee follows the ankle on curve P, §4.3): its
θ4 gets the rates of a C1 spline through its nodes. Plain shooting's lock events repeat a node's
time (the rates jump there): each interval of positive length is interpolated on its own, and a
sample at the event's instant takes the state after it.

Times: walk time t (s from the first heel strike) and step-local time τ (0 at the step's heel
strike, t_step at the next). Frames: x forward, y up (the stance model's plane, :mod:`klaw_ocp.dynamics`).
"""
from __future__ import annotations

import math
import weakref
from dataclasses import dataclass
from functools import cached_property

import numpy as np


def frame_times(duration: float, fps: float) -> np.ndarray:
    """The frames of a walk of ``duration`` s at ``fps`` frames per second: k/fps for k = 0 ..
    floor(duration·fps) (the 1e-9 keeps a walk that ends on a frame from losing it to rounding)."""
    if not (isinstance(fps, (int, float)) and not isinstance(fps, bool) and math.isfinite(fps) and fps > 0):
        raise ValueError(f"fps: expected a finite number > 0, got {fps!r}")
    return np.arange(math.floor(duration * fps + 1e-9) + 1) / fps


def _positive_interval(t_nodes: np.ndarray, t: np.ndarray) -> np.ndarray:
    """For each time in ``t``, the node i that starts its interval [t_i, t_i+1] of positive length
    (clamped to the first and last such interval outside the nodes' span)."""
    intervals = np.flatnonzero(t_nodes[1:] - t_nodes[:-1] > 0)      # (np.diff's numbers)
    k = np.searchsorted(t_nodes[intervals], t, side="right") - 1
    return intervals[np.clip(k, 0, len(intervals) - 1)]


def hermite(t_nodes, values, rates, t, interval=None) -> np.ndarray:
    """Cubic Hermite interpolation of ``values`` with derivatives ``rates`` (both (m,) or (m, c),
    at the nodes ``t_nodes`` (m,), non-decreasing) at the times ``t`` (n,): (n,) or (n, c).
    ``interval`` (n,), if given, names the node that starts each sample's interval."""
    t_nodes, t = np.asarray(t_nodes, float), np.asarray(t, float)
    values, rates = np.asarray(values, float), np.asarray(rates, float)
    i = _positive_interval(t_nodes, t) if interval is None else interval
    j = i + 1
    start = t_nodes[i]
    h = t_nodes[j] - start
    s = (t - start) / h
    if values.ndim == 2:
        s, h = s[:, None], h[:, None]
    return hermite_sum(s, h, values[i], rates[i], values[j], rates[j])


def hermite_sum(s, h, value0, rate0, value1, rate1):
    """The cubic Hermite interpolant at the fraction ``s`` of an interval of length ``h`` between
    (``value0``, ``rate0``) and (``value1``, ``rate1``): numpy arrays, or CasADi symbols (the
    body's compiled swing legs interpolate with this)."""
    # (the factors used twice computed once: the same numbers)
    rest, squared = (1 - s) ** 2, s * s
    h00, h10 = (1 + 2 * s) * rest, s * rest
    h01, h11 = squared * (3 - 2 * s), squared * (s - 1)
    return h00 * value0 + h10 * h * rate0 + h01 * value1 + h11 * h * rate1


def gradient(f: np.ndarray, x: np.ndarray) -> np.ndarray:
    """np.gradient(f, x) of 1-D float arrays (two points or more), its operations in its order:
    central differences weighted by the spacings inside (plain ones where the spacing is
    uniform), one-sided at the ends. numpy's general form took 50 us a call (dynamics.csv's
    rates: three a step; the body's swing1 knee: one a step)."""
    dx = x[1:] - x[:-1]         # np.diff's numbers, without its wrapper
    out = np.empty(len(f))
    if (dx == dx[0]).all():
        out[1:-1] = (f[2:] - f[:-2]) / (2. * dx[0])
    else:
        dx1, dx2 = dx[:-1], dx[1:]
        a = -(dx2) / (dx1 * (dx1 + dx2))
        b = (dx2 - dx1) / (dx1 * dx2)
        c = dx1 / (dx2 * (dx1 + dx2))
        out[1:-1] = a * f[:-2] + b * f[1:-1] + c * f[2:]
    out[0] = (f[1] - f[0]) / dx[0]
    out[-1] = (f[-1] - f[-2]) / dx[-1]
    return out


def spline_rates(t_nodes, values) -> np.ndarray:
    """Rates at the nodes for a C1 Hermite spline through ``values`` (m,): second-order finite
    differences (np.gradient) over the distinct node times; a repeated node takes the rate of
    the first node at its time (the value is the same there: nothing jumps)."""
    t_nodes, values = np.asarray(t_nodes, float), np.asarray(values, float)
    distinct = np.empty(len(t_nodes), bool)
    distinct[0], distinct[1:] = True, t_nodes[1:] > t_nodes[:-1]     # (np.diff(t_nodes) > 0)
    if np.count_nonzero(distinct) < 2:
        return np.zeros_like(values)
    rates = gradient(values[distinct], t_nodes[distinct])
    return rates[np.cumsum(distinct) - 1]


def locate_steps(steps, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(step index, step-local time τ) of each walk time ``t``: a heel strike's instant belongs to
    the step it opens, the walk's last instant to the last step (τ = its t_step)."""
    starts = np.array([s.t_start for s in steps])
    k = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(steps) - 1)
    return k, t - starts[k]


@dataclass(frozen=True)
class StepCurves:
    """Curves given per step at step-local node times, evaluated at samples of any steps in one
    call. The nodes live on the step coordinate u = k + τ/t_step_k, which grows through the walk
    (one step's last node and the next one's first share u = k + 1, and the later one wins, as a
    heel strike's instant belongs to the step it opens), so one Hermite pass serves every step."""
    t_step: np.ndarray   # (steps,) s
    u: np.ndarray        # (m,) node step coordinates
    values: np.ndarray   # (m, c)
    rates: np.ndarray    # (m, c), per unit of u
    first: np.ndarray    # (steps,) the node starting each step's first interval of positive length
    last: np.ndarray     # (steps,) ... and its last one

    @classmethod
    def of(cls, t_step, pieces) -> "StepCurves":
        """``pieces``: (step index, node times τ (m,), values (m, c), rates (m, c) per second), in
        walk order."""
        t_step = np.asarray(t_step, float)
        node_step = np.repeat([k for k, *_ in pieces], [len(tau) for _, tau, _, _ in pieces])
        # (the pieces' nodes at once: each node's own step, as piece by piece)
        u = node_step + np.concatenate([tau for _, tau, _, _ in pieces]).astype(float) / t_step[node_step]
        # (np.concatenate: np.vstack's numbers for these (m, c) pieces, without its wrapper)
        rates = np.concatenate([r for *_, r in pieces]).astype(float) * t_step[node_step][:, None]
        own = np.flatnonzero((u[1:] - u[:-1] > 0) & (node_step[1:] == node_step[:-1]))   # (np.diff's numbers)
        first, last = np.zeros(len(t_step), int), np.zeros(len(t_step), int)
        first[node_step[own][::-1]] = own[::-1]       # of repeated indices the last assignment wins
        last[node_step[own]] = own
        return cls(t_step, u, np.concatenate([v for _, _, v, _ in pieces]).astype(float), rates, first, last)

    def __call__(self, step: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """The curves at samples of steps ``step`` (n,) and local times ``tau`` (n,): (n, c)."""
        return hermite(self.u, self.values, self.rates, *self.locate(step, tau))

    def locate(self, step: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The samples' step coordinates u (n,) and the node that starts each one's interval (n,).

        Each sample is interpolated on its own step's nodes: at a heel strike's instant u = k + 1
        is also the next step's first node, and a sample of step k a round-off before it (τ one
        ulp short of t_step) can round to that u, where the next step's curve (another stance
        origin, the other leg) would be taken."""
        u = step + tau / self.t_step[step]
        intervals, interval_starts = self._intervals
        k = np.searchsorted(interval_starts, u, side="right") - 1
        k = intervals[np.minimum(np.maximum(k, 0), len(intervals) - 1)]     # _positive_interval's
        return u, np.minimum(np.maximum(k, self.first[step]), self.last[step])

    @cached_property
    def _intervals(self) -> tuple[np.ndarray, np.ndarray]:
        """The nodes that start an interval of positive length, and their u (every call reads them)."""
        intervals = np.flatnonzero(self.u[1:] - self.u[:-1] > 0)      # (np.diff's numbers)
        return intervals, self.u[intervals]


def stance_curves(walk) -> StepCurves:
    """w, θ1, θ2 of every step's simulated stance."""
    t_step = [s.plan.timings.t_step for s in walk.steps]
    pieces = [(k, sub.t, sub.states[:, :3], sub.states[:, 3:6])
              for k, sub in enumerate(s.subphase("stance") for s in walk.steps)]
    return StepCurves.of(t_step, pieces)


def stance_at(walk, curves: StepCurves, step: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The simulated stance at samples (step (n,), τ (n,)): the hip (n, 2), world x and height,
    hip = ankle + w (sin θ1, cos θ1) with the step's ankle at (origin_x, l9), and the upper body's
    lean θ2 (n,)."""
    w, theta1, theta2 = curves(step, tau).T
    origin_x = np.array([s.origin_x for s in walk.steps])[step]
    hip = np.empty((len(w), 2))
    hip[:, 0], hip[:, 1] = origin_x + w * np.sin(theta1), walk.spec.body.l9 + w * np.cos(theta1)
    return hip, theta2


def swung_steps(walk) -> list:
    """The walk's steps whose swings are solved: every one, but a last one that is only its stance
    half (a :class:`~klaw_ocp.control.step.StanceStage`, which the live playground's frames of the
    step before read for its stance foot: docs/serve.md)."""
    steps = walk.steps
    return steps if steps[-1].has_swings else steps[:-1]


def swing_curves(walk) -> StepCurves:
    """θ3, θ4 of every step's swing leg from toe-off to heel strike (:func:`swung_steps`): swing1
    (θ4 kinematic: the rates of a C1 spline), swing2 (θ4 with θ̇4), swing3 (the knee locked:
    θ4 = 0). Swing2's first node repeats swing1's last: the later one wins, as it does between any
    two subphases."""
    swung = swung_steps(walk)
    t_step = [s.plan.timings.t_step for s in swung]
    return StepCurves.of(t_step, [(k, *piece) for k, step in enumerate(swung) for piece in _swing_pieces(step)])


#: each solved step's swing pieces (:func:`_swing_pieces`) by the step's id (with a weak reference
#: to the step, which the pieces' arrays do not hold), dropped when the step is:
#: the body's frames of a step read its swing and its neighbours' (the playground's windows: each
#: step's swing curves three times), and a step's pieces cost 0.05-0.08 ms to make
_SWING_PIECES: dict = {}


def _swing_pieces(step) -> tuple:
    """A solved step's swing nodes, subphase by subphase: (node times τ, θ3 θ4 (m, 2), their rates
    (m, 2) per second). Made once a step (a step's solution never changes)."""
    key = id(step)
    pieces = _SWING_PIECES.get(key)
    if pieces is None or pieces[0]() is not step:
        swing1, swing2, swing3 = (step.subphase(name) for name in ("swing1", "swing2", "swing3"))
        x, rates1 = swing1.states, np.empty((len(swing1.t), 2))
        rates1[:, 0], rates1[:, 1] = x[:, 8], spline_rates(swing1.t, x[:, 7])
        x2, x3 = swing2.states, swing3.states                 # swing3's states: [stance(6), θ3, θ̇3]
        values3, rates3 = np.zeros((len(swing3.t), 2)), np.zeros((len(swing3.t), 2))
        values3[:, 0], rates3[:, 0] = x3[:, 6], x3[:, 7]
        pieces = (weakref.ref(step), ((swing1.t, x[:, 6:8], rates1), (swing2.t, x2[:, 6:8], x2[:, 8:10]),
                         (swing3.t, values3, rates3)))
        _SWING_PIECES[key] = pieces
        weakref.finalize(step, _SWING_PIECES.pop, key, None)
    return pieces[1]
