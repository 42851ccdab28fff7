"""The multiple-shooting NLP for IPOPT, with compiled derivative functions.

    min_z  |r(z)|^2    s.t.   X_{k+1} - Phi(X_k, u) = 0,   g(X_N) = 0,   h(X_k, t_k, u) >= lower_k

``z = [X_1..X_N, u]`` (every unknown free), ``p = [x0, t_0..t_N, c, u_nominal, u_scale, weights]``.
The residuals r are the deviations of the unknowns from their nominal values (``weights`` 1 for
the unknowns the square problem holds fixed, so that a repair changes them as little as it can,
and 1e-4 for all, so that the problem is never singular) and, for an optimised formulation, the
spec's running residuals over the nodes divided by sqrt(N+1).

IPOPT gets four functions, built here in MX around the per-interval RK4 of
:func:`.integrator.rk4_interval` mapped over the grid (the block structure of multiple shooting;
one Jacobian of the whole transcription in SX, as before, took 6 s and 740 MB to build), and
compiled with the solver kernels (:mod:`klaw_ocp.kernels`): ``nlp`` (f, g), ``grad_f``, ``jac_g`` and a
Gauss-Newton ``hess_lag`` = 2 lam_f J_r^T J_r. The Gauss-Newton Hessian is exact for the
objective's curvature when r is linear in z (the repairs) and drops the constraints' curvature,
whose second derivatives through 80 RK4 stages cost 80 ms an evaluation and buy few iterations
near a small-residual optimum.
"""
from __future__ import annotations

import sys

import casadi as ca
import numpy as np

from ..casadi_builds import built_once
from . import integrator
from .integrator import rk4_interval
from ..kernels import KernelLibrary, source_key
from .problem import SubphaseSpec

NAMES = ("nlp", "grad_f", "jac_g", "hess_lag")
#: IPOPT's barrier parameter when it starts from the previous pass's solution and multipliers: a
#: solution is already near the central path's end, and the default 0.1 first walks back from it
#: (a 1 km/h stance's repair: 38 iterations, 24 with this; the solutions differ by 2e-14)
WARM_MU_INIT = 1e-6


def _sparse_from_blocks(blocks: list, n_rows: int, n_cols: int) -> ca.MX:
    """A sparse MX matrix from dense blocks ``(rows, cols, value)``: ``value`` is a
    (len(rows), len(cols)) MX or DM placed at those row and column indices (blocks do not overlap).
    The nonzeros are gathered once, in CasADi's compressed-column order."""
    rows, cols, pieces = [], [], []
    for r, c, value in blocks:
        rr, cc = np.meshgrid(r, c, indexing="ij")
        rows.append(rr.ravel(order="F"))          # column-major, as ca.vec orders the value
        cols.append(cc.ravel(order="F"))
        pieces.append(ca.vec(value))
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    order = np.lexsort((rows, cols))
    colind = np.concatenate([[0], np.cumsum(np.bincount(cols, minlength=n_cols))])
    nonzeros = ca.vertcat(*pieces)[order.tolist()]
    return ca.MX(ca.Sparsity(n_rows, n_cols, colind.tolist(), rows[order].tolist()), nonzeros)


def _constraint_jacobian(spec, n, A_B, G, path_x, path_u, n_rows, n_z) -> ca.MX:
    """d g / d z assembled from the per-interval Jacobians (the block structure of multiple
    shooting) instead of CasADi's AD of the whole transcription (2 ms an evaluation here).
    Rows: the defects X_{k+1} - Phi(X_k, u), the final conditions, then each path function at
    nodes 0..N; columns: X_1..X_N, u."""
    nx, nu, nf = spec.nx, spec.nu, G.size1()
    u_cols = np.arange(n * nx, n * nx + nu)
    node_cols = lambda k: np.arange((k - 1) * nx, k * nx)     # the columns of X_k, k >= 1
    blocks = []
    for k in range(n):
        rows_k = np.arange(k * nx, (k + 1) * nx)
        jac_k = A_B[:, k * (nx + nu):(k + 1) * (nx + nu)]
        blocks.append((rows_k, node_cols(k + 1), ca.DM.eye(nx)))
        if k > 0:                                              # X_0 = x0 is a parameter
            blocks.append((rows_k, node_cols(k), -jac_k[:, :nx]))
        blocks.append((rows_k, u_cols, -jac_k[:, nx:]))
    blocks.append((np.arange(n * nx, n * nx + nf), node_cols(n), G))
    for i in range(path_x.size1() if path_x is not None else 0):
        first = n * nx + nf + i * (n + 1)
        for k in range(1, n + 1):
            blocks.append((np.array([first + k]), node_cols(k), path_x[i, k * nx:(k + 1) * nx]))
        blocks.append((first + np.arange(n + 1), u_cols, ca.reshape(path_u[i, :], nu, n + 1).T))
    return _sparse_from_blocks(blocks, n_rows, n_z)


