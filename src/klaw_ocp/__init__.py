"""klaw_ocp: the KLAW walking system (Bruderlin & Calvert, SIGGRAPH 1989) as optimal-control problems in CasADi."""
from .body import Body
from .errors import ConfigError, ConvergenceError, GaitLimitError, KlawError


def simulate_walk(spec, method=None, progress=False, raise_on_failure=True, on_step=None):
    """Run a walk (see :func:`klaw_ocp.walk.simulate_walk`); imported lazily to keep
    ``import klaw_ocp`` free of CasADi builds."""
    from .walk import simulate_walk as run
    return run(spec, method=method, progress=progress, raise_on_failure=raise_on_failure, on_step=on_step)


__all__ = ["Body", "KlawError", "ConfigError", "GaitLimitError", "ConvergenceError", "simulate_walk"]
__version__ = "0.1.0"
