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
"""
from __future__ import annotations

import gc
import os
import time

from ..result_files.registry import RUN_FILES
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
            from multiprocessing import forkserver
            forkserver.ensure_running()
    except (OSError, ValueError):
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
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _receive(run) -> None:
    global _RUN
    _RUN = run


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
