"""The public API from several threads at once (issue #37, docs/limits.md "Threads").

Real threads run short walks in both solver modes, the tracking stance (IPOPT) and invalid walks
mixed; every valid walk must be the walk computed alone, bit for bit, and every invalid one a
ConfigError. Bit for bit, not to a tolerance: a walk is a fixed sequence of floating-point
operations on its own inputs (compiled kernels, CasADi's virtual machine, numpy), none of which
depends on what another thread does, so any difference, however small, means two walks shared
something they must not (a kernel's work array: before issue #37 such walks differed, then the
interpreter aborted). No wall-clock time is asserted.
"""
from __future__ import annotations

import io
import sys
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import klaw_ocp
from klaw_ocp import ConfigError, GaitLimitError
from klaw_ocp.body_motion import body_motion
from klaw_ocp.console import CasadiMessages
from klaw_ocp.results import walk_table
from klaw_ocp.solvers import thread_safety


def _walk(steps=2, speed=5.0, **solver):
    return {"name": "t", "body": {"height": 1.8, "mass": 80}, "walk": {"speed": speed, "steps": steps},
            "solver": solver}


VALID = {
    "multiple shooting": _walk(),
    "plain shooting": _walk(method="plain-shooting"),
    "tracking stance (IPOPT)": _walk(stance="tracking"),
    "4 km/h": _walk(speed=4.0),
}
INVALID = {
    "too fast": (_walk(speed=50.0), GaitLimitError),
    "too few intervals": (_walk(intervals=2), ConfigError),
    "not a walk": (42, ConfigError),
}


def _fingerprint(walk) -> list:
    """Everything a walk computed, in order: its start, each subphase's unknowns, samples,
    forces, residual and path, and how it ended (times left out: they differ run to run)."""
    out = [walk.status, walk.message, walk.initial_state, walk.solver_messages]
    for step in walk.steps:
        for sub in step.subphases:
            out += [sub.name, sub.nlp, sub.success, sub.iterations, sub.residual, sub.path_min, sub.fallbacks,
                    sorted(sub.parameters.items()), sub.t, sub.states, sub.forces]
    return out


def _same(a, b) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return np.array_equal(a, b, equal_nan=a.dtype.kind == "f" and b.dtype.kind == "f")
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return a == b or (a != a and b != b)     # NaN == NaN here


def _attempt(job):
    """One call of the public API: ("walk", name, walk) or ("refused", name, the error)."""
    name, spec = job
    try:
        return "walk", name, klaw_ocp.simulate_walk(spec)
    except ConfigError as err:
        return "refused", name, err


def test_walks_in_threads_are_the_walks_run_alone():
    jobs = [(name, spec) for name, spec in VALID.items()] * 2 + [(name, spec) for name, (spec, _) in INVALID.items()]
    order = np.random.default_rng(37).permutation(len(jobs))
    jobs = [jobs[i] for i in order]
    # first in threads (a fresh process builds and compiles its solvers here, in several threads at
    # once), then each walk alone
    with ThreadPoolExecutor(max_workers=4) as pool:
        outcomes = list(pool.map(_attempt, jobs))      # an exception other than ConfigError fails here
    alone = {name: klaw_ocp.simulate_walk(spec) for name, spec in VALID.items()}
    assert len(outcomes) == len(jobs)
    for (kind, name, result) in outcomes:
        if name in INVALID:
            assert kind == "refused" and type(result) is INVALID[name][1], (name, result)
            assert "\n" not in str(result)
        else:
            assert kind == "walk" and result.status == "ok", (name, kind, result)
            assert len(result.steps) == len(alone[name].steps) == 2
            assert _same(_fingerprint(result), _fingerprint(alone[name])), name


def test_reading_walks_while_others_solve():
    """A walk's table and its body's angles (CasADi Functions evaluated from numpy) computed in
    threads while other threads solve walks: the same numbers as computed alone."""
    walk = klaw_ocp.simulate_walk(VALID["multiple shooting"])
    table, angles = walk_table(walk), body_motion(walk, 30.0).angles

    def read(_):
        return walk_table(walk), body_motion(walk, 30.0).angles

    with ThreadPoolExecutor(max_workers=4) as pool:
        solving = [pool.submit(klaw_ocp.simulate_walk, VALID[name]) for name in ("plain shooting", "4 km/h")]
        reads = list(pool.map(read, range(4)))
        solved = [future.result() for future in solving]
    assert all(w.status == "ok" for w in solved)
    for other_table, other_angles in reads:
        assert other_table.keys() == table.keys()
        assert all(_same(other_table[c], table[c]) for c in table)
        assert np.array_equal(other_angles, angles)


def test_each_thread_keeps_its_own_casadi_messages_and_stderr_comes_back(monkeypatch):
    """Two walks' collectors open and close interleaved (A opens, B opens, A closes, B closes):
    each keeps the CasADi lines written from its own thread, other lines go through, and
    sys.stderr is the original stream afterwards (one swap per thread restored the other's)."""
    stream = io.StringIO()
    monkeypatch.setattr(sys, "stderr", stream)
    a_open, b_open, a_closed = threading.Event(), threading.Event(), threading.Event()
    kept = {}

    def walk_a():
        with CasadiMessages() as messages:
            a_open.set()
            b_open.wait(10)
            sys.stderr.write("CasADi - 2030-01-01 00:00:00 WARNING(\"from A\") [a.cpp:1]\n")
            print("a line of A's", file=sys.stderr)
        kept["A"] = messages.messages
        a_closed.set()

    def walk_b():
        a_open.wait(10)
        with CasadiMessages() as messages:
            b_open.set()
            a_closed.wait(10)
            sys.stderr.write("CasADi - 2030-01-01 00:00:00 WARNING(\"from B\") [b.cpp:1]\n")
        kept["B"] = messages.messages

    threads = [threading.Thread(target=walk_a), threading.Thread(target=walk_b)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(30)
    assert sys.stderr is stream
    assert kept == {"A": ['WARNING("from A") [a.cpp:1]'], "B": ['WARNING("from B") [b.cpp:1]']}
    assert stream.getvalue() == "a line of A's\n"


def test_a_casadi_without_thread_safety_solves_one_walk_at_a_time(monkeypatch):
    """Where CasADi was built without thread-safe symbolics, walks take turns: a walk started
    while another solves builds nothing until that one is done."""
    import klaw_ocp.walk
    monkeypatch.setattr(thread_safety, "CASADI_THREAD_SAFE", False)
    started, make_solver = threading.Event(), klaw_ocp.walk.make_solver

    def spy(*args, **kwargs):
        started.set()
        return make_solver(*args, **kwargs)
    monkeypatch.setattr(klaw_ocp.walk, "make_solver", spy)
    walks = []
    with thread_safety.solving():      # as a walk in this thread holds it
        waiting = threading.Thread(target=lambda: walks.append(klaw_ocp.simulate_walk(VALID["multiple shooting"])))
        waiting.start()
        assert not started.wait(1.0), "a second walk solved while the first held the lock"
    waiting.join(120)
    assert started.is_set() and len(walks) == 1 and walks[0].status == "ok"
