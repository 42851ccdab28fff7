"""Parameter sweeps (``klaw-ocp sweep``): many walks over a grid of configuration values.

A sweep takes one experiment mapping (a YAML file or a dict) and, for every dotted config path
to vary, a list of values. The grid is their Cartesian product in the order given (the first
path varies slowest); each combination is validated like a config file
(:meth:`klaw_ocp.config.ExperimentConfig.from_mapping`) before any walk starts, and then walked
with one or both solver modes. Walks run in this process (``workers=1``), on local worker
processes ('spawn': CasADi objects never cross a fork) or on a dask.distributed cluster
(:mod:`klaw_ocp.sweep_pool`, where a worker that dies loses only the walk it was running). Only
plain dicts and strings cross process boundaries: a worker gets ``(mapping, method)`` and returns one row as a dict
(:func:`run_walk`); each worker process builds its CasADi Functions once (they are cached per
process) and reuses them for every walk it gets.

One walk that does not converge never stops the sweep: its row has ``status`` "failed" and
names the failing step, subphase and residual; any other exception gives ``status`` "error"
and its one-line message; a walk whose worker process died, ``status`` "lost" and the cause.
:func:`write_sweep` writes ``sweep.csv`` (columns:
:data:`RESULT_COLUMNS` after one column per varied path) and the map ``sweep.png``
(:mod:`klaw_ocp.figures.sweep_plot`). docs/sweep.md has the user's view.
The `--vary` values are parsed by :mod:`klaw_ocp.config_paths` (the syntax `--set` shares).
"""
from __future__ import annotations

import copy
import itertools
import math
import os
import sys
import threading
import time
from pathlib import Path
from typing import Any

from . import choices
from .errors import ConfigError, ConvergenceError, Interrupted, KlawError, finite_real, one_line, out_of_range
from .config_paths import (_PATH, _VARY_ALLOWED, MAX_WALKS, RANGE_DIGITS, RANGE_REL_TOL,  # noqa: F401
                           combination_label, format_value, parse_values, parse_vary, set_path)

METHODS = choices.METHODS
FORCE_COLUMNS = ("F_w", "F_theta1", "F_theta2", "pa", "F_theta3", "F_theta4")
#: The columns of a row after the varied paths, in CSV order.
RESULT_COLUMNS = ("method", "status", "failed_step", "failed_subphase", "residual", "steps", "iterations",
                  "wall_s", "build_s", "compile_s", "max_subphase_s", "mean_speed_kmh", "hip_excursion_m", *(f"peak_{c}" for c in FORCE_COLUMNS),
                  "fallbacks", "message")
#: "lost": the worker process running the walk died (docs/sweep.md, "When a worker dies")
STATUSES = ("ok", "failed", "error", "lost")

# ---------------------------------------------------------------------------- grid, validation

def read_mapping(config) -> dict:
    """The experiment as a plain mapping: a dict (copied) or a YAML file (read by the bounded
    loader of config files, :func:`klaw_ocp.config_yaml.read_yaml_file`; not validated here)."""
    if isinstance(config, dict):
        return copy.deepcopy(config)
    from .config_yaml import read_yaml_file
    data = read_yaml_file(config)
    if not isinstance(data, dict):
        raise ConfigError(out_of_range("config", str(config), "a mapping with name, body, walk"))
    return data


def _check_vary(vary: dict) -> dict[str, list]:
    if not isinstance(vary, dict) or not vary:
        raise ConfigError(out_of_range("--vary", vary, f"at least one {_VARY_ALLOWED}"))
    out = {path: list(v) if isinstance(v, (list, tuple, range)) else [v] for path, v in vary.items()}
    for path, values in out.items():
        if not isinstance(path, str) or not _PATH.match(path) or not values:
            raise ConfigError(out_of_range("--vary", f"{path}={values}", _VARY_ALLOWED))
    return out


def _methods(methods) -> tuple | None:
    chosen = METHODS if methods == choices.ALL_METHODS else ((methods,) if isinstance(methods, str) else methods)
    if chosen is not None and (not chosen or any(m not in METHODS for m in chosen)):
        raise ConfigError(out_of_range("--method", methods, f"one of {', '.join(METHODS)}, {choices.ALL_METHODS}"))
    return None if chosen is None else tuple(chosen)


