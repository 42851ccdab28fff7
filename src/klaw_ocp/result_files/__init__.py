"""A run's result files and its results folder: the registry that names every file
(:mod:`.registry`), atomic writes (:mod:`.atomic`), the formats (:mod:`.tables`,
:mod:`.summary_json`, :mod:`.bvh`, :mod:`.opensim`), a finished run read back (:mod:`.run_data`),
the step-by-step writer (:mod:`.run_writer`) and the folder staging (:mod:`.results_folder`).
The plots and walk.gif are :mod:`klaw_ocp.figures`'.

They read results and never drive a solve. The names below are imported on first use, so that
``klaw_ocp.result_files.registry`` stays light (no CasADi, no matplotlib) for ``klaw-ocp run``."""
from __future__ import annotations

#: public name -> the module that defines it
_PUBLIC = {"RunData": "run_data", "atomic_write_bytes": "atomic", "atomic_write_text": "atomic",
           "write_rendered": "atomic", "render_run": "render", "render_walk": "render", "write_walk": "render"}

__all__ = sorted(_PUBLIC)


def __getattr__(name: str):
    if name not in _PUBLIC:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from importlib import import_module
    return getattr(import_module(f"{__name__}.{_PUBLIC[name]}"), name)
