"""Writers of result files. They read results and never drive a solve (STYLE.md)."""
from .writers import render_walk, write_rendered, write_walk

__all__ = ["render_walk", "write_rendered", "write_walk"]
