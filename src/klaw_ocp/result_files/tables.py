"""The CSV result files of a run, and the fixed-decimal rows of walk.bvh and walk.mot.

- ``dynamics.csv``: :func:`dynamics_csv`, one row per time sample (:func:`klaw_ocp.results.walk_table`),
  every float as its shortest repr (it reads back as the same double).
- ``events.csv``: :func:`events_csv`, the foot events (heel strike, foot flat, heel-off, toe-off).
- ``angles.csv``: :func:`angles_csv`, the body at every frame: time, root, the 56 angles in degrees
  (:mod:`klaw_ocp.body_motion`, docs/body.md).

Each is one ``%`` format per row (the per-value work in C). The registry's renderers
(:mod:`.registry`) are the ``*_file`` functions, each of a :class:`~.run_data.RunData`. The
reader is :func:`klaw_ocp.result_files.run_data.read_table`.
"""
from __future__ import annotations

import csv
import io

import numpy as np

#: Significant digits of angles.csv: 1e-10 degrees and 1e-10 m at 10 m, far below any use (an
#: animation, a gait curve), at a third of the time of writing every float exactly.
ANGLES_DIGITS = 12
#: dynamics.csv's columns that are not floats, and their formats
_NOT_FLOAT = {"step": "%d", "subphase": "%s"}


def dynamics_csv(walk, table: dict | None = None, header: bool = True) -> str:
    """``dynamics.csv``: the header and one row per sample of ``table`` (default: the walk's);
    without ``header`` only the rows, which a run appends step by step (the same bytes)."""
    from ..results import COLUMNS, walk_table       # (results loads CasADi: only when a table is written)
    if table is None:
        table = walk_table(walk) if walk.steps else {c: np.array([]) for c in COLUMNS}
    head = ",".join(COLUMNS) + "\n" if header else ""
    # "%r" of a float is its shortest repr; no cell needs the csv module's quoting (numbers and
    # subphase names)
    row = ",".join(_NOT_FLOAT.get(c, "%r") for c in COLUMNS)
    return head + "".join([row % values + "\n" for values in zip(*(table[c].tolist() for c in COLUMNS))])


def angles_csv(angles: dict) -> str:
    """``angles.csv``: the columns of ``angles`` (time, root_x/y/z in m, the 56 angles in degrees,
    in skeleton.ANGLE_NAMES order) in their order, one row per frame, each value to
    ANGLES_DIGITS significant digits."""
    header = ",".join(angles) + "\n"
    if not len(next(iter(angles.values()))):
        return header
    row = ",".join([f"%.{ANGLES_DIGITS}g"] * len(angles))
    return header + "\n".join(row % values for values in zip(*(c.tolist() for c in angles.values()))) + "\n"


def events_csv(summary: dict) -> str:
    """``events.csv``: one row per foot event (time s, side, event), from the summary's ``events``
    (:func:`klaw_ocp.results.foot_events`); only the header for a result written before them."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(("time", "side", "event"))
    writer.writerows((repr(float(e["time"])), e["side"], e["event"]) for e in summary.get("events", []))
    return buffer.getvalue()


def decimal_rows(values, decimals: int, separator: str) -> str:
    """The rows of ``values`` (n, c) as text: each value rounded to ``decimals`` and written as
    ``"%.{decimals}f"``, joined by ``separator``, every row ending in a newline ("" for no rows).
    Rounded first and + 0.0, so that a value a hair below zero is written 0, not -0 (walk.bvh,
    walk.mot)."""
    rounded = np.round(np.asarray(values, float), decimals) + 0.0
    if not len(rounded):
        return ""
    row = separator.join([f"%.{decimals}f"] * rounded.shape[1])
    return "".join([row % tuple(v) + "\n" for v in rounded.tolist()])


# -- the registry's renderers: a RunData -> the file's bytes ---------------------------------------
def dynamics_file(run) -> bytes:
    return dynamics_csv(None, run.table).encode("utf-8")


def events_file(run) -> bytes:
    return events_csv(run.summary).encode("utf-8")


def angles_file(run) -> bytes:
    return angles_csv(run.angles).encode("utf-8")
