"""The fixed-step integrator shared by both solver modes.

Both modes integrate with the same explicit Runge-Kutta 4 scheme (``substeps`` RK4 steps per
interval), so where they solve the same square problem they find the same torque parameters to
solver tolerance: the comparison then measures the solvers, not two discretisations. The
interval Function takes its start time and length as inputs, so one Function serves every grid,
and a partial interval (an event inside it) is the same call with a shorter ``h``.
"""
from __future__ import annotations

from functools import lru_cache

import casadi as ca

from .problem import SubphaseSpec


@lru_cache(maxsize=None)
def interval_function(spec: SubphaseSpec, substeps: int) -> ca.Function:
    """``(x, t, h, u, c) -> x(t + h)`` by ``substeps`` RK4 steps; SX, built once per spec."""
    x = ca.SX.sym("x", spec.nx)
    t, h = ca.SX.sym("t"), ca.SX.sym("h")
    u, c = ca.SX.sym("u", spec.nu), ca.SX.sym("c", spec.nc)
    dt = h / substeps
    xk, tk = x, t
    for _ in range(substeps):
        k1 = spec.rhs(xk, tk, u, c)
        k2 = spec.rhs(xk + dt / 2 * k1, tk + dt / 2, u, c)
        k3 = spec.rhs(xk + dt / 2 * k2, tk + dt / 2, u, c)
        k4 = spec.rhs(xk + dt * k3, tk + dt, u, c)
        xk = xk + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        tk = tk + dt
    return ca.Function(f"{spec.name}_rk4_{substeps}", [x, t, h, u, c], [xk], ["x", "t", "h", "u", "c"], ["xf"])


@lru_cache(maxsize=None)
def trajectory_function(spec: SubphaseSpec, substeps: int, intervals: int) -> ca.Function:
    """``(x0, t[N], h[N], u, c) -> X[nx, N]``: the states at nodes 1..N, one call per shot."""
    step = interval_function(spec, substeps)
    return step.mapaccum(f"{spec.name}_traj_{substeps}_{intervals}", intervals, ["x"], ["xf"])
