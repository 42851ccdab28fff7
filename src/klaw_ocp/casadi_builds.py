"""CasADi expressions built once per process, one build at a time (docs/limits.md, "Threads").

The models, the subphase specs and the solvers' Functions are CasADi expressions built on first
use and kept for the process. Two threads that build them at the same time can get expressions
that evaluate to slightly different numbers: the first short walks of a fresh process, started
in four threads at once, differed from the same walks alone by 1e-14 to 1e-11 in 8 of 18
processes, and in none once their Functions had been built first (CasADi promises thread-safe
evaluation; its symbolic layer is thread-safe only in some builds, and even there not
deterministic). So every such build runs under one process-wide lock (:data:`BUILD_LOCK`,
re-entrant: a build calls other builds), which made 26 of 26 processes bit for bit; what is
built is then only evaluated, from any thread.
"""
from __future__ import annotations

import functools
import threading

#: held while CasADi expressions are built (and C generated from them, kernels.py)
BUILD_LOCK = threading.RLock()


def built_once(build):
    """``functools.lru_cache(maxsize=None)`` for a function that builds CasADi expressions: the
    first call with given (hashable) arguments builds under :data:`BUILD_LOCK`; later calls read
    the result without taking the lock (a dict lookup, atomic under the GIL), so threads that
    evaluate never wait for a build of something else. As with lru_cache, ``f(1)`` and ``f(x=1)``
    are two entries, and ``cache_clear()`` forgets every result."""
    done: dict = {}

    @functools.wraps(build)
    def once(*args, **kwargs):
        key = (args, tuple(sorted(kwargs.items()))) if kwargs else args
        try:
            return done[key]
        except KeyError:
            pass
        with BUILD_LOCK:
            if key not in done:         # another thread may have built it while this one waited
                done[key] = build(*args, **kwargs)
            return done[key]

    once.cache_clear = done.clear
    return once
