"""Where a sweep's walks run: local worker processes that survive one another's death, or a dask
cluster (issue #37 item 3; docs/sweep.md, "When something goes wrong").

A sweep hands its jobs (the arguments of one function call each) to :func:`run_jobs` and hears
of each job exactly once, in the order they end, through one of three callbacks:
``on_done(i, value)``, ``on_lost(i, cause, wall_s)`` (the process running it died: the out-of-
memory killer, a crash in native code) or ``on_error(i, text)`` (the cluster failed it).

Why not ``concurrent.futures.ProcessPoolExecutor``: once one of its workers dies, the pool is
broken and every unfinished future fails with BrokenProcessPool, including the walk running in
the other worker, and it cannot say which worker died. Here each local worker has its own pipe
and runs one job at a time, so the process that died and the job it was running are known
exactly: only that job is lost (with the signal that ended its process); the other workers go
on, and a new process takes the next job. A lost job is not run again: a walk that exhausted the
memory once would do it again (rerun it alone with ``klaw-ocp run``).

Stopping: any exception in the calling process while jobs run (Ctrl-C; SIGTERM, which
``klaw-ocp`` makes raise KeyboardInterrupt as Ctrl-C does, :mod:`klaw_ocp.stop_signals`; a row
that cannot be written) kills the workers at once (their walks are abandoned) before it goes on.
Workers ignore SIGINT and SIGTERM (a terminal sends Ctrl-C to every process of the job, ``kill``
of a process group SIGTERM): only the sweep's own process answers, in one line, and it owns the
workers. A worker whose parent is gone ends by itself.
"""
from __future__ import annotations

import os
import signal
import threading
import time
from collections import deque

from .errors import KlawError, one_line
from .stop_signals import STOP_SIGNALS, blocked

#: how often a worker checks that the sweep's process is still there, s
_PARENT_CHECK_S = 1.0
#: how long a worker may take to end after being told to, s (then it is killed)
_JOIN_S = 5.0


def death_cause(exitcode: int | None) -> str:
    """How a worker process ended, in words: its signal (SIGKILL: possibly the out-of-memory
    killer) or its exit code."""
    if exitcode is None:
        return "worker process died"
    if exitcode < 0:
        try:
            name = signal.Signals(-exitcode).name
        except ValueError:
            name = "unknown signal"
        why = {"SIGKILL": ", possibly out of memory", "SIGSEGV": ", a crash in native code",
               "SIGBUS": ", a crash in native code", "SIGABRT": ", a crash in native code"}.get(name, "")
        return f"worker process died (signal {-exitcode}: {name}){why}"
    return f"worker process exited with code {exitcode}"


def run_jobs(function, jobs: list[tuple], on_done, on_lost, on_error, workers: int = 1,
             scheduler: str | None = None) -> None:
    """Call ``function(*jobs[i])`` for every job on ``workers`` local processes, or on the dask
    cluster at ``scheduler``, and report each job's end through the callbacks (module docstring).
    ``function`` must be importable by name (it is sent to spawned processes)."""
    if scheduler is not None:
        _run_on_dask(function, jobs, scheduler, on_done, on_lost, on_error)
    else:
        _run_local(function, jobs, min(workers, len(jobs)), on_done, on_lost, on_error)


# ------------------------------------------------------------------------------- local processes

def _serve(conn, function) -> None:
    """A worker process: run the jobs that come through ``conn``, one at a time, and send back
    ``(i, "done", value)`` or ``(i, "error", text)``; end on None or when the sweep is gone."""
    for signum in STOP_SIGNALS:                         # the sweep's process answers them
        signal.signal(signum, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):              # blocked while it started (_Worker)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, set(STOP_SIGNALS))
    parent = os.getppid()

    def watch_parent():           # a sweep killed with SIGKILL leaves no worker walking for nobody
        while True:
            time.sleep(_PARENT_CHECK_S)
            if os.getppid() != parent:
                os._exit(1)
    threading.Thread(target=watch_parent, daemon=True).start()
    while True:
        try:
            job = conn.recv()
        except (EOFError, OSError):
            return
        if job is None:
            return
        i, args = job
        try:
            answer = (i, "done", function(*args))
        except BaseException as exc:   # noqa: BLE001 - the job's failure, reported as its row
            answer = (i, "error", _text(exc))
        try:
            conn.send(answer)
        except (OSError, EOFError):
            return
        except Exception as exc:       # noqa: BLE001 - a value that cannot be pickled
            conn.send((i, "error", _text(exc)))


def _text(exc: BaseException) -> str:
    text = one_line(exc)
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


class _Worker:
    """One spawned process ('spawn': CasADi objects never cross a fork), its pipe, and the job it
    is running (None when idle)."""

    def __init__(self, context, function):
        self.conn, child = context.Pipe()
        self.process = context.Process(target=_serve, args=(child, function), daemon=True,
                                       name="klaw-ocp sweep worker")
        # SIGINT and SIGTERM blocked while it starts: the new process inherits the mask, so a
        # Ctrl-C while it imports never prints its traceback (it ignores both once up); one that
        # came meanwhile is delivered here when the block ends
        with blocked(STOP_SIGNALS):
            self.process.start()
        child.close()
        self.job: int | None = None
        self.started = 0.0

    def give(self, i: int, args: tuple) -> bool:
        """Send job ``i``; False if this worker is gone (the job never reached it)."""
        if not self.process.is_alive():
            return False
        try:
            self.conn.send((i, args))
        except OSError:
            return False
        self.job, self.started = i, time.perf_counter()
        return True

    def tell_to_end(self) -> None:
        """No more jobs: the process ends by itself (see :func:`_serve`)."""
        try:
            self.conn.send(None)
        except OSError:
            pass

    def kill(self) -> None:
        """End the process at once (its walk is abandoned; it ignores SIGTERM) and reap it."""
        if self.process.is_alive():
            self.process.kill()
        self.process.join()
        self.conn.close()


