"""A long walk's results without solving it: a solved walk's results laid end to end (the plots and
walk.gif of a long walk are tested on these; solving 300 steps would take the suite's time)."""
from __future__ import annotations

import numpy as np

from klaw_ocp.result_files.run_data import RunData


def tiled(run: RunData, copies: int, name: str | None = None) -> RunData:
    """``run`` (an even number of steps, so that the legs keep alternating) walked ``copies`` times
    end to end: each copy's steps, samples, frames and events later by the walk's duration and
    further by its distance (its last step's origin plus one step)."""
    steps = run.steps
    assert len(steps) % 2 == 0, "the stance legs alternate across copies only for an even number of steps"
    period = steps[-1]["t_start_s"] + steps[-1]["t_step_s"] - steps[0]["t_start_s"]
    distance = 2 * steps[-1]["origin_x_m"] - steps[-2]["origin_x_m"] - steps[0]["origin_x_m"]
    summary = dict(run.summary, steps=[], events=[], name=name or f"{run.name}x{copies}")
    table = {c: [] for c in run.table}
    angles = {c: [] for c in run.angles}
    for k in range(copies):
        dt, dx = k * period, k * distance
        summary["steps"] += [dict(s, index=s["index"] + k * len(steps), t_start_s=s["t_start_s"] + dt,
                                  origin_x_m=s["origin_x_m"] + dx) for s in steps]
        summary["events"] += [dict(e, time=e["time"] + dt) for e in run.summary.get("events", [])]
        shift = {"t": dt, "hip_x": dx, "swing_hip_x": dx, "step": k * len(steps), "time": dt, "root_x": dx}
        for source, target in ((run.table, table), (run.angles, angles)):
            for column, values in source.items():
                target[column].append(values + shift[column] if column in shift else values)
    summary["steps_completed"] = summary["steps_planned"] = len(summary["steps"])
    return RunData(name=summary["name"], summary=summary, table={c: np.concatenate(v) for c, v in table.items()},
                   angles={c: np.concatenate(v) for c, v in angles.items()})
