"""What a subphase boundary-value problem is, independent of how it is solved (section 4.1).

    A(q) qdd = B(q, qd, F(t, x; u)),   x(t0) = x0,   g(x(t_end)) = 0,   h(x(t), t) >= lower(t)

    and, when the problem is posed as an optimal control problem, min  sum_k |r(x_k, t_k, u)|^2 / (N+1)

A :class:`SubphaseSpec` is the symbolic structure, built once per process by ``klaw_ocp.control``:
the closed-loop right-hand side ``rhs(x, t, u, c)``, the final conditions ``final(x_end, c)``, optional
path functions ``path(x, t, u, c) >= lower``, an optional least-squares running cost and the forces to report. ``u`` are the few free
parameters of the paper's torque shapes; ``c`` is a numeric context (body, gains, targets) that
each step fills in, so one compiled Function serves every step.

A :class:`SubphaseProblem` is one numeric instance: initial state, time grid, context, guess.
A :class:`SubphaseSolution` is what every solver returns, converged or not (scipy-style: a failed
solve comes back with ``success = False`` and a message, it does not raise midway).
"""
from __future__ import annotations

import math

from dataclasses import dataclass, field, fields
from typing import Callable, Optional, Sequence

import casadi as ca
import numpy as np

from ..casadi_builds import built_once


@dataclass(frozen=True)
class Event:
    """A state event for forward integration (plain shooting): ``fn(x, t, u, c)`` crossing zero.

    ``direction`` +1 fires on an upward crossing, -1 downward. ``guard(x, t, c_dict, mode)`` says
    whether the event is armed; ``apply(x, c, mode) -> (x, c, mode)`` is the switch (a lock map).
    ``rate(states) -> dg/dt`` at (M, nx) states, when the state holds it (the rate of a position
    is a velocity of the state): with it a crossing that goes and comes back inside one interval
    is found too (:mod:`.events`).
    """
    name: str
    fn: ca.Function
    direction: int
    guard: Callable
    apply: Callable
    rate: Optional[Callable] = None


@dataclass(frozen=True)
class SubphaseSpec:
    """Symbolic structure of one subphase (built once; see module docstring).

    Dimensions: nx states, nu free parameters, nc context entries, nf final conditions (= nu for
    a square problem), nh path functions.
    """
    name: str
    state_names: tuple
    unknown_names: tuple
    context_names: tuple
    rhs: ca.Function                 # (x[nx], t, u[nu], c[nc]) -> xdot[nx]
    final: ca.Function               # (x[nx], c[nc]) -> g[nf]
    outputs: ca.Function             # (x, t, u, c) -> reported forces [no]
    output_names: tuple
    path: Optional[ca.Function] = None   # (x, t, u, c) -> h[nh] >= lower
    path_names: tuple = ()
    residuals: Optional[ca.Function] = None   # (x, t, u, c) -> r; running cost |r|^2 (optimised formulations)
    events: tuple = ()
    #: whether the path constraints hold at the nodes what the events enforce between them (the
    #: stance's lock rule): then plain shooting may take the smooth problem's root where the
    #: evented one has none (:data:`.plain_shooting.EVENT_FREE_ROOT`)
    path_holds_events: bool = False
    #: pairs (unknown index, final-condition index) for the paper's one-unknown-at-a-time shooting
    pairing: tuple = ()
    #: (x, c) -> margins, all >= 0 on a physically meaningful state: a trajectory that leaves them
    #: is not a solution, whatever its residual (Newton can converge to a leg metres long)
    plausible: Optional[ca.Function] = None
    #: the subphase its solutions are named after, where it is one of two forms of a subphase (a
    #: closing step's swing2): None, its own name (which names its compiled kernels)
    subphase: Optional[str] = None

    @property
    def solution_name(self) -> str:
        return self.subphase or self.name

    def __hash__(self) -> int:
        # the dataclass's hash of every field, computed once: the solvers look their kernels and
        # Newton state up by spec about 300 times a walk, and each CasADi Function's hash crosses
        # SWIG (22 us a spec)
        cached = self.__dict__.get("_hash")
        if cached is None:
            cached = hash(tuple(getattr(self, f.name) for f in fields(self) if f.compare))
            object.__setattr__(self, "_hash", cached)
        return cached

    def __getstate__(self) -> dict:
        # a Function's hash is its address: another process computes its own
        return {k: v for k, v in self.__dict__.items() if k != "_hash"}

    @property
    def nx(self) -> int:
        return len(self.state_names)

    @property
    def nu(self) -> int:
        return len(self.unknown_names)

    @property
    def nc(self) -> int:
        return len(self.context_names)