def _kill_all(pool: list[_Worker]) -> None:
    """Every worker killed first, then reaped, with Ctrl-C and SIGTERM held until then: a second
    Ctrl-C must not leave a worker running (it would ignore the SIGTERM multiprocessing sends its
    daemon processes at exit, and the exit would wait for it)."""
    with blocked(STOP_SIGNALS):
        for worker in pool:
            if worker.process.is_alive():
                worker.process.kill()
        for worker in pool:
            worker.kill()


def _run_local(function, jobs, workers, on_done, on_lost, on_error) -> None:
    import multiprocessing
    from multiprocessing.connection import wait

    context = multiprocessing.get_context("spawn")
    pending, pool = deque(range(len(jobs))), []
    # each start is one of the first ``workers`` or replaces a worker that died with its job (at
    # most one per job): more means processes that die before they take one, and no end
    starts_left = workers + len(jobs)
    try:
        while pending or any(w.job is not None for w in pool):
            for worker in [w for w in pool if w.job is None]:
                if not pending:
                    break
                if not worker.give(pending[0], jobs[pending[0]]):
                    pool.remove(worker)          # died idle: no job of it is lost
                    worker.kill()
                    continue
                pending.popleft()
            while pending and len(pool) < workers:
                if starts_left == 0:
                    raise KlawError("--workers: the worker processes keep ending before they take a walk")
                starts_left -= 1
                try:
                    worker = _Worker(context, function)
                except OSError as exc:       # no process to be had (a limit): go on with fewer
                    if not pool:
                        raise KlawError(f"--workers: could not start a worker process: {_text(exc)}") from None
                    break
                pool.append(worker)
                if worker.give(pending[0], jobs[pending[0]]):
                    pending.popleft()
            busy = [w for w in pool if w.job is not None]
            if not busy:
                continue
            ready = set(wait([w.conn for w in busy] + [w.process.sentinel for w in busy]))
            for worker in busy:
                if worker.conn in ready or worker.process.sentinel in ready:
                    if not _collect(worker, on_done, on_error):
                        pool.remove(worker)
                        i, wall = worker.job, time.perf_counter() - worker.started
                        worker.process.join(_JOIN_S)     # its own exit status, not our kill's
                        worker.kill()
                        on_lost(i, death_cause(worker.process.exitcode), wall)
        for worker in pool:
            worker.tell_to_end()
        for worker in pool:
            worker.process.join(_JOIN_S)
            worker.kill()                        # if it did not end by itself
    except BaseException:
        _kill_all(pool)
        raise


def _collect(worker: _Worker, on_done, on_error) -> bool:
    """Take the answer of ``worker``'s job; False if its process died first (no answer, or half
    of one: the pipe ends then)."""
    try:
        if not worker.conn.poll():
            return worker.process.is_alive()
        i, kind, value = worker.conn.recv()
    except (EOFError, OSError):
        return False
    worker.job = None
    (on_done if kind == "done" else on_error)(i, value)
    return True


# ----------------------------------------------------------------------------------------- dask

def _run_on_dask(function, jobs, address, on_done, on_lost, on_error) -> None:
    """The same jobs on a dask.distributed cluster. Its nanny restarts a worker that dies and the
    scheduler gives the task to another; a task whose workers died more than
    ``distributed.scheduler.allowed-failures`` times (3 by default) fails with KilledWorker: that
    job is lost, the others go on. Ctrl-C or SIGTERM cancels the jobs not finished."""
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise KlawError('--scheduler needs dask.distributed, which is not installed: '
                        'pip install -e ".[cluster]"') from None
    try:
        client = Client(address)
    except (OSError, TimeoutError, ValueError) as exc:
        raise KlawError(f"--scheduler: could not connect to {address!r}: {one_line(exc)}") from None
    futures = {}
    try:
        futures = {client.submit(function, *args, pure=False): i for i, args in enumerate(jobs)}
        for future in as_completed(futures):
            i = futures.pop(future)
            try:
                value = future.result()
            except Exception as exc:  # noqa: BLE001 - the cluster lost or failed this task
                if type(exc).__name__ == "KilledWorker":     # wall_s: unknown (several tries)
                    on_lost(i, _killed_worker_cause(exc), None)
                else:
                    on_error(i, f"worker: {_text(exc)}")
                continue
            on_done(i, value)
    finally:
        if futures:
            client.cancel(list(futures))
        client.close()


def _killed_worker_cause(exc) -> str:
    tries = getattr(exc, "allowed_failures", None)
    times = f"{tries + 1} times" if isinstance(tries, int) else "repeatedly"
    return (f"worker process died {times} running it (dask KilledWorker), possibly out of memory; "
            f"the dask workers' logs name the signal")