def expand(config, vary: dict, methods=None) -> tuple[str, list[dict]]:
    """Validate every combination and list the walks in grid order.

    Returns the base config's name and the tasks ``{"values", "mapping", "method"}``. ``methods``
    is None (each combination's solver.method), a method, "both", or a sequence of methods.
    Raises the combination's one-line ConfigError/GaitLimitError, prefixed by the combination.
    """
    from .config import ExperimentConfig, check_stance_method

    base, vary, chosen = read_mapping(config), _check_vary(vary), _methods(methods)
    paths = list(vary)
    n_walks = math.prod(len(v) for v in vary.values()) * (len(chosen) if chosen else 1)
    if n_walks > MAX_WALKS:
        raise ConfigError(f"--vary: got {n_walks} walks, allowed at most {MAX_WALKS}")
    tasks, name = [], None
    for combo in itertools.product(*vary.values()):
        values = dict(zip(paths, combo))
        mapping = copy.deepcopy(base)
        for path, value in values.items():
            set_path(mapping, path, value)
        label = combination_label(values)
        try:
            cfg = ExperimentConfig.from_mapping(mapping)
        except KlawError as exc:
            raise _prefixed(exc, label) from None
        name = name or cfg.name
        for method in chosen or (cfg.solver.method,):
            check_stance_method(cfg.solver.stance, method, prefix=f"{label}: ")
            tasks.append({"values": values, "mapping": mapping, "method": method})
    return name, tasks


def _prefixed(exc: KlawError, label: str) -> KlawError:
    message = f"{label}: {one_line(exc)}"
    try:
        return type(exc)(message)
    except TypeError:
        return ConfigError(message)


def default_out_dir(config) -> Path:
    """``results/<name>-sweep`` for the config's name."""
    name = read_mapping(config).get("name")
    return Path("results") / f"{name if isinstance(name, str) and name else 'sweep'}-sweep"


# ------------------------------------------------------------------------------------ one walk

#: One walk at a time per process, although walks are thread-safe (docs/limits.md, "Threads"):
#: a dask worker may run several tasks in threads of one process, whose walks would mostly take
#: turns on the GIL and each count the others' turns in its row's wall_s.
_WALK_LOCK = threading.Lock()


def run_walk(mapping: dict, method: str) -> dict:
    """Walk one validated mapping with ``method``; the result columns of its row, as plain data."""
    from .walk import simulate_walk

    row: dict[str, Any] = dict.fromkeys(RESULT_COLUMNS)
    row.update(method=method, status="ok")
    walk = None
    with _WALK_LOCK:
        t0 = time.perf_counter()
        try:
            walk = simulate_walk(mapping, method=method, raise_on_failure=True)
        except ConvergenceError as err:
            walk = err.partial
            row.update(status="failed", failed_step=int(err.step), failed_subphase=str(err.subphase),
                       residual=finite_real(err.residual), message=_one_line(err))
        except Exception as exc:  # noqa: BLE001 - any other failure is this walk's, not the sweep's
            walk = None
            row.update(status="error", message=_one_line(exc, type(exc).__name__))
        row["wall_s"] = time.perf_counter() - t0
    try:
        if walk is not None:
            row.update(_walk_metrics(walk, keep_residual=row["status"] != "ok") if walk.steps else {"steps": 0})
    except Exception as exc:  # noqa: BLE001 - a walk whose results cannot be read is an error row
        row.update(status="error", message=_one_line(exc, f"reading the walk: {type(exc).__name__}"))
    return row