@dataclass
class SubphaseProblem:
    """One numeric instance of a :class:`SubphaseSpec`.

    ``grid`` holds the N+1 node times (breakpoints of the torque shapes must be nodes).
    ``guess`` the initial free parameters; ``scale`` their typical size (for brackets and
    tolerances). ``fixed`` marks unknowns held at their guess unless the solver needs them to
    satisfy path constraints (the swing2 recovery actuator). ``path_lower`` are lower bounds of
    the path functions (e.g. the toe clearance); ``None`` means no inequality is enforced. It may
    also be a callable ``(t, states, context) -> (N+1, nh)``, for inequalities whose nodes depend
    on the motion (the stance lock rule). ``optimize``: solve as the optimal control problem with
    the spec's residuals and every unknown free, even when the square solution is feasible.
    ``mode``: the event mode forward integration starts in (plain shooting; multiple shooting has
    no events): a swing re-simulates the stance from the lock state the stance is in at its start,
    with ``context`` agreeing (its ``locked`` entry; control/stance_spec.py, ``lock_mode``).
    ``scan``: where everything else fails, a solver that can (``scans``) may search the unknowns'
    space about the guess (multiple shooting's ``scan``): the caller's last resort, after its own
    continuations.
    """
    spec: SubphaseSpec
    x0: np.ndarray
    grid: np.ndarray
    context: np.ndarray
    guess: np.ndarray
    scale: np.ndarray
    fixed: Sequence[bool] = ()
    path_lower: object = None                    # (nh,), (N+1, nh) or callable; -inf disables a node
    recovery_step: Optional[np.ndarray] = None   # signed increments of fixed unknowns (plain shooting)
    state_guess: Optional[np.ndarray] = None     # (N+1, nx) warm start for multiple shooting
    #: the previous step's solution of this subphase: multiple shooting's IPOPT (a repair, an
    #: optimisation) starts from its nodes, unknowns and multipliers when it solved the same
    #: problem (:class:`IpoptPoint`)
    previous_solution: Optional["SubphaseSolution"] = None
    optimize: bool = False
    mode: dict = field(default_factory=dict)
    scan: bool = False

    def __post_init__(self):
        self.x0 = np.asarray(self.x0, float).ravel()
        self.grid = np.asarray(self.grid, float).ravel()
        self.context = np.asarray(self.context, float).ravel()
        self.guess = np.asarray(self.guess, float).ravel()
        self.scale = np.asarray(self.scale, float).ravel()
        if not self.fixed:
            self.fixed = tuple(False for _ in range(self.spec.nu))
        if self.path_lower is not None and not callable(self.path_lower):
            lower = np.asarray(self.path_lower, float)
            self.path_lower = np.full((self.grid.size, lower.shape[-1]), lower)
        #: the intervals' lengths (N,), which every simulation of the problem asks for
        self.h = self.grid[1:] - self.grid[:-1]     # np.diff's numbers, without its wrapper
        if (self.h <= 0).any():
            raise ValueError(f"{self.spec.name}: time grid must increase strictly")


@dataclass(frozen=True)
class IpoptPoint:
    """IPOPT's multipliers at a solution (of the constraints, of the unknowns) and the numbers
    ``problem`` that define the problem it solved (the NLP's parameters: x0, grid, context, nominal
    unknowns, scales, weights; its numeric path bounds)."""
    lam_g: np.ndarray
    lam_x: np.ndarray
    problem: np.ndarray

    def repeated_by(self, problem: np.ndarray, tolerance: float) -> bool:
        """Whether ``problem`` is this one's to ``tolerance`` (relative, absolute near 0)."""
        mine = self.problem
        return mine.shape == problem.shape and bool(np.all(np.abs(problem - mine) <= tolerance * (1.0 + np.abs(mine))))


@dataclass
class SubphaseSolution:
    """The result of any solver for one subphase.

    ``parameters`` maps unknown names to values; ``t`` (N+1) and ``states`` (N+1, nx) sample the
    trajectory; ``forces`` (N+1, no) the reported forces; ``residual`` is the maximum absolute
    final-condition error; ``path_min`` the smallest path-function margin (>= 0 when satisfied).
    """
    name: str
    method: str
    parameters: dict
    t: np.ndarray
    states: np.ndarray
    forces: np.ndarray
    residual: float
    iterations: int
    success: bool
    wall_s: float
    message: str = ""
    path_min: float = float("inf")
    events: list = field(default_factory=list)
    #: which algorithm produced it: "rootfinder", "ipopt" or "bisection-secant"
    nlp: str = ""
    #: the fallbacks this solve needed beyond the mode's plain method, in order (docs/solvers.md):
    #: "bracket", "single-shooting-root", "homotopy", "scan", "ipopt-repair" (multiple shooting);
    #: "swapped-pairing", "broyden", "event-free-start", "homotopy", "recovery-loop" (plain shooting);
    #: the controller's "curve-p-continuation", "closing-restart" and "closing-longer-curve-p" (both)
    #: first where it took them
    fallbacks: list = field(default_factory=list)
    #: one-off CasADi build time (s) spent in this call, not counted in ``wall_s``
    build_s: float = 0.0
    #: IPOPT's multipliers at the solution and the problem they solve, for the next step's IPOPT
    #: to start from; None from every other algorithm
    ipopt: Optional["IpoptPoint"] = None

    @property
    def status(self) -> str:
        return "ok" if self.success else "failed"

    @property
    def final_state(self) -> np.ndarray:
        return self.states[-1]


