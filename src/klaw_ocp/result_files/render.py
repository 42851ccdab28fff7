"""A run's text files rendered in memory, every one the registry lists (:data:`.registry.RUN_FILES`
with ``made_by`` TEXT), and written atomically. Rendering is separate from writing so that the
benchmark can time the two, and a failure to render writes nothing."""
from __future__ import annotations

from .atomic import write_rendered
from .registry import RUN_FILES, TEXT, load


def render_run(run, keys=None) -> dict:
    """The text files of a :class:`~.run_data.RunData` (those of ``keys``, default all) as
    key -> (file name, bytes), in the registry's order; the body's files only when the run has
    angles with a frame."""
    body = run.angles is not None and len(run.angles["time"]) > 0
    return {f.key: (f.name, load(f.renderer)(run)) for f in RUN_FILES.values()
            if f.made_by == TEXT and (keys is None or f.key in keys) and (body or not f.body)}


def body_keys() -> list:
    """The keys of the body's text files (written when the whole walk is known)."""
    return [f.key for f in RUN_FILES.values() if f.made_by == TEXT and f.body]


def render_walk(walk, fps: float | None = None) -> dict:
    """Every text file of ``walk`` in memory, the body's angles at ``fps`` frames per second
    (default: the walk's own, output.fps): key -> (file name, bytes)."""
    from .run_data import RunData
    return render_run(RunData.from_walk(walk, fps=fps))


def write_walk(walk, out_dir, fps: float | None = None) -> dict:
    """Write every text file of ``walk`` (the angles at ``fps``, default the walk's) into
    ``out_dir``; returns key -> path."""
    return write_rendered(render_walk(walk, fps), out_dir)
