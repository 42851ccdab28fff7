"""A run's result files written as its walk goes (``klaw-ocp run``; issue #24, "failure loses
nothing").

:class:`RunWriter` is handed to :func:`klaw_ocp.walk.simulate_walk` as its ``on_step``. After each
completed step it

- appends the step's rows to ``dynamics.csv`` (the file grows step by step; its bytes at the end
  are those of :func:`klaw_ocp.result_files.tables.dynamics_csv` of the whole walk),
- appends the new foot events to ``events.csv`` (rewritten instead, atomically, in the rare
  case that an event of the new step falls before one already written),
- rewrites ``summary.json`` atomically (``status: "running"``, every completed step): the full
  summary, but as compact JSON, each step's entry serialised once, when it completes, and the
  summary assembled from those texts (:func:`klaw_ocp.result_files.summary_json.summary_text`).

These per-step writes skip the fsync of :func:`~klaw_ocp.result_files.atomic.atomic_write_bytes` (they are
safe against a crash of the process, and the next step rewrites them anyway); they cost about 1 ms
a step beside the 15-20 ms of the natural walk's solve (docs/experiments.md). :meth:`RunWriter.finish`
then writes ``events.csv`` durably and the files that need the whole walk: the body's
(``angles.csv``, ``walk.bvh``, ``walk.mot``: the last stance leg is completed by the next step's
double support), at the walk's own frame rate (``output.fps``); the caller draws the plots and
``walk.gif``; the final ``summary.json`` (indented; ``status`` "ok", "failed" with its ``failure``,
or "interrupted") is written last, so that a summary saying "ok" comes with every file. A crash
between steps leaves the completed steps on disk with ``status: "running"``; a write that fails
(a full disk) leaves "running", or "incomplete" with the path and the cause if the summary can
still be written (:meth:`RunWriter.record_write_error`). Every file name is the registry's
(:mod:`.registry`).
"""
from __future__ import annotations

import json
import os
import time
from pathlib import Path

import numpy as np

from ..results import COLUMNS, step_hip_offsets, mean_hip_speed_kmh, step_summary, step_table, summary_of
from .atomic import atomic_write_bytes, naming, write_rendered
from .registry import RUN_FILES
from .render import body_keys, render_run
from .summary_json import summary_text
from .tables import dynamics_csv, events_csv

DYNAMICS_FILE, SUMMARY_FILE, EVENTS_FILE, RESOLVED_FILE = (RUN_FILES[k].name for k in
                                                           ("dynamics", "summary", "events", "resolved"))