def _walk_metrics(walk, keep_residual: bool) -> dict:
    import numpy as np

    from .results import hip_offsets, walk_summary, walk_table

    offsets = hip_offsets(walk) if walk.steps else []       # the stance hips once, for both
    table = walk_table(walk, offsets)
    summary = walk_summary(walk, table, offsets=offsets)
    subs = [(entry.get("index", k), s) for k, entry in enumerate(summary["steps"]) for s in entry["subphases"]]
    residuals = [s["residual"] for _, s in subs if s.get("residual") is not None]
    out = {"steps": len(walk.steps), "iterations": int(sum(s.get("iterations", 0) for _, s in subs)),
           "mean_speed_kmh": finite_real(summary.get("mean_hip_speed_kmh")),
           "build_s": float(sum(s.get("build_s", 0.0) for _, s in subs)),
           "compile_s": float(walk.compile_s),
           "max_subphase_s": float(max((s.get("wall_s", 0.0) for _, s in subs), default=0.0)),
           "fallbacks": ";".join(f"step{k}.{s['name']}:{f.get('name') if isinstance(f, dict) else f}"
                                 for k, s in subs for f in s.get("fallbacks", []))}
    if not keep_residual:
        out["residual"] = max(residuals) if residuals else None
    hip = table["hip_y"][np.isfinite(table["hip_y"])]
    out["hip_excursion_m"] = float(hip.max() - hip.min()) if hip.size else None
    for column in FORCE_COLUMNS:
        values = np.abs(table[column][np.isfinite(table[column])])
        out[f"peak_{column}"] = float(values.max()) if values.size else None
    return out


def _one_line(exc: BaseException, prefix: str = "") -> str:
    text = one_line(exc)
    return f"{prefix}: {text}" if prefix and text else (text or prefix)


# ------------------------------------------------------------------------------------ executors

def run_sweep(config, vary: dict, methods=None, workers: int | None = None, scheduler: str | None = None,
              progress: bool = False, on_row=None) -> list[dict]:
    """Walk every combination of ``vary`` (path -> list of values) with ``methods``.

    ``config`` is a mapping or a YAML path; ``methods`` None (the config's solver.method), a
    method name, "both" or a sequence. ``workers`` (default ``os.cpu_count()``) local processes,
    1 = in this process; ``scheduler`` a dask.distributed address (``workers`` is then the
    cluster's business). Every combination is validated first. Returns one row per walk and
    method in grid order: the varied paths, then :data:`RESULT_COLUMNS`. ``on_row(row)``, if
    given, is called after each walk with its row, in the order the walks finish: ``klaw-ocp
    sweep`` appends it to sweep.csv there. A walk whose worker process died has ``status``
    "lost" (:mod:`klaw_ocp.sweep_pool`). Ctrl-C (or SIGTERM, which ``klaw-ocp`` turns into one:
    :mod:`klaw_ocp.stop_signals` says which came) raises :class:`~klaw_ocp.errors.Interrupted`
    whose ``partial`` is the rows finished; the walks running are abandoned, their workers
    killed. Any other exception (``on_row`` could not write) also kills the workers before it
    goes on.
    """
    from .stop_signals import received
    from .sweep_pool import run_jobs

    _, tasks = expand(config, vary, methods)
    workers = (os.cpu_count() or 1) if workers is None else workers
    if scheduler is None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise ConfigError(out_of_range("--workers", workers, "an integer >= 1"))
    from tqdm import tqdm

    results: list[dict | None] = [None] * len(tasks)

    def finished() -> list[dict]:
        return [row for row in results if row is not None]

    def done(i: int, row: dict) -> None:
        results[i] = {**tasks[i]["values"], **row}      # the swept values first, as sweep.csv has them
        bar.update()
        if on_row is not None:
            on_row(results[i])

    def unfinished(i: int, status: str, message: str, wall_s=None) -> None:
        done(i, {**dict.fromkeys(RESULT_COLUMNS), "method": tasks[i]["method"], "status": status,
                 "wall_s": wall_s, "message": message})

    def stop_if_signalled() -> None:
        # a stop signal CasADi's wrappers swallowed in this process (they drop a
        # KeyboardInterrupt raised inside them): the sweep stops all the same, and the row of a
        # walk it cut short is not that walk's
        if received() > signals_before:
            raise KeyboardInterrupt

    signals_before = received()
    bar = tqdm(total=len(tasks), unit="walk", desc="sweep", file=sys.stderr, disable=not progress)
    try:
        if scheduler is None and (workers == 1 or len(tasks) == 1):
            for i, task in enumerate(tasks):
                row = run_walk(task["mapping"], task["method"])
                stop_if_signalled()
                done(i, row)
        else:
            if scheduler is None:
                _compile_here_first(tasks)
                stop_if_signalled()
            run_jobs(run_walk, [(task["mapping"], task["method"]) for task in tasks],
                     on_done=done, on_error=lambda i, text: unfinished(i, "error", text),
                     on_lost=lambda i, cause, wall_s: unfinished(i, "lost", cause, wall_s),
                     workers=workers, scheduler=scheduler)
    except KeyboardInterrupt as err:
        raise Interrupted(finished()) from err
    finally:
        bar.close()
    return finished()