def time_grid(t0: float, t1: float, n: int, breakpoints: Sequence[float] = (),
              lead: Sequence[float] = ()) -> np.ndarray:
    """N+1 nodes from t0 to t1 with every breakpoint inside (t0, t1) on a node.

    The nodes are distributed over the segments in proportion to their length (at least one
    interval each), so the number of intervals, and hence the compiled solver, never changes.
    ``lead``: fractions of t1 - t0, increasing in (0, 1), of extra nodes at the start, one interval
    each (a grid dense where the motion changes fast, such as right after an impact); the other
    n - len(lead) intervals span the rest as above, a little longer. The breakpoints must lie
    after the last of them. Without ``lead`` the grid is the one it always was, bit for bit.
    """
    if lead:
        return _led_grid(t0, t1, n, breakpoints, lead)
    cuts = sorted(b for b in breakpoints if t0 + 1e-9 < b < t1 - 1e-9)
    edges = [t0, *cuts, t1]
    # Python floats and ints, not numpy arrays of four: the solvers ask for ~90 grids a walk and
    # numpy's fixed costs were most of each (the same operations in the same order)
    lengths = [b - a for a, b in zip(edges[:-1], edges[1:])]
    if n < len(lengths):
        raise ValueError(f"need at least {len(lengths)} intervals for {len(cuts)} breakpoints, got {n}")
    counts = [max(1, math.floor(length / (t1 - t0) * n)) for length in lengths]
    segments = range(len(lengths))
    while sum(counts) < n:
        counts[max(segments, key=lambda i: lengths[i] / counts[i])] += 1      # the first largest
    while sum(counts) > n:
        counts[min((i for i in segments if counts[i] > 1), key=lambda i: lengths[i] / counts[i])] -= 1
    # each segment's np.linspace(a, b, k + 1)[1:] as linspace computes it: the node
    # j * ((b - a) / k) + a, and b itself at the segment's end; in Python floats (the same IEEE
    # operations), since numpy's per-call costs were most of a grid of twenty nodes
    nodes = [t0]
    for a, b, k in zip(edges[:-1], edges[1:], counts):
        step = (b - a) / k
        nodes.extend([j * step + a for j in range(1, k)])
        nodes.append(b)
    return np.array(nodes)


def _led_grid(t0: float, t1: float, n: int, breakpoints: Sequence[float], lead: Sequence[float]) -> np.ndarray:
    """:func:`time_grid` with ``lead`` nodes at its start."""
    fractions = list(lead)
    if not all(a < b for a, b in zip([0.0, *fractions], [*fractions, 1.0])):
        raise ValueError(f"lead fractions must increase strictly inside (0, 1), got {fractions}")
    starts = [t0 + f * (t1 - t0) for f in fractions]
    # a breakpoint among the lead nodes would not be a node of the grid
    early = [b for b in breakpoints if t0 + 1e-9 < b <= starts[-1] + 1e-9]
    if early:
        raise ValueError(f"breakpoints {early} fall among the lead nodes, which end at {starts[-1]}")
    if n <= len(fractions):
        raise ValueError(f"need more than {len(fractions)} intervals for {len(fractions)} lead nodes, got {n}")
    return np.concatenate([[t0, *starts[:-1]], time_grid(starts[-1], t1, n - len(fractions), breakpoints)])


@built_once
def mapped(fn: ca.Function, n: int) -> ca.Function:
    """``fn`` evaluated on n columns in one call (vector inputs given once are broadcast)."""
    return fn.map(n)


def fd_jacobian(residual, u: np.ndarray, res: np.ndarray, columns, scale: np.ndarray) -> np.ndarray:
    """Forward differences of ``residual`` (parameters -> an array like ``res``, its value at
    ``u``) by the parameters ``columns``, each stepped by 1e-4 of its typical size ``scale[i]``
    (1e-6 where that is 0): the single-shooting Jacobians both solver modes start from."""
    jac = np.empty((np.size(res), len(columns)))
    for col, i in enumerate(columns):
        du = 1e-4 * abs(scale[i]) or 1e-6
        trial = u.copy(); trial[i] += du
        jac[:, col] = (residual(trial) - res) / du
    return jac


def path_bounds(pb: SubphaseProblem, times: np.ndarray, states: np.ndarray) -> Optional[np.ndarray]:
    """Lower bounds of the path functions at the samples ``times`` (None: no inequality).

    A callable ``path_lower`` is evaluated on the trajectory itself; fixed bounds of samples off
    the grid (event nodes of plain shooting) are those of the node before them.
    """
    if pb.spec.path is None or pb.path_lower is None:
        return None
    if callable(pb.path_lower):
        return np.asarray(pb.path_lower(np.asarray(times), np.asarray(states), pb.context), float)
    if times is pb.grid:      # the grid's own nodes (multiple shooting): the bounds as they are
        return pb.path_lower
    node = np.clip(np.searchsorted(pb.grid, times, side="right") - 1, 0, pb.grid.size - 1)
    return pb.path_lower[node]
