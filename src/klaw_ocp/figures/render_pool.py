"""A run's plots and walk.gif drawn on the machine's cores (``klaw-ocp run`` and ``plot``).

The plots (:data:`klaw_ocp.figures.registry.PLOTS`) and walk.gif are independent of each other
and take seconds of matplotlib (its fixed costs per axes, tick and text), while the walk itself
takes a fraction of one. On a machine with two cores or more they are drawn in worker processes,
each output a task, the longest first (:func:`klaw_ocp.figures.registry.cost_order`), so that the
cores finish together.

The workers are forked from multiprocessing's *forkserver*, a clean process that has imported
matplotlib and the drawing modules once (:data:`PRELOAD`): a worker then starts in milliseconds
with nothing left to import, and never inherits the solving process (CasADi, its threads). The
server is started by :func:`prewarm` before the walk is solved, so its imports (about a second
of CPU) run on the other core while the walk runs on this one.

Results stay as they were: a worker hands back a plot's PNG bytes, written here atomically in
the usual order, and writes walk.gif atomically itself (:func:`write_animation`).
A task's exception is raised here as if it had been drawn in this process. With one core, no
forkserver, a single output or a pool that cannot start (or breaks), everything is drawn in this
process, one after the other, as before.

Ctrl-C and SIGTERM are answered by this process alone (issue #37): the forkserver is started with
SIGINT blocked, so that it and every worker it forks never see the Ctrl-C the terminal sends to
each process of the job (a worker stopped while it unpickled its data printed a traceback); a
stop signal waits while the workers are started; when the drawing is stopped, the workers are
ended at once (SIGTERM, silent) and a walk.gif they left half written is removed; and the
forkserver is ended when this process exits (:func:`stop_server`): no process is left behind.
"""
from __future__ import annotations

import contextlib
import gc
import os
import signal
import time

from ..result_files.registry import RUN_FILES
from ..stop_signals import Deferred, blocked, deferred
from .registry import GIF_TASK, PLOTS, cost_order, figure_modules

#: walk.gif's function, ``(run, path) -> path or None``
_GIF = RUN_FILES["animation"].renderer
#: the modules the forkserver imports once for every worker (matplotlib with them)
PRELOAD = figure_modules() + [_GIF.partition(":")[0]]

_RUN = None                  # the worker's RunData, sent once per worker (_receive)


def usable_cores() -> int:
    """The processors this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:                 # not on Linux
        return os.cpu_count() or 1


def _forkserver_context():
    """multiprocessing's forkserver context with :data:`PRELOAD`, or None where there is none or
    only one core (a pool would only add its start-up)."""
    import multiprocessing
    if usable_cores() < 2 or "forkserver" not in multiprocessing.get_all_start_methods():
        return None
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(PRELOAD)
    return context


def prewarm() -> None:
    """Start the forkserver now (it imports :data:`PRELOAD` while the caller goes on, e.g. solves
    the walk); nothing where the outputs will be drawn in this process. Never fails: a server
    that cannot start only means drawing here later."""
    try:
        if _forkserver_context() is not None:
            _start_server()
    except (OSError, ValueError):
        pass


def _start_server() -> None:
    """The forkserver, started (if it is not) with SIGINT blocked: it keeps that mask, and so does
    every worker it forks, which then never sees Ctrl-C, from its first instruction on. It is
    ended when this process exits (:func:`stop_server`)."""
    from multiprocessing import forkserver, resource_tracker
    global _STOP_REGISTERED
    # the tracker first: its own start unblocks SIGINT afterwards, whatever the mask was
    resource_tracker.ensure_running()
    with blocked():
        forkserver.ensure_running()
    if not _STOP_REGISTERED:
        import atexit
        atexit.register(stop_server)
        _adopt_orphans()
        _STOP_REGISTERED = True


def _adopt_orphans() -> None:
    """Make this process the one that reaps the workers if the forkserver dies before them (a
    SIGTERM to the whole job ends every process at once): :func:`stop_server` reaps them, where
    they would otherwise wait as zombies for the system's init (Linux; elsewhere nothing)."""
    with contextlib.suppress(Exception):
        import ctypes
        ctypes.CDLL(None, use_errno=True).prctl(36, 1, 0, 0, 0)     # PR_SET_CHILD_SUBREAPER


_STOP_REGISTERED = False


def stop_server() -> None:
    """End the forkserver this process started, and multiprocessing's resource tracker, now and
    reaped here, rather than when they notice this process has gone (the forkserver only looks
    once it has imported matplotlib, a second or two after it started): a command stopped early
    left them behind, as processes or as zombies of the system's init. Never fails, never waits
    more than a few seconds."""
    from multiprocessing import forkserver, resource_tracker
    server = forkserver._forkserver                                        # noqa: SLF001
    with contextlib.suppress(Exception):
        pid = getattr(server, "_forkserver_pid", None)
        if pid is not None:
            os.kill(pid, signal.SIGTERM)         # at once, even in the middle of its imports
            server._stop()                       # noqa: SLF001 - closes its pipe and reaps it
    tracker = resource_tracker._resource_tracker                           # noqa: SLF001
    fd, pid = getattr(tracker, "_fd", None), getattr(tracker, "_pid", None)
    if fd is None or pid is None:
        return
    with contextlib.suppress(Exception):
        os.close(fd)                             # its pipe closed: it ends (it ignores signals)
        tracker._fd = tracker._pid = None                                   # noqa: SLF001
        for _ in range(100):
            if os.waitpid(pid, os.WNOHANG)[0]:
                break
            time.sleep(0.05)
    with contextlib.suppress(ChildProcessError):      # the workers adopted (_adopt_orphans), if ended
        while os.waitpid(-1, os.WNOHANG)[0]:
            pass