#: The most solver settings whose kernels a sweep compiles before its workers start.
MAX_PRECOMPILED = 4


def _compile_here_first(tasks: list[dict]) -> None:
    """Compile the kernels the walks need in this process before local workers start (each worker
    would otherwise compile the same ones at once, on a machine's first sweep), so that a caller
    listening with :func:`klaw_ocp.kernels.compile_notices` hears of it; a cached kernel
    only loads. Settings beyond MAX_PRECOMPILED compile in their workers as before."""
    from .control.step import prepare_kernels
    from .solvers import make_solver
    seen = []
    for task in tasks:
        solver = task["mapping"].get("solver") or {}
        key = (task["method"], solver.get("intervals", choices.DEFAULT_INTERVALS),
               solver.get("lock_rule", choices.DEFAULT_LOCK_RULE))
        if key not in seen and len(seen) < MAX_PRECOMPILED:
            seen.append(key)
            prepare_kernels(make_solver(key[0], intervals=key[1]), key[2])


# ---------------------------------------------------------------------------------- the files

def counts(rows: list[dict]) -> dict[str, int]:
    """Walks per status: {"ok": .., "failed": .., "error": .., "lost": ..}."""
    return {status: sum(row["status"] == status for row in rows) for status in STATUSES}


def _cell(value) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return ""
    return format_value(value)


def sweep_csv(rows: list[dict], varied_paths: list[str], header: bool = True) -> str:
    """``sweep.csv``: the header and one line per row; without ``header`` only the lines, which
    :func:`append_sweep_row` adds to the file."""
    import csv
    import io

    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    if header:
        writer.writerow([*varied_paths, *RESULT_COLUMNS])
    for row in rows:
        writer.writerow([_cell(row.get(c)) for c in (*varied_paths, *RESULT_COLUMNS)])
    return buffer.getvalue()


def write_sweep(rows: list[dict], varied_paths, out_dir, title: str | None = None) -> dict[str, Path]:
    """Write ``sweep.csv`` and ``sweep.png`` into ``out_dir`` (atomically); returns name -> path."""
    from .figures.sweep_plot import write_sweep_png
    from .result_files.atomic import atomic_write_text
    from .result_files.registry import SWEEP_CSV, SWEEP_PNG

    out = Path(out_dir)
    paths = {"csv": out / SWEEP_CSV, "png": out / SWEEP_PNG}
    atomic_write_text(paths["csv"], sweep_csv(rows, list(varied_paths)))
    write_sweep_png(rows, list(varied_paths), paths["png"], title=title)
    return paths


def append_sweep_row(path, row: dict, varied_paths) -> None:
    """Add ``row``'s line to the sweep.csv at ``path`` (with its header), or write the file with
    the header and that line when there is none yet.

    Why appending is safe: the first line and the header go in together, atomically, so the file
    is never without its header; each later line is one write, flushed and fsynced before the
    next walk's, so a finished walk is on the disk once its row is (a crash can at worst cut the
    line being written, never an earlier one). The lines are in the order the walks finished;
    ``klaw-ocp sweep`` writes the file again, atomically and in grid order, when the sweep ends
    (:func:`write_sweep`) or is interrupted."""
    from .result_files.atomic import atomic_write_text, naming

    path = Path(path)
    if not path.is_file():
        atomic_write_text(path, sweep_csv([row], list(varied_paths)))
        return
    # a write or an fsync that fails (a full disk) names no file: naming() makes its line say which
    with naming(path), open(path, "a", encoding="utf-8", newline="") as handle:
        handle.write(sweep_csv([row], list(varied_paths), header=False))
        handle.flush()
        os.fsync(handle.fileno())


def summary_line(rows: list[dict], paths: dict[str, Path]) -> str:
    n = counts(rows)
    lost = f", {n['lost']} lost" if n["lost"] else ""
    return (f"{len(rows)} walks: {n['ok']} ok, {n['failed']} failed, {n['error']} error{lost}; "
            f"wrote {paths['csv']} and {paths['png']}")
