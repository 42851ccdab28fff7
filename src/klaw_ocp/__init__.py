"""klaw_ocp: the KLAW walking system (Bruderlin & Calvert, SIGGRAPH 1989) as optimal-control problems in CasADi."""
from .body import Body
from .errors import ConfigError, ConvergenceError, GaitLimitError, KlawError


def simulate_walk(spec, method=None, progress=False, raise_on_failure=True, on_step=None):
    """Run a walk (see :func:`klaw_ocp.walk.simulate_walk`); imported lazily to keep
    ``import klaw_ocp`` free of CasADi builds.

    Thread-safe: several threads may call it at once, each walk the walk it would be alone to
    the last bit, at no measurable cost to a walk (docs/limits.md, "Threads"). Threads do not
    make walks faster (most of a walk holds the GIL); processes do."""
    from .walk import simulate_walk as run
    return run(spec, method=method, progress=progress, raise_on_failure=raise_on_failure, on_step=on_step)


__all__ = ["Body", "KlawError", "ConfigError", "GaitLimitError", "ConvergenceError", "simulate_walk"]
__version__ = "0.1.0"