class RunWriter:
    """Writes one run into ``folder``: ``config.resolved.yaml`` (``resolved_yaml``, if given) and
    the header of ``dynamics.csv`` now, each completed step when called (:meth:`step`, the
    ``on_step`` of :func:`~klaw_ocp.walk.simulate_walk`), everything else in :meth:`finish`.
    The body's files are at the walk's frame rate (``walk.spec.fps``, from ``output.fps``)."""

    def __init__(self, folder, resolved_yaml: str | None = None):
        self.folder = Path(folder)
        #: per written step: (table, summary entry, its JSON text, dynamics.csv's size after it)
        self.done: list[tuple] = []
        self.step_s = 0.0          # time spent writing the steps (the benchmark's "per-step writing")
        self._walk = None          # the walk last written (for record_write_error)
        self._events: list = []    # the foot events in events.csv
        if resolved_yaml is not None:
            atomic_write_bytes(self.folder / RESOLVED_FILE, resolved_yaml.encode("utf-8"))
        header = dynamics_csv(None, {c: np.array([]) for c in COLUMNS}).encode("utf-8")
        atomic_write_bytes(self.folder / DYNAMICS_FILE, header, durable=False)     # fsynced by finish
        self._header_size = len(header)

    # -- per step --------------------------------------------------------------------------------
    def step(self, walk) -> None:
        """Write every completed step of ``walk`` not written yet, then the summary so far."""
        t0 = time.perf_counter()
        self._walk = walk
        self._catch_up(walk)
        summary = self._summary(walk, status="running")
        self._write_events(summary["events"])
        text = summary_text(summary, [d[2] for d in self.done])
        atomic_write_bytes(self.folder / SUMMARY_FILE, text.encode("utf-8"), durable=False)
        self.step_s += time.perf_counter() - t0

    def _write_events(self, events: list) -> None:
        path, n = self.folder / EVENTS_FILE, len(self._events)
        if n and events[:n] == self._events and path.is_file():
            rows = events_csv({"events": events[n:]}).split("\n", 1)[1]       # without the header
            with naming(path), open(path, "a", encoding="utf-8", newline="") as handle:
                handle.write(rows)
        else:
            atomic_write_bytes(path, events_csv({"events": events}).encode("utf-8"), durable=False)
        self._events = events

    def _catch_up(self, walk) -> None:
        for step in walk.steps[len(self.done):]:
            offsets = step_hip_offsets(walk.spec.body, step)     # the stance hips once, for both
            table = step_table(step, walk.spec.body, offsets)
            entry = step_summary(walk.spec, step, offsets)
            text = json.dumps(entry, allow_nan=False)
            size = self._append(dynamics_csv(None, table, header=False).encode("utf-8"))
            self.done.append((table, entry, text, size))     # one statement: the step is written

    def _append(self, data: bytes) -> int:
        """Append ``data`` after the rows written so far (an append an interrupt cut short is
        overwritten); returns the file's size after it."""
        start = self.done[-1][3] if self.done else self._header_size
        with naming(self.folder / DYNAMICS_FILE):
            fd = os.open(self.folder / DYNAMICS_FILE, os.O_WRONLY)
            try:
                os.lseek(fd, start, os.SEEK_SET)
                view = memoryview(data)
                while view:
                    view = view[os.write(fd, view):]
                os.ftruncate(fd, start + len(data))
            finally:
                os.close(fd)
        return start + len(data)

    def _summary(self, walk, status: str | None = None) -> dict:
        speed = mean_hip_speed_kmh(self.done[0][0], self.done[-1][0]) if self.done else None
        summary = summary_of(walk, [d[1] for d in self.done], speed)
        if status is not None:
            summary["status"] = status
        return summary

    # -- at the end ------------------------------------------------------------------------------
    def table(self) -> dict:
        """The whole walk's table (:func:`klaw_ocp.results.walk_table`), from the steps written."""
        if not self.done:
            return {c: np.array([], dtype=str if c == "subphase" else float) for c in COLUMNS}
        return {c: np.concatenate([d[0][c] for d in self.done]) for c in COLUMNS}

    def finish(self, walk, body: bool = True, summary: bool = True):
        """Write the rest of the run: any step not written yet, the final events (durably), with
        ``body`` angles.csv, walk.bvh and walk.mot, and last, with ``summary``, the final summary
        (durably; without it the caller writes it with :meth:`write_summary` once the plots are
        drawn): a folder whose summary says "ok" has every file. Returns the paths by name and the
        RunData of the walk (the plots and walk.gif are drawn from it:
        :func:`klaw_ocp.figures.render_pool.render_outputs`)."""
        from .run_data import RunData
        self._catch_up(walk)
        self._walk = walk
        path = self.folder / DYNAMICS_FILE
        with naming(path), open(path, "rb+") as handle:     # the rows of the written steps, durably
            handle.truncate(self.done[-1][3] if self.done else self._header_size)
            os.fsync(handle.fileno())
        final = self._summary(walk)
        paths = {"dynamics": path, "events": self.folder / EVENTS_FILE}
        atomic_write_bytes(paths["events"], events_csv(final).encode("utf-8"))
        self._events = final["events"]
        if (self.folder / RESOLVED_FILE).exists():
            paths["resolved"] = self.folder / RESOLVED_FILE
        table = self.table()
        run = RunData.from_walk(walk, table=table, summary=final) if body else \
            RunData(name=walk.spec.name, summary=final, table=table, fps=walk.spec.fps)
        if body:
            paths.update(write_rendered(render_run(run, body_keys()), self.folder))
        if summary:
            paths["summary"] = self.write_summary(final)
        return paths, run

    def write_summary(self, summary: dict) -> Path:
        """The final summary.json (indented, durably); returns its path."""
        path = self.folder / SUMMARY_FILE
        atomic_write_bytes(path, summary_text(summary).encode("utf-8"))
        return path

    def record_write_error(self, text: str) -> None:
        """Writing the run failed (``text``: the path and the cause): summary.json says so, if it
        still can be written: status "incomplete", ``message`` the failure (the walk's own
        ``failure``, if any, kept). Never raises: on a full disk the earlier summary stays, its
        status "running"; either way no summary claims "ok" for files the folder lacks."""
        walk = self._walk
        if walk is None or not self.folder.is_dir():      # a folder removed is not made again
            return
        summary = self._summary(walk)
        summary["status"], summary["message"] = "incomplete", f"could not write {text}"
        try:
            atomic_write_bytes(self.folder / SUMMARY_FILE, summary_text(summary).encode("utf-8"))
        except Exception:   # noqa: BLE001 - the first failure is the one to report
            pass