def render_outputs(run, plots_dir=None, gif_path=None) -> tuple[dict, dict]:
    """Draw ``run``'s plots into ``plots_dir`` and its walk.gif to ``gif_path`` (each: None for
    none). Returns (name -> path: the plots by name, walk.gif as "animation" if drawn (not without
    a body to animate); {"plots": s, "animation": s}, None for what was not drawn: drawn in
    parallel, the wall time from the start until the last plot, or walk.gif, was ready; in this
    process, each one's own time)."""
    tasks = [t for t in cost_order() if (t == GIF_TASK and gif_path is not None)
             or (t != GIF_TASK and plots_dir is not None)]
    # the result files are written: what rendering them took (a 1000-step walk's text files are
    # a few hundred MB of transient strings) goes back to the system before the workers draw
    gc.collect()
    _trim()
    start = time.perf_counter()
    done = _in_pool(run, tasks, gif_path, start)
    if done is None:         # in this process: the plots then walk.gif, each timed on its own
        done = {}
        for task in sorted(tasks, key=lambda t: t == GIF_TASK):
            t0 = time.perf_counter()
            done[task] = (_draw(run, task, gif_path), time.perf_counter() - t0)
        plots_s = sum(seconds for task, (_, seconds) in done.items() if task != GIF_TASK)
    else:                    # in parallel: the plots are done when the last one is
        plots_s = max([seconds for task, (_, seconds) in done.items() if task != GIF_TASK], default=0.0)
    paths, times = {}, {"plots": None, "animation": None}
    if plots_dir is not None:
        from ..result_files.atomic import write_rendered
        t0 = time.perf_counter()
        paths.update(write_rendered({name: done[name][0] for name in PLOTS}, plots_dir))
        times["plots"] = plots_s + time.perf_counter() - t0
    if gif_path is not None and done[GIF_TASK][0] is not None:
        paths["animation"], times["animation"] = done[GIF_TASK]
    return paths, times


def _in_pool(run, tasks: list, gif_path, start: float) -> dict | None:
    """task -> (result, seconds since ``start``) drawn in worker processes, or None if they cannot
    be used (drawn in this process instead)."""
    context = _forkserver_context() if len(tasks) > 1 else None
    if context is None:
        return None
    from concurrent.futures import ProcessPoolExecutor, as_completed
    from concurrent.futures.process import BrokenProcessPool
    pool = ProcessPoolExecutor(max_workers=min(usable_cores(), len(tasks)), mp_context=context,
                               initializer=_receive, initargs=(run,))
    try:
        try:
            # the workers start whole: one handed half its data (Ctrl-C in the middle of the pipe
            # write) printed a traceback; the signal is acted on once they are all started
            with deferred():
                _start_server()
                futures = {pool.submit(_draw_here, task, gif_path): task for task in tasks}
        except (OSError, BrokenProcessPool):         # no worker could be started
            return None
        done = {}
        for future in as_completed(futures):
            try:
                result = future.result()             # a task's own exception is raised here
            except BrokenProcessPool:                # a worker died (killed, out of memory)
                return None
            done[futures[future]] = (result, time.perf_counter() - start)
        return done
    except BaseException:        # Ctrl-C, SIGTERM, a task's error: the workers stop now, not at their task's end
        with Deferred(second_raises=False):          # the clean-up is not cut short either
            _end_workers(pool, gif_path)
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _end_workers(pool, gif_path) -> None:
    """End ``pool``'s workers at once (SIGTERM: their default, silent end) and remove the
    temporary walk.gif one of them left (it was being written when it ended)."""
    processes = list((getattr(pool, "_processes", None) or {}).values())     # noqa: SLF001
    for process in processes:
        with contextlib.suppress(Exception):
            process.terminate()
    for process in processes:
        with contextlib.suppress(Exception):
            process.join()
    if gif_path is not None:
        from pathlib import Path
        for tmp in Path(gif_path).parent.glob(f".{Path(gif_path).name}.*"):    # atomic_path's temporary
            with contextlib.suppress(OSError):
                tmp.unlink()


def _receive(run) -> None:
    global _RUN
    _RUN = run
    # belt and braces for a forkserver started by someone else, unmasked: Ctrl-C is the main
    # process's to answer
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _draw_here(task: str, gif_path):
    """A worker's task, on the RunData it received; then the memory its drawing freed handed back
    to the system (glibc keeps it in the process otherwise), so that a worker holds about one
    plot's at a time."""
    try:
        return _draw(_RUN, task, gif_path)
    finally:
        _trim()


def _trim() -> None:
    try:
        import ctypes
        ctypes.CDLL(None).malloc_trim(0)
    except (OSError, AttributeError, TypeError):       # not glibc (macOS; Windows has no forkserver anyway)
        pass


def _draw(run, task: str, gif_path):
    """walk.gif written (its path, or None without a body to animate), or a plot's (file name,
    PNG bytes)."""
    from ..result_files.registry import load
    if task == GIF_TASK:
        return load(_GIF)(run, gif_path)
    from .plots import render_plots
    return render_plots(run, [task])[task]
