"""A CasADi Function evaluated on numpy arrays without CasADi's argument conversion.

Calling a Function with numpy arrays converts each one to a DM through SWIG, about 40 us an
argument: a call of a small model (a lock map, the hip of a stance state) costs 100-300 us, ten
times its evaluation. :func:`evaluate` hands CasADi the arrays' memory instead
(``Function.buffer``): the same virtual machine computes the same numbers, in a fraction of the
time. Each thread keeps one buffer per Function (a buffer is a Function's working memory, so two
threads must not share one).
"""
from __future__ import annotations

import threading

import casadi as ca
import numpy as np

_local = threading.local()
#: Functions remembered per thread; beyond this the memory is cleared (maps of many lengths)
_MAX_REMEMBERED = 256


class _Plan:
    """A Function's buffer and the sizes of its inputs and outputs, looked up once."""

    def __init__(self, fn: ca.Function):
        self.fn = fn   # held: a Function's hash is its address, which must stay its own
        self.dense = (all(fn.sparsity_in(i).is_dense() for i in range(fn.n_in()))
                      and all(fn.sparsity_out(i).is_dense() for i in range(fn.n_out())))
        self.rows_in = [fn.size1_in(i) for i in range(fn.n_in())]
        self.sizes_in = [fn.nnz_in(i) for i in range(fn.n_in())]
        self.sizes_out = [fn.nnz_out(i) for i in range(fn.n_out())]
        self.buffer, self.run = fn.buffer() if self.dense else (None, None)
        # the buffer reads and writes arrays whose addresses are set once: handing CasADi a new
        # array crosses SWIG (~3 us an argument), copying into these costs a fraction of that
        self.args = [np.empty(size) for size in self.sizes_in]
        self.results = [np.empty(size) for size in self.sizes_out]
        if self.dense:
            for i, arr in enumerate(self.args):
                self.buffer.set_arg(i, memoryview(arr))
            for i, arr in enumerate(self.results):
                self.buffer.set_res(i, memoryview(arr))


def _plan(fn: ca.Function) -> _Plan:
    # first by the Python object (its hash crosses SWIG, ~2 us), kept alive with its plan so that
    # its id is not reused; then by CasADi's hash: maps of one Function and length are one
    # object behind different Python objects, and share a plan
    by_object = getattr(_local, "by_object", None)
    if by_object is None or len(by_object) > _MAX_REMEMBERED:
        by_object = _local.by_object = {}
        _local.plans = {}
    entry = by_object.get(id(fn))
    if entry is not None:
        return entry[1]
    key = hash(fn)
    plan = _local.plans.get(key)
    if plan is None:
        plan = _local.plans[key] = _Plan(fn)
    by_object[id(fn)] = (fn, plan)
    return plan


def evaluate(fn: ca.Function, *inputs) -> list:
    """``fn(*inputs)`` as flat float arrays, one per output, in CasADi's column-major order (an
    (r, c) output reshapes to (c, r)). Each input is an array (or number) with the input's entries
    in column-major order; a column given once for an (r, n) input is repeated n times, as
    CasADi's call broadcasts it. Functions with sparse inputs or outputs take CasADi's call."""
    plan = _plan(fn)
    if not plan.dense:
        return [np.asarray(ca.densify(out), float).ravel(order="F") for out in fn.call(list(inputs))]
    for i, value in enumerate(inputs):
        flat, arg = np.ravel(value), plan.args[i]
        if flat.size == arg.size:
            arg[:] = flat
        elif flat.size == plan.rows_in[i] and arg.size % max(flat.size, 1) == 0:
            arg.reshape(-1, flat.size)[:] = flat          # one column for all: CasADi's broadcast
        else:
            raise ValueError(f"{fn.name()}: input {i} has {flat.size} entries, expected {arg.size}")
    plan.run()
    return [out.copy() for out in plan.results]
