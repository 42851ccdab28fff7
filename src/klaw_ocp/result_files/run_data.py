"""A finished run as plots, comparisons and writers read it: its summary and its sample table.

:class:`RunData` is built either from a simulated :class:`~klaw_ocp.walk.Walk` in memory
(:meth:`RunData.from_walk`) or from a results folder that ``klaw-ocp run`` wrote
(:meth:`RunData.from_folder`: its summary, sample table and angles, :mod:`.registry`). Both give the same object,
so ``klaw-ocp plot DIR`` redraws a finished run and ``klaw-ocp compare`` reads old ones without
solving anything. Nothing here imports a solver.

``table`` maps every column of ``dynamics.csv`` (:data:`klaw_ocp.results.COLUMNS`) to an array
(``subphase`` an array of str, ``step`` of int); ``summary`` is the dict of ``summary.json``
(:func:`klaw_ocp.results.walk_summary`); ``angles`` every column of ``angles.csv`` (the body at
every frame: time, root, the 56 angles in degrees, :meth:`klaw_ocp.body_motion.BodyMotion.table`),
or None for a results folder written before the body was; ``fps`` the frames per second of the
body's files (``output.fps``, which summary.json records), so that walk.bvh is written at the rate
the run was, never one guessed from the frame times.
"""
from __future__ import annotations

import csv
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..body import Body
from ..errors import ConfigError
from .registry import RUN_FILES

SUMMARY_FILE, DYNAMICS_FILE, ANGLES_FILE, RESOLVED_FILE = (RUN_FILES[k].name for k in
                                                           ("summary", "dynamics", "angles", "resolved"))
#: a folder written before summary.json recorded its fps and before config.resolved.yaml was: 30
#: fps, the only rate there was (output.fps came after config.resolved.yaml)
_OLD_FPS = 30.0
_TEXT_COLUMNS = ("subphase",)
_INT_COLUMNS = ("step",)


@dataclass
class RunData:
    """One run's results: ``name`` (a label), ``summary``, ``table``, ``angles``, ``fps`` (the
    frames per second of ``angles``) and, when read from disk, ``folder``."""
    name: str
    summary: dict
    table: dict
    folder: Path | None = None
    extra: dict = field(default_factory=dict)
    angles: dict | None = None
    fps: float | None = None

    # -- construction ----------------------------------------------------------------------------
    @classmethod
    def from_walk(cls, walk, table: dict | None = None, summary: dict | None = None,
                  fps: float | None = None) -> "RunData":
        """The results of a walk in memory (``table``/``summary``: when the caller has them
        already), the body's angles at ``fps`` frames per second (default: the walk's own,
        ``output.fps`` of its config)."""
        from ..body_motion import ANGLES_COLUMNS, body_motion
        from ..results import hip_offsets, walk_summary, walk_table
        # the hips of every node, once for the table and the summary
        offsets = hip_offsets(walk) if walk.steps and (table is None or summary is None) else None
        if table is None:
            table = walk_table(walk, offsets) if walk.steps else _empty_table()
        if summary is None:
            summary = walk_summary(walk, table, offsets=offsets)
        fps = walk.spec.fps if fps is None else fps
        angles = (body_motion(walk, fps).table() if walk.steps
                  else {c: np.array([]) for c in ANGLES_COLUMNS})
        return cls(name=walk.spec.name, summary=summary, table=table, angles=angles, fps=fps)

    @classmethod
    def from_folder(cls, folder, what: str = "results folder") -> "RunData":
        """Read ``summary.json``, ``dynamics.csv`` and, if there is one, ``angles.csv`` of a
        finished run; one-line ConfigError if ``folder`` is not one (``what`` names the argument
        in that message)."""
        folder = Path(folder)
        summary_path, table_path = folder / SUMMARY_FILE, folder / DYNAMICS_FILE
        if not folder.is_dir() or not summary_path.is_file() or not table_path.is_file():
            raise ConfigError(f"{what}: got {str(folder)!r}, allowed a folder written by klaw-ocp run "
                              f"(with {SUMMARY_FILE} and {DYNAMICS_FILE})")
        try:
            summary = json.loads(summary_path.read_text(encoding="utf-8"))
            table = read_table(table_path)
            angles = read_table(folder / ANGLES_FILE) if (folder / ANGLES_FILE).is_file() else None
        except (OSError, UnicodeDecodeError, ValueError, KeyError) as exc:
            raise ConfigError(f"{what}: got {str(folder)!r} whose result files cannot be read "
                              f"({type(exc).__name__}: {' '.join(str(exc).split())[:120]}), allowed files "
                              f"written by klaw-ocp run") from None
        if not isinstance(summary, dict) or "steps" not in summary or "body" not in summary:
            raise ConfigError(f"{what}: got {str(summary_path)!r} without steps and body, allowed a "
                              f"{SUMMARY_FILE} written by klaw-ocp run")
        return cls(name=str(summary.get("name", folder.name)), summary=summary, table=table, folder=folder,
                   angles=angles, fps=_folder_fps(folder, summary))

    # -- views -----------------------------------------------------------------------------------
    @property
    def steps(self) -> list[dict]:
        return self.summary["steps"]

    @property
    def body(self) -> dict:
        return self.summary["body"]

    def body_model(self) -> Body:
        """The walker's :class:`~klaw_ocp.body.Body`, rebuilt from the summary's height and mass
        (the rest of the summary's body is derived from them)."""
        return Body(height=self.body["height"], mass=self.body["mass"])

    @property
    def method(self) -> str:
        return str(self.summary.get("method", ""))

    @property
    def stance(self) -> str:
        return str((self.summary.get("solver") or {}).get("stance", "monitored"))

    @property
    def label(self) -> str:
        """``name (method, stance)``: how a legend or table names this run."""
        return f"{self.name} ({self.method}, {self.stance} stance)"

    @property
    def duration(self) -> float:
        steps = self.steps
        return steps[-1]["t_start_s"] + steps[-1]["t_step_s"] - steps[0]["t_start_s"] if steps else 0.0


def _folder_fps(folder: Path, summary: dict) -> float:
    """The frames per second a results folder was written at: summary.json's ``fps``, else (a
    folder written before it recorded it) config.resolved.yaml's ``output.fps``, else 30."""
    fps = summary.get("fps")
    if fps is None and (folder / RESOLVED_FILE).is_file():
        import yaml
        try:
            resolved = yaml.safe_load((folder / RESOLVED_FILE).read_text(encoding="utf-8"))
            fps = resolved["output"]["fps"]
        except (OSError, UnicodeDecodeError, yaml.YAMLError, KeyError, TypeError):
            fps = None
    return float(fps) if isinstance(fps, (int, float)) and not isinstance(fps, bool) and fps > 0 else _OLD_FPS


def _empty_table() -> dict:
    from ..results import COLUMNS
    return {c: np.array([], dtype=str if c in _TEXT_COLUMNS else float) for c in COLUMNS}


def read_table(path) -> dict:
    """``dynamics.csv`` or ``angles.csv`` -> column name -> array (float; ``subphase`` str;
    ``step`` int)."""
    with open(path, newline="", encoding="utf-8") as handle:
        reader = csv.reader(handle)
        header = next(reader)
        rows = list(reader)
    columns = list(zip(*rows)) if rows else [()] * len(header)
    table = {}
    for name, values in zip(header, columns):
        if name in _TEXT_COLUMNS:
            table[name] = np.array(values, dtype=str)
        elif name in _INT_COLUMNS:
            table[name] = np.array([int(v) for v in values], dtype=int)
        else:
            table[name] = np.array([float(v) for v in values], dtype=float)
    return table
