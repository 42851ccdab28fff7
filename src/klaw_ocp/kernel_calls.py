"""How a kernel of :mod:`.kernels` is called: compiled C through ctypes, or CasADi without a compiler.

Both take flat numpy arrays in CasADi's column-major order and return a list of flat arrays, one
per output (:class:`CompiledFunction`, :class:`CasadiFunction`).

Threads. One kernel object serves every walk of the process (the libraries are loaded once), so it
may be called from several threads at once (docs/limits.md, "Threads"). ctypes releases the GIL
for the whole C call, so two threads really are inside the same kernel at the same time: each
thread therefore has work arrays of its own (:class:`_Workspace`, made on its first call), the
generated code itself keeping no state between calls. Sharing one set of work arrays is what
crashed the interpreter (two walks writing each other's intermediate numbers, then freed memory).
A CasADi Function may be evaluated from several threads at once (CasADi checks out a memory per
call).
"""
from __future__ import annotations

import ctypes
import threading
import weakref

import casadi as ca
import numpy as np


class _Workspace:
    """One thread's arrays for one compiled function: the pointer tables CasADi's calling
    convention takes, the integer and real work arrays, the inputs and outputs, and a memory
    checked out of the library (released when the thread's workspace goes)."""

    def __init__(self, fn: "CompiledFunction"):
        sz_arg, sz_res, sz_iw, sz_w = fn.work_sizes
        self.arg = (ctypes.c_void_p * sz_arg)()
        self.res = (ctypes.c_void_p * sz_res)()
        self.iw = np.zeros(sz_iw, dtype=np.int64)
        self.w = np.zeros(sz_w)
        # the inputs and outputs cross in arrays of their own, whose addresses are set once:
        # looking up a numpy array's address costs 3 us, copying a few hundred numbers into one
        # a fraction of that, and a kernel is called 650 times a walk
        self.inputs = [np.zeros(size) for size in fn.sizes_in]
        self.outputs = [np.zeros(size) for size in fn.sizes_out]
        for i, buffer in enumerate(self.inputs):
            self.arg[i] = buffer.ctypes.data
        for i, buffer in enumerate(self.outputs):
            self.res[i] = buffer.ctypes.data
        self.iw_address, self.w_address = self.iw.ctypes.data, self.w.ctypes.data
        self.mem = fn.checkout()
        weakref.finalize(self, fn.release, self.mem)


class CompiledFunction:
    """One compiled CasADi function called through ctypes (dense inputs and outputs), with work
    arrays per thread."""

    def __init__(self, lib: ctypes.CDLL, name: str):
        self.name = name
        self._fn = getattr(lib, name)
        self._fn.restype = ctypes.c_int
        self._fn.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int]
        n_in, n_out = (getattr(lib, f"{name}_n_{s}") for s in ("in", "out"))
        n_in.restype = n_out.restype = ctypes.c_longlong
        sparsity = {}
        for side, count in (("in", n_in()), ("out", n_out())):
            fn = getattr(lib, f"{name}_sparsity_{side}")
            fn.restype = ctypes.POINTER(ctypes.c_longlong)
            fn.argtypes = [ctypes.c_longlong]
            sparsity[side] = [self._dense_size(fn(i), side, i) for i in range(count)]
        self.sizes_in, self.sizes_out = sparsity["in"], sparsity["out"]
        work = getattr(lib, f"{name}_work")
        sizes = [ctypes.c_longlong() for _ in range(4)]
        work(*[ctypes.byref(s) for s in sizes])
        self.work_sizes = tuple(max(int(s.value), 1) for s in sizes)
        incref = getattr(lib, f"{name}_incref", None)
        if incref is not None:
            incref()
        self._checkout = getattr(lib, f"{name}_checkout", None)
        self._release = getattr(lib, f"{name}_release", None)
        if self._release is not None:
            self._release.argtypes, self._release.restype = [ctypes.c_int], None
        # the generated checkout and release are not written for threads: one at a time
        self._memory_lock = threading.Lock()
        self._local = threading.local()

    def _dense_size(self, pattern, side: str, i: int) -> int:
        rows, cols = int(pattern[0]), int(pattern[1])
        if rows * cols and int(pattern[2]) != 1:   # CasADi's compact form marks a dense pattern with 1
            raise ValueError(f"{self.name}: {side}put {i} is sparse; kernels take and return dense arrays")
        return rows * cols

    def checkout(self) -> int:
        """A memory of the library for one thread (0 for a function that needs none)."""
        if self._checkout is None:
            return 0
        with self._memory_lock:
            return int(self._checkout())

    def release(self, mem: int) -> None:
        if self._release is not None:
            with self._memory_lock:
                self._release(mem)

    def __call__(self, *inputs) -> list:
        # this thread's arrays (an attribute of a threading.local: a few tens of ns, a walk's
        # ~650 calls 0.03 ms of its ~160 ms)
        work = getattr(self._local, "work", None)
        if work is None:
            work = self._local.work = _Workspace(self)
        for i, (x, buffer) in enumerate(zip(inputs, work.inputs)):
            a = np.asarray(x, dtype=float).reshape(-1)   # C order, as the docstring says
            if a.size != buffer.size:
                raise ValueError(f"{self.name}: input {i} has {a.size} entries, expected {buffer.size}")
            buffer[:] = a
        status = self._fn(work.arg, work.res, work.iw_address, work.w_address, work.mem)
        if status:
            raise RuntimeError(f"{self.name}: compiled evaluation failed (status {status})")
        return [buffer.copy() for buffer in work.outputs]


class CasadiFunction:
    """The same calling convention on a CasADi Function (no compiler)."""

    def __init__(self, fn: ca.Function):
        self.name, self._fn = fn.name(), fn
        self._shapes = [(fn.size1_in(i), fn.size2_in(i)) for i in range(fn.n_in())]
        self.sizes_in = [r * c for r, c in self._shapes]
        self.sizes_out = [fn.numel_out(i) for i in range(fn.n_out())]

    def __call__(self, *inputs) -> list:
        args = [np.asarray(x, float).reshape(c, r).T for x, (r, c) in zip(inputs, self._shapes)]
        return [np.asarray(ca.densify(out)).ravel(order="F") for out in self._fn.call(args)]
