"""Readers and writers of result files, and the plots. They read results and never drive a
solve; matplotlib is imported only by the plotting modules, on first use."""
from .run_data import RunData
from .writers import atomic_write_bytes, atomic_write_text, render_run, render_walk, write_rendered, write_walk

__all__ = ["RunData", "atomic_write_bytes", "atomic_write_text", "render_run", "render_walk", "write_rendered",
           "write_walk"]
