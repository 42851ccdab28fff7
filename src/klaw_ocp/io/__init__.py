"""Writers of result files. They read results and never drive a solve (STYLE.md)."""
from .writers import write_walk

__all__ = ["write_walk"]
