"""Result files of ``klaw-ocp run``, written atomically (temporary file, then rename); a run
writes them step by step through :mod:`klaw_ocp.io.run_writer`, the same bytes.

- ``summary.json``: :func:`klaw_ocp.results.walk_summary`.
- ``dynamics.csv``: :func:`klaw_ocp.results.walk_table`, one row per time sample.
- ``events.csv``: :func:`events_csv`, the foot events (heel strike, foot flat, heel-off, toe-off).
- ``angles.csv``: :func:`angles_csv`, the body at every frame: time, root, the 56 angles in degrees
  (:mod:`klaw_ocp.body_motion`, docs/body.md).
"""
from __future__ import annotations

import csv
import io
import json
import math
import os
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..results import COLUMNS, walk_table
from .fixed_text import shortest_repr_slots, slots_text, text_slots

#: Significant digits of angles.csv: 1e-10 degrees and 1e-10 m at 10 m, far below any use (an
#: animation, a gait curve), at a third of the time of writing every float exactly.
ANGLES_DIGITS = 12


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextmanager
def atomic_path(path: Path, suffix: str = ".tmp"):
    """A temporary path in ``path``'s folder to write the file into; when the block ends, the file
    gets the user's normal mode (mkstemp makes it 0600) and is renamed to ``path``, so that a reader
    never sees a half-written file; if the block raises, the temporary is removed."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=suffix)
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def atomic_write_bytes(path: Path, data: bytes, durable: bool = True) -> None:
    """Write ``data`` to ``path`` atomically (:func:`atomic_path`). ``durable``: flushed to the
    disk before the rename (fsync, a few ms); without it the file is as safe against a crash of
    the process, not against one of the machine (the per-step rewrites of a run,
    :mod:`klaw_ocp.io.run_writer`)."""
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        handle.write(data)
        handle.flush()
        if durable:
            os.fsync(handle.fileno())


def atomic_write_text(path: Path, text: str, durable: bool = True) -> None:
    """:func:`atomic_write_bytes` of UTF-8 text (newlines written as given)."""
    atomic_write_bytes(path, text.encode("utf-8"), durable)


def dynamics_csv(walk, table: dict | None = None, header: bool = True) -> str:
    """``dynamics.csv``: the header and one row per sample of ``table`` (default: the walk's);
    without ``header`` only the rows, which a run appends step by step (the same bytes)."""
    if table is None:
        table = walk_table(walk) if walk.steps else {c: np.array([]) for c in COLUMNS}
    n = len(table[COLUMNS[0]])
    head = ",".join(COLUMNS) + "\n" if header else ""
    if not n:
        return head
    # every float as its exact shortest repr, built in numpy for all values at once
    # (io/fixed_text.py: a repr per value was a third of rendering the files); no cell needs the
    # csv module's quoting (numbers and subphase names)
    columns, floats = [], []
    for c in COLUMNS:
        if c in ("step", "subphase"):
            columns.append(c)
        else:
            floats.append(table[c])
            if not columns or isinstance(columns[-1], str):
                columns.append([])
            columns[-1].append(len(floats) - 1)
    # the floats in one pass (its fixed cost is a few hundred numpy calls), then cut into runs
    cells = shortest_repr_slots(np.column_stack(floats)).reshape(n, len(floats), -1)
    return head + slots_text([text_slots(table[c].tolist()) if c == "subphase" else
                              text_slots([str(int(v)) for v in table[c].tolist()]) if c == "step" else
                              cells[:, c[0]:c[-1] + 1] for c in columns])


def render_walk(walk, fps: float | None = None) -> dict:
    """Every result file of ``walk`` in memory, the body's angles at ``fps`` frames per second
    (default: output.fps's): name -> (file name, bytes). Rendering is separate from writing so
    that the benchmark can time the two, and a failure to render writes nothing."""
    from .run_data import RunData
    return render_run(RunData.from_walk(walk, fps=fps))


def render_run(run) -> dict:
    """:func:`render_walk` of a :class:`~klaw_ocp.io.run_data.RunData` (its table, summary and,
    when it has them, the body's angles)."""
    files = _render(run.summary, dynamics_csv(None, run.table))
    files.update(render_body(run))
    return files


def render_body(run) -> dict:
    """The body's files of a run (angles.csv, walk.bvh, walk.mot), none without angles."""
    files = {}
    if run.angles is not None and len(run.angles["time"]):
        from .bvh import BVH_FILE, bvh_text
        from .opensim import MOT_FILE, render_mot
        files["angles"] = ("angles.csv", angles_csv(run.angles).encode("utf-8"))
        files["bvh"] = (BVH_FILE, bvh_text(run).encode("utf-8"))
        files["mot"] = (MOT_FILE, render_mot(run.angles, run.body_model(), name=run.summary.get("name", "walk")))
    return files


def angles_csv(angles: dict) -> str:
    """``angles.csv``: the columns of ``angles`` (time, root_x/y/z in m, the 56 angles in degrees,
    in skeleton.ANGLE_NAMES order) in their order, one row per frame, each value to
    ANGLES_DIGITS significant digits."""
    header = ",".join(angles) + "\n"
    if not len(next(iter(angles.values()))):
        return header
    row = ",".join([f"%.{ANGLES_DIGITS}g"] * len(angles))
    # one format per row (C speed): a repr per value costs more than the body's kinematics
    return header + "\n".join(row % values for values in zip(*(c.tolist() for c in angles.values()))) + "\n"


def events_csv(summary: dict) -> str:
    """``events.csv``: one row per foot event (time s, side, event), from the summary's ``events``
    (:func:`klaw_ocp.results.foot_events`); only the header for a result written before them."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(("time", "side", "event"))
    writer.writerows((repr(float(e["time"])), e["side"], e["event"]) for e in summary.get("events", []))
    return buffer.getvalue()


#: stands for the steps in the summary's top level while :func:`summary_text` assembles it
_STEPS_SLOT = "\x00steps\x00"


def summary_text(summary: dict, step_texts: list[str] | None = None) -> str:
    """``summary.json``: ``json.dumps(summary, indent=2)`` and a newline. With ``step_texts``
    (each step's entry as ``json.dumps(entry)``, kept by a run as its steps come) the compact
    ``json.dumps(summary)`` instead, assembled without serialising the steps again: the summary a
    run rewrites after every step (:mod:`klaw_ocp.io.run_writer`; Python's JSON encoder is four
    times slower with an indent)."""
    if step_texts is None:
        try:
            return _indented(summary, "\n") + "\n"
        except _NotPlainJson:   # another type, a non-finite number: the json module's verdict
            return json.dumps(summary, indent=2, allow_nan=False) + "\n"
    text = json.dumps(dict(summary, steps=_STEPS_SLOT), allow_nan=False)
    return text.replace(json.dumps(_STEPS_SLOT), "[" + ", ".join(step_texts) + "]", 1) + "\n"


class _NotPlainJson(Exception):
    """A value :func:`_indented` leaves to the json module."""


_encode_str = json.encoder.encode_basestring_ascii


def _float_text(value: float) -> str:
    if not math.isfinite(value):
        raise _NotPlainJson
    return float.__repr__(value)


#: the text of a scalar of exactly these types (subclasses take the isinstance tests)
_SCALARS = {str: _encode_str, float: _float_text, int: int.__repr__, bool: lambda v: "true" if v else "false",
            type(None): lambda v: "null"}


def _indented(value, newline: str) -> str:
    """``json.dumps(value, indent=2)``, character for character, for dicts with string keys,
    lists, tuples, strings, numbers, booleans and None (anything else raises _NotPlainJson).
    Python's json module has no C encoder for indented output; its pure-Python one took 6 ms
    of the natural walk's 120 KB summary, this one 60 % of that (a type lookup per value, one
    join per container). ``newline``: a newline and the indent of ``value``'s own level."""
    scalar = _SCALARS.get(type(value))
    if scalar is not None:
        return scalar(value)
    inner = newline + "  "
    if isinstance(value, dict):
        if not value:
            return "{}"
        parts = []
        for key, item in value.items():
            if type(key) is not str:
                raise _NotPlainJson
            scalar = _SCALARS.get(type(item))
            parts.append(_encode_str(key) + ": " + (scalar(item) if scalar is not None else _indented(item, inner)))
        return "{" + inner + ("," + inner).join(parts) + newline + "}"
    if isinstance(value, (list, tuple)):
        if not value:
            return "[]"
        parts = [_indented(item, inner) for item in value]
        return "[" + inner + ("," + inner).join(parts) + newline + "]"
    if isinstance(value, str):
        return _encode_str(value)
    if isinstance(value, bool):   # before int: json writes True as true, not 1
        return "true" if value else "false"
    if isinstance(value, int):
        return int.__repr__(value)
    if isinstance(value, float):
        return _float_text(value)
    raise _NotPlainJson


def _render(summary: dict, table_csv: str) -> dict:
    text = summary_text(summary)
    return {"dynamics": ("dynamics.csv", table_csv.encode("utf-8")),
            "summary": ("summary.json", text.encode("utf-8")),
            "events": ("events.csv", events_csv(summary).encode("utf-8"))}


def write_rendered(files: dict, out_dir) -> dict:
    """Write rendered files (:func:`render_walk`) atomically into ``out_dir``; returns name -> path."""
    out = Path(out_dir)
    paths = {}
    for name, (filename, data) in files.items():
        paths[name] = out / filename
        atomic_write_bytes(paths[name], data)
    return paths


def write_walk(walk, out_dir, fps: float | None = None) -> dict:
    """Write every result file of ``walk`` (the angles at ``fps``) into ``out_dir``; returns name -> path."""
    return write_rendered(render_walk(walk, fps), out_dir)
