"""``summary.json``: the summary of a run (:func:`klaw_ocp.results.walk_summary`) as JSON, indented
when the run is over, compact while it goes (:mod:`.run_writer` rewrites it after every step)."""
from __future__ import annotations

import json

#: stands for the steps in the summary's top level while :func:`summary_text` assembles it
_STEPS_SLOT = "\x00steps\x00"


def summary_text(summary: dict, step_texts: list[str] | None = None) -> str:
    """``summary.json``: ``json.dumps(summary, indent=2)`` and a newline. With ``step_texts``
    (each step's entry as ``json.dumps(entry)``, kept by a run as its steps come) the compact
    ``json.dumps(summary)`` instead, assembled without serialising the steps again: a run rewrites
    its summary after every step, and serialising every step each time would grow with the
    square of the walk's length."""
    if step_texts is None:
        return json.dumps(summary, indent=2, allow_nan=False) + "\n"
    text = json.dumps(dict(summary, steps=_STEPS_SLOT), allow_nan=False)
    return text.replace(json.dumps(_STEPS_SLOT), "[" + ", ".join(step_texts) + "]", 1) + "\n"


def summary_file(run) -> bytes:
    """summary.json of a :class:`~.run_data.RunData` (its registry renderer)."""
    return summary_text(run.summary).encode("utf-8")
