"""The fixed-step integrator shared by both solver modes.

Both modes integrate with the same explicit Runge-Kutta 4 scheme (``substeps`` RK4 steps per
interval), so where they solve the same square problem they find the same torque parameters to
solver tolerance: the comparison then measures the solvers, not two discretisations. The
interval Function takes its start time and length as inputs, so one Function serves every grid,
and a partial interval (an event inside it) is the same call with a shorter ``h``.

:class:`SubphaseKernels` are the interval and what the solvers need around it, compiled once per
machine (:mod:`klaw_ocp.kernels`, docs/performance.md).
"""
from __future__ import annotations

import sys

import casadi as ca
import numpy as np

from ..casadi_builds import built_once
from ..kernels import KernelLibrary, prefetch, source_key
from .problem import SubphaseSpec, mapped


class SubphaseKernels:
    """The compiled numeric core of one subphase on a grid of ``intervals`` intervals.

    Each kernel is a flat-array callable (:mod:`klaw_ocp.kernels`); matrices come back column-major, so
    an (nx, N) output reshapes to (N, nx). Built once per (spec, substeps, intervals):

    - ``sim(x0, t[N], h[N], u, c) -> X[nx, N]``: the states at nodes 1..N, one forward shot;
    - ``prop(X[nx, N], t, h, u, c) -> Xf[nx, N]``: each interval from its own start state;
    - ``sens(X, t, h, u, c) -> Xf, J[nx, (nx + nu) N]``: the same with each interval's Jacobian
      d xf / d(x, u), the blocks of multiple shooting's Jacobian (forward AD of the RK4 interval);
    - ``step(x, t, h, u, c) -> xf``: one interval of any length (events, partial intervals);
    - ``final(x, c) -> g, G``: the final conditions and their Jacobian;
    - ``nodes(X[nx, N+1], t[N+1], u, c) -> forces, path, plausible, events``: what is reported
      and checked at the nodes (empty outputs for functions the spec does not have);
    - ``events(x, t, u, c) -> values``: the event functions at one state.
    """

    NAMES = ("sim", "prop", "sens", "step", "final", "nodes", "events")

    def __init__(self, spec: SubphaseSpec, substeps: int, intervals: int):
        self.spec, self.substeps, self.intervals = spec, int(substeps), int(intervals)
        parts = [source_key(sys.modules[__name__]), spec.name, spec.nx, spec.nu, spec.nc, self.substeps, self.intervals]
        for fn in (spec.rhs, spec.final, spec.outputs, spec.path, spec.plausible, *(e.fn for e in spec.events)):
            parts.append(fn.serialize() if fn is not None else "-")
        self.library = KernelLibrary(parts, [f"{spec.name}_{n}" for n in self.NAMES], self._build)
        self._fns = None

    def load(self) -> None:
        """Compile or load the kernels now (the first use does it otherwise)."""
        if self._fns is None:
            self._fns = self.library.functions()
            # each kernel an attribute of its own from now on: the solvers ask for them ~650
            # times a walk, and every lookup through __getattr__ first fails an ordinary one
            for name in self.NAMES:
                setattr(self, name, self._fns[f"{self.spec.name}_{name}"])

    def __getattr__(self, name):
        if name in SubphaseKernels.NAMES:
            self.load()
            return self._fns[f"{self.spec.name}_{name}"]
        raise AttributeError(name)

    def samples(self, states, times, u, c) -> list:
        """forces (M, no), path (M, nh), plausible (M, np) and event values (M, ne) at M samples:
        the ``nodes`` kernel on the grid's nodes; CasADi's maps for a trajectory with event
        samples added (plain shooting's lock events, rare)."""
        states, times, m = np.asarray(states, float), np.asarray(times, float), len(times)
        if m == self.intervals + 1:
            return [v.reshape(m, -1) for v in self.nodes(states, times, u, c)]
        spec, cols = self.spec, (states.T, times[None, :], np.tile(np.reshape(u, (-1, 1)), (1, m)),
                                 np.tile(np.reshape(c, (-1, 1)), (1, m)))
        out = [np.asarray(mapped(spec.outputs, m)(*cols)).T]   # maps cached: built once per length
        out.append(np.asarray(mapped(spec.path, m)(*cols)).T if spec.path is not None else np.zeros((m, 0)))
        out.append(np.asarray(mapped(spec.plausible, m)(cols[0], cols[3])).T if spec.plausible is not None
                   else np.zeros((m, 0)))
        out.append(np.array([self.events(states[k], times[k], u, c)[0] for k in range(m)]).reshape(m, -1))
        return out

    def _build(self, compiling: bool) -> list:
        spec, n = self.spec, self.intervals
        nx, nu, nc = spec.nx, spec.nu, spec.nc
        step, sens = rk4_interval(spec, self.substeps, False), rk4_interval(spec, self.substeps, True)
        if not compiling:   # CasADi's virtual machine is fastest on one flat SX graph per interval
            step, sens = step.expand(), sens.expand()
        mx = lambda name, rows=1, cols=1: ca.MX.sym(name, rows, cols)
        X, T, H, U, C = mx("X", nx, n), mx("t", 1, n), mx("h", 1, n), mx("u", nu), mx("c", nc)
        x0, x, t, h = mx("x0", nx), mx("x", nx), mx("t"), mx("h")
        rep = lambda v, k: ca.repmat(v, 1, k)
        name = lambda kind: f"{spec.name}_{kind}"
        traj = step.mapaccum(f"{spec.name}_accum", n)
        fns = [ca.Function(name("sim"), [x0, T, H, U, C], [traj(x0, T, H, rep(U, n), rep(C, n))]),
               ca.Function(name("prop"), [X, T, H, U, C], [step.map(n)(X, T, H, rep(U, n), rep(C, n))])]
        xf_all, j_all = sens.map(n)(X, T, H, rep(U, n), rep(C, n))
        fns.append(ca.Function(name("sens"), [X, T, H, U, C], [xf_all, j_all]))
        fns.append(ca.Function(name("step"), [x, t, h, U, C], [step(x, t, h, U, C)]))
        xs, cs = ca.SX.sym("x", nx), ca.SX.sym("c", nc)
        g = spec.final(xs, cs)
        fns.append(ca.Function(name("final"), [xs, cs], [g, ca.densify(ca.jacobian(g, xs))]))
        Xn, Tn = mx("X", nx, n + 1), mx("t", 1, n + 1)
        per_node = lambda fn, *args: fn.map(n + 1)(*args) if fn is not None else ca.MX(0, n + 1)
        events = [e.fn(x, t, U, C) for e in spec.events]
        event_fn = ca.Function(name("events"), [x, t, U, C], [ca.vertcat(*events) if events else ca.MX(0, 1)])
        fns.append(ca.Function(name("nodes"), [Xn, Tn, U, C], [
            per_node(spec.outputs, Xn, Tn, rep(U, n + 1), rep(C, n + 1)),
            per_node(spec.path, Xn, Tn, rep(U, n + 1), rep(C, n + 1)),
            per_node(spec.plausible, Xn, rep(C, n + 1)),
            per_node(event_fn if events else None, Xn, Tn, rep(U, n + 1), rep(C, n + 1))]))
        fns.append(event_fn)
        return fns


