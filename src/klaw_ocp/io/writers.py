"""Result files of ``klaw-ocp run``, written atomically (temporary file, then rename).

- ``summary.json``: :func:`klaw_ocp.results.walk_summary`.
- ``dynamics.csv``: :func:`klaw_ocp.results.walk_table`, one row per time sample.
"""
from __future__ import annotations

import csv
import io
import json
import os
import tempfile
from pathlib import Path

from ..results import COLUMNS, walk_summary, walk_table


def atomic_write_text(path: Path, text: str) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as handle:
            handle.write(text)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def dynamics_csv(walk) -> str:
    table = walk_table(walk) if walk.steps else {c: [] for c in COLUMNS}
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(COLUMNS)
    for i in range(len(table["t"])):
        writer.writerow([table[c][i] if c == "subphase" else
                         (int(table[c][i]) if c == "step" else repr(float(table[c][i]))) for c in COLUMNS])
    return buffer.getvalue()


def write_walk(walk, out_dir) -> dict:
    """Write every result file of ``walk`` into ``out_dir``; returns name -> path."""
    out = Path(out_dir)
    paths = {"summary": out / "summary.json", "dynamics": out / "dynamics.csv"}
    atomic_write_text(paths["dynamics"], dynamics_csv(walk))
    atomic_write_text(paths["summary"], json.dumps(walk_summary(walk), indent=2, allow_nan=False) + "\n")
    return paths
