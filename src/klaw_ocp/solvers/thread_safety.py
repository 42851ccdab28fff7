"""What the solvers share between threads, and the locks around what must not run at once.

Walks may be solved in several threads of one process at the same time (docs/limits.md,
"Threads"). What they share, and how each is made safe:

- the compiled kernels, one set per process: each thread calls them with work arrays of its own
  (:mod:`klaw_ocp.kernel_calls`); ctypes releases the GIL, so their C code runs in parallel;
- CasADi: its Functions may be evaluated from several threads at once, and its symbolic layer
  (the expressions the solvers build on first use) may be used from several threads in builds
  with thread-safe symbolics, which the PyPI wheels are (``CASADI_WITH_THREADSAFE_SYMBOLICS`` and
  ``CASADI_WITH_THREAD`` among ``casadi.CasadiMeta.compiler_flags()``). A CasADi built without
  them gets one solving at a time instead (:func:`solving`);
- IPOPT (multiple shooting's repairs, the tracking stance): one solve at a time for the process
  (:data:`IPOPT_LOCK`). Its linear solver, MUMPS, is not made for concurrent use, and a solve's
  statistics are read from the shared solver Function after the call returns (``stats()`` reads
  the memory of the last call, which another thread's call would replace). Walks with the
  tracking stance, which solves every stance with IPOPT, take turns there.

What the walk shares beyond the solvers (``sys.stderr`` while CasADi may warn) is made safe in
:mod:`klaw_ocp.console`.
"""
from __future__ import annotations

import threading
from contextlib import nullcontext

import casadi as ca

_FLAGS = ca.CasadiMeta.compiler_flags()
#: whether this CasADi may build expressions and evaluate Functions in several threads at once
CASADI_THREAD_SAFE = "CASADI_WITH_THREADSAFE_SYMBOLICS" in _FLAGS and "CASADI_WITH_THREAD" in _FLAGS
#: held around each IPOPT solve and the reading of its statistics
IPOPT_LOCK = threading.Lock()
#: one solving at a time where CasADi is not thread-safe (re-entrant: an ``on_step`` callback may
#: run a walk of its own)
_ONE_AT_A_TIME = threading.RLock()


def solving():
    """The context a caller holds while it solves (builds and calls solvers): nothing where
    CasADi is thread-safe, else one process-wide lock, so that solves in several threads take
    turns instead of corrupting CasADi's expressions."""
    return nullcontext() if CASADI_THREAD_SAFE else _ONE_AT_A_TIME
