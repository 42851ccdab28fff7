"""Newton's method on the multiple-shooting equations, by condensing, with chord steps.

The square system of a subphase on N intervals, unknowns the node states X_1..X_N and the free
parameters u (X_0 = x0 is given):

    d_k = X_{k+1} - Phi(X_k, u) = 0   (k = 0..N-1),      g(X_N) - shift = 0.

Its Jacobian is block bidiagonal: identity blocks, -A_k = -dPhi/dX_k below them, and a column of
-B_k = -dPhi/du blocks. Newton's step follows from the linearisation by forward recursion
(condensing, a block elimination of the same linear system, so the same step as a sparse LU of
the whole Jacobian would give):

    dX_k = S_k du + s_k,   S_{k+1} = A_k S_k + B_k,   s_{k+1} = A_k s_k - d_k,   S_0 = s_0 = 0,
    G S_N du = -(g - shift) - G s_N.

Only G S_N, a matrix of the size of u, is solved with. The blocks A_k, B_k come from the compiled
``sens`` kernel (:class:`.integrator.SubphaseKernels`), one call for all intervals. The recursion
for s is linear in the defects, s_{k+1} = -sum_{j<=k} A_k ... A_{j+1} d_j: a linearisation keeps
those transition products as one block lower-triangular matrix, so that each of the many steps
taken with it (chord steps) is a few matrix products, not a Python loop over the intervals (on
grids up to DENSE_TRANSITIONS_MAX node states; finer ones run the recursion).

Chord steps: a solve first checks the residual of its start point (often already converged: it is
the simulation of the previous step's parameters), then steps with the last Jacobian it has,
possibly the previous step's, and evaluates a new one only when the residual does not contract
by ``CONTRACTION`` per step. A chord step that makes things worse is undone and taken again with
a fresh Jacobian, as is one that a kept Jacobian, singular at this point, cannot give; a step
with a fresh Jacobian backtracks until |residual|_2 decreases (as CasADi's Newton rootfinder
does). Converged solutions satisfy the same tolerance (max |residual|)
as plain Newton's.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

#: a chord step must reduce |residual|_2 at least this much, else the Jacobian is renewed
CONTRACTION = 0.25


#: up to this many node states (N nx) a linearisation keeps the transition products as one dense
#: matrix T: (N nx)² numbers, 115 kB at the default 20 intervals of a stance; a finer grid (up to
#: 500 intervals, 200 MB and slower than the loop from ~100 intervals) takes the recursion itself
DENSE_TRANSITIONS_MAX = 300


@dataclass
class _Linearisation:
    """Jacobian blocks of one point, with the condensed matrix inverted."""
    A: np.ndarray        # (N, nx, nx)
    B: np.ndarray        # (N, nx, n_free)
    G: np.ndarray        # (nf, nx)
    S: np.ndarray        # (N + 1, nx, n_free): sensitivities of the nodes to u
    #: (N nx, N nx): s_1..s_N = -T d, the transition products A_k ... A_{j+1}; None on grids of
    #: more than DENSE_TRANSITIONS_MAX node states, where the recursion runs
    T: Optional[np.ndarray]
    #: the inverse of M = G S_N, the condensed Newton matrix (None: M is singular): it is the size
    #: of u, so inverting costs nothing, and each chord step then spares numpy.linalg.solve's ~10 us
    M_inv: Optional[np.ndarray]


@dataclass
class NewtonResult:
    states: np.ndarray   # (N, nx): nodes 1..N
    u: np.ndarray        # all parameters (fixed ones unchanged)
    residual: float      # max |d|, |g - shift| at the returned point
    iterations: int
    jacobians: int       # fresh Jacobian evaluations
    success: bool


class CondensedNewton:
    """Solve the square multiple-shooting system of one kernel set; keeps its last Jacobian."""

    def __init__(self, kernels, tolerance: float, max_iterations: int):
        self.k, self.tol, self.max_iterations = kernels, float(tolerance), int(max_iterations)
        self.nx, self.n = kernels.spec.nx, kernels.intervals
        self._last: dict = {}   # free-index tuple -> _Linearisation (the chord's Jacobian)

    def _residual(self, x0, t, h, u, c, X, shift):
        starts = np.concatenate([x0[None, :], X[:-1]])   # (vstack's numbers, without its wrapper)
        xf = self.k.prop(starts, t, h, u, c)[0].reshape(self.n, self.nx)
        g, G = self.k.final(X[-1], c)
        return X - xf, g - shift, G.reshape(self.nx, -1).T

    def _linearise(self, x0, t, h, u, c, X, free, G):
        starts = np.concatenate([x0[None, :], X[:-1]])
        xf, jac = self.k.sens(starts, t, h, u, c)
        n, nx = self.n, self.nx
        jac = jac.reshape(n, nx + self.k.spec.nu, nx).transpose(0, 2, 1)
        A, B = jac[:, :, :nx], jac[:, :, nx + np.asarray(free)]
        S = np.zeros((n + 1, nx, len(free)))
        for k in range(n):
            S[k + 1] = A[k] @ S[k] + B[k]
        T = None
        if n * nx <= DENSE_TRANSITIONS_MAX:
            T = np.zeros((n, nx, n, nx))   # block (k, j): d s_{k+1} / d(-d_j)
            for k in range(n):
                if k:
                    T[k, :, :k] = np.einsum("ab,bjc->ajc", A[k], T[k - 1, :, :k])
                T[k, :, k] = np.eye(nx)
            T = T.reshape(n * nx, n * nx)
        try:
            M_inv = np.linalg.inv(G @ S[-1])
        except np.linalg.LinAlgError:
            M_inv = None
        return _Linearisation(A, B, G, S, T, M_inv), X - xf.reshape(n, nx)

    def _step(self, lin: _Linearisation, d, g):
        if lin.M_inv is None:
            raise np.linalg.LinAlgError("singular condensed Newton matrix")
        if lin.T is not None:
            s_all = -(lin.T @ d.reshape(-1)).reshape(self.n, self.nx)
        else:                      # the recursion s_{k+1} = A_k s_k - d_k itself
            s_all, s = np.empty((self.n, self.nx)), np.zeros(self.nx)
            for k in range(self.n):
                s = lin.A[k] @ s - d[k]
                s_all[k] = s
        du = lin.M_inv @ (-g - lin.G @ s_all[-1])
        dX = lin.S[1:] @ du + s_all
        return dX, du

    def solve(self, x0, grid, u, free, c, X, shift=None, simulated=False) -> NewtonResult:
        """Newton from node states ``X`` (N, nx) and parameters ``u`` (only ``free`` change).
        ``simulated``: X is the forward simulation of u from x0, so its defects are zero."""
        t, h = grid[:-1], grid[1:] - grid[:-1]   # np.diff's numbers, without its wrapper
        free, u, X = tuple(free), np.array(u, float), np.array(X, float)
        shift = 0.0 if shift is None else np.asarray(shift)
        if simulated:
            g, G = self.k.final(X[-1], c)
            d, g, G = np.zeros_like(X), g - shift, G.reshape(self.nx, -1).T
        else:
            d, g, G = self._residual(x0, t, h, u, c, X, shift)
        norm, merit = _norms(d, g)
        lin, fresh, iterations, jacobians = self._last.get(free), False, 0, 0
        while np.isfinite(norm) and norm > self.tol and iterations < self.max_iterations:
            if lin is None:
                lin, d = self._linearise(x0, t, h, u, c, X, free, G)
                fresh, jacobians = True, jacobians + 1
                self._last[free] = lin
            try:
                dX, du = self._step(lin, d, g)
            except (np.linalg.LinAlgError, ValueError):
                if fresh:
                    break
                # a kept Jacobian singular here (another problem's, or this one's at a point
                # since left) says nothing of this point: renew it (a walk's swing1 failed
                # at once with the last swing1's singular one, a fresh solver solving it)
                lin = None
                continue
            iterations += 1
            # backtracking on |F|_2 (as CasADi's Newton rootfinder does): a stale Jacobian gets
            # the full step only, a fresh one up to ten halvings
            for alpha in (1.0,) if not fresh else 0.5 ** np.arange(11):
                X_new, u_new = X + alpha * dX, u.copy()
                u_new[list(free)] += alpha * du
                d_new, g_new, G_new = self._residual(x0, t, h, u_new, c, X_new, shift)
                norm_new, merit_new = _norms(d_new, g_new)
                if merit_new < merit:
                    break
            if not merit_new < merit:
                if fresh:
                    break             # no descent along Newton's direction: a fallback's turn
                lin = None            # a stale Jacobian made it worse: undo, renew it here
                continue
            X, u, d, g, G = X_new, u_new, d_new, g_new, G_new
            if merit_new > CONTRACTION * merit and norm_new > self.tol:
                lin = None            # poor contraction: renew the Jacobian at the new point
            norm, merit, fresh = norm_new, merit_new, False
        return NewtonResult(X, u, float(norm), iterations, jacobians, bool(norm <= self.tol))


def _norms(d, g) -> tuple[float, float]:
    """max |F| and |F|_2 of the residual F = (d, g); both infinite at a point with an entry that is
    not finite or beyond 1e150 (a diverged trial point is just worse). The dots are BLAS's: numpy's
    reductions need an errstate (several us) to overflow quietly, these cannot."""
    a, b = float(np.abs(d).max()), float(np.abs(g).max())
    largest = max(a, b)
    if not (math.isfinite(a) and math.isfinite(b) and largest < 1e150):
        return float("inf"), float("inf")
    return largest, math.sqrt(float(np.dot(d.ravel(), d.ravel()) + np.dot(g, g)))