#: Where in its substep the RK4's last stage evaluates the right-hand side: a billionth of the
#: substep before its end. The torque shapes switch at grid nodes (F_theta1's step at 0.4 t_step
#: is a breakpoint of every grid), and at the node itself ``t < t_off`` depends on round-off
#: (t + h lands a few 1e-17 s either side of t_off on different grids), so the interval before
#: the switch took the switched-off torque for a sixth of its last substep on some grids and not
#: on others: up to 1.4e-2 rad/s at that node, and a swing whose re-simulated stance drifted
#: 9e-3 from the stance it hangs from (tests/test_walk_checks.py). Just before the node the stage
#: sees the interval's own (left) limit on every grid; for smooth right-hand sides the shift is
#: a relative 1e-9 of one stage's time, far below the RK4's own error.
LAST_STAGE = 1 - 1e-9


def rk4_interval(spec: SubphaseSpec, substeps: int, sensitivities: bool) -> ca.Function:
    """The RK4 interval as calls of the right-hand side (compact compiled code); with
    ``sensitivities`` also J = d xf / d(x, u), propagated through the same RK4 stages (the
    variational equations discretised exactly as forward AD of the interval would: same numbers,
    but the generated code holds one Jacobian of the right-hand side instead of one of the whole
    interval, a twentieth of the size)."""
    nx, nu = spec.nx, spec.nu
    xs, ts, us, cs = ca.SX.sym("x", nx), ca.SX.sym("t"), ca.SX.sym("u", nu), ca.SX.sym("c", spec.nc)
    f = spec.rhs(xs, ts, us, cs)
    # with common subexpressions merged (CasADi's "cse": the same operation on the same operands
    # computed once, so the same numbers): the models' pieces (forces, hip height, foot points)
    # each take their own sin and cos of the same angles, 33 trigonometric calls a stance
    # right-hand side and 74 a swing1 one, 9 and 13 after it
    # (the interval needs the right-hand side alone, its sensitivities the Jacobian with it)
    outputs = [f, ca.densify(ca.jacobian(f, ca.vertcat(xs, us)))] if sensitivities else [f]
    rhs = ca.Function(f"{spec.name}_rhs{'_jac' if sensitivities else ''}", [xs, ts, us, cs], outputs, {"cse": True})
    x, t, h = ca.MX.sym("x", nx), ca.MX.sym("t"), ca.MX.sym("h")
    u, c = ca.MX.sym("u", nu), ca.MX.sym("c", spec.nc)
    dt = h / substeps
    seed_u = ca.MX.zeros(nx, nx)
    S = ca.MX.eye(nx + nu)[:nx, :] if sensitivities else None

    def stage(xk, tk, Sk):
        if not sensitivities:
            return rhs(xk, tk, u, c), None
        k, jac = rhs(xk, tk, u, c)
        return k, ca.mtimes(jac[:, :nx], Sk) + ca.horzcat(seed_u, jac[:, nx:])

    xk, tk = x, t
    for _ in range(substeps):
        k1, d1 = stage(xk, tk, S)
        k2, d2 = stage(xk + dt / 2 * k1, tk + dt / 2, S + dt / 2 * d1 if sensitivities else None)
        k3, d3 = stage(xk + dt / 2 * k2, tk + dt / 2, S + dt / 2 * d2 if sensitivities else None)
        k4, d4 = stage(xk + dt * k3, tk + dt * LAST_STAGE, S + dt * d3 if sensitivities else None)
        xk = xk + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if sensitivities:
            S = S + dt / 6 * (d1 + 2 * d2 + 2 * d3 + d4)
        tk = tk + dt
    outputs = [xk, S] if sensitivities else [xk]
    return ca.Function(f"{spec.name}_rk4_{substeps}{'_sens' if sensitivities else ''}", [x, t, h, u, c], outputs)


def prepare_kernels(specs, substeps: int, intervals: int) -> None:
    """Compile or load the kernels of ``specs`` now, in parallel (:func:`.kernels.prefetch`)."""
    prefetch([subphase_kernels(spec, substeps, intervals).load for spec in specs])


@built_once
def subphase_kernels(spec: SubphaseSpec, substeps: int, intervals: int) -> SubphaseKernels:
    """The kernels of a spec on N intervals, built or loaded once per process."""
    return SubphaseKernels(spec, substeps, intervals)