def _build(spec: SubphaseSpec, n: int, substeps: int, compiling: bool) -> list:
    nx, nu = spec.nx, spec.nu
    step, sens = rk4_interval(spec, substeps, False), rk4_interval(spec, substeps, True)
    if not compiling:
        step, sens = step.expand(), sens.expand()
    z = ca.MX.sym("z", n * nx + nu)
    x0, tn, c = ca.MX.sym("x0", nx), ca.MX.sym("t", n + 1), ca.MX.sym("c", spec.nc)
    u_nominal, u_scale, weights = (ca.MX.sym(s, nu) for s in ("u_nominal", "u_scale", "w"))
    p = ca.vertcat(x0, tn, c, u_nominal, u_scale, weights)
    states = ca.reshape(z[: n * nx], nx, n)
    u = z[n * nx:]
    previous = ca.horzcat(x0, states[:, : n - 1])
    grid = (previous, tn[:n].T, (tn[1:] - tn[:n]).T, ca.repmat(u, 1, n), ca.repmat(c, 1, n))
    propagated = step.map(n)(*grid)
    g = [ca.vec(states - propagated), spec.final(states[:, n - 1], c)]
    all_states = ca.horzcat(x0, states)
    node_args = (all_states, tn.T, ca.repmat(u, 1, n + 1), ca.repmat(c, 1, n + 1))
    nodes = lambda fn: fn.map(n + 1)(*node_args)
    xs, ts, us, cs = ca.SX.sym("x", nx), ca.SX.sym("t"), ca.SX.sym("u", nu), ca.SX.sym("c", spec.nc)
    final_jac = ca.Function("final_jac", [xs, cs], [ca.densify(ca.jacobian(spec.final(xs, cs), xs))])
    path_x = path_u = None
    if spec.path is not None:
        g.append(ca.vec(nodes(spec.path).T))
        h = spec.path(xs, ts, us, cs)
        path_jac = ca.Function("path_jac", [xs, ts, us, cs], [ca.densify(ca.jacobian(h, xs)), ca.densify(ca.jacobian(h, us))])
        path_x, path_u = path_jac.map(n + 1)(*node_args)
    g = ca.vertcat(*g)
    _, a_b = sens.map(n)(*grid)
    jac_g = _constraint_jacobian(spec, n, a_b, final_jac(states[:, n - 1], c), path_x, path_u, g.numel(), z.numel())
    deviation = (u - u_nominal) / u_scale
    r = [weights * deviation, 1e-4 * deviation]
    if spec.residuals is not None:
        r.append(ca.vec(nodes(spec.residuals)) / np.sqrt(n + 1))
    r = ca.vertcat(*r)
    f = ca.sumsqr(r)
    jac_r = ca.jacobian(r, z)
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", g.numel())
    pre = f"{spec.name}_{n}_"
    return [ca.Function(pre + "nlp", [z, p], [f, g], ["x", "p"], ["f", "g"]),
            ca.Function(pre + "grad_f", [z, p], [f, ca.densify(2 * ca.mtimes(jac_r.T, r))], ["x", "p"], ["f", "grad_f_x"]),
            ca.Function(pre + "jac_g", [z, p], [g, jac_g], ["x", "p"], ["g", "jac_g_x"]),
            ca.Function(pre + "hess_lag", [z, p, lam_f, lam_g], [ca.triu(2 * lam_f * ca.mtimes(jac_r.T, jac_r))],
                        ["x", "p", "lam_f", "lam_g"], ["hess_gamma_x_x"])]


@built_once
def ipopt_solver(spec: SubphaseSpec, intervals: int, substeps: int, tol: float, max_iter: int,
                 warm: bool = False) -> ca.Function:
    """IPOPT on the subphase's multiple-shooting NLP (built or loaded once per process); ``warm``:
    the one that starts from a solution and its multipliers (the repair's later passes, whose
    active path constraints changed a little), with a small barrier parameter."""
    parts = [source_key(sys.modules[__name__], integrator), "ipopt", spec.name, spec.nx, spec.nu, spec.nc, substeps, intervals]
    for fn in (spec.rhs, spec.final, spec.path, spec.residuals):
        parts.append(fn.serialize() if fn is not None else "-")
    pre = f"{spec.name}_{intervals}_"
    library = KernelLibrary(parts, [pre + n for n in NAMES], lambda compiling: _build(spec, intervals, substeps, compiling))
    nlp, grad_f, jac_g, hess_lag = (library.casadi_external(pre + n) for n in NAMES)
    opts = {"ipopt.tol": tol, "ipopt.constr_viol_tol": tol, "ipopt.max_iter": max_iter * 10,
            "ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "error_on_fail": False,
            "show_eval_warnings": False, "calc_lam_p": False, "no_nlp_grad": True,
            "grad_f": grad_f, "jac_g": jac_g, "hess_lag": hess_lag}
    if warm:
        opts.update({"ipopt.warm_start_init_point": "yes", "ipopt.mu_init": WARM_MU_INIT,
                     "ipopt.warm_start_bound_push": 1e-9, "ipopt.warm_start_mult_bound_push": 1e-9,
                     "ipopt.warm_start_slack_bound_push": 1e-9})
    return ca.nlpsol(f"{spec.name}_ms_ipopt", "ipopt", nlp, opts)
