"""The exception hierarchy of klaw_ocp.

Every error a user can cause or act on derives from :class:`KlawError`, so a caller (the CLI in
particular) can catch one type and print one line. Messages name the offending field, the value
received and what is allowed.
"""
from __future__ import annotations


class KlawError(Exception):
    """Base class of every error raised deliberately by klaw_ocp."""


class ConfigError(KlawError, ValueError):
    """A configuration value or API argument is malformed or out of its documented range."""


class GaitLimitError(KlawError, ValueError):
    """Locomotion parameters that are well-formed but outside the anatomical limits (section 3)."""


class ConvergenceError(KlawError, RuntimeError):
    """A subphase boundary-value problem did not meet its final conditions.

    Carries the step index, the subphase name and the residual so that a caller can report them
    and keep the steps completed before it.
    """

    def __init__(self, step: int, subphase: str, residual: float, detail: str = "", partial=None):
        self.step = step
        self.subphase = subphase
        self.residual = residual
        self.detail = detail
        self.partial = partial
        msg = f"step {step}, subphase {subphase!r}: did not converge (residual {residual:.3g})"
        if detail:
            msg += f": {detail}"
        super().__init__(msg)


def out_of_range(field: str, value, allowed: str) -> str:
    """The one-line message format shared by every range check."""
    return f"{field}: got {value!r}, allowed {allowed}"
