"""klaw_ocp: the KLAW walking system (Bruderlin & Calvert, SIGGRAPH 1989) as optimal-control problems in CasADi."""
from .body import Body
from .errors import ConfigError, ConvergenceError, GaitLimitError, KlawError

__all__ = ["Body", "KlawError", "ConfigError", "GaitLimitError", "ConvergenceError"]
__version__ = "0.1.0"
