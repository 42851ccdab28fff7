"""The exception hierarchy of klaw_ocp.

Every error a user can cause or act on derives from :class:`KlawError`, so a caller (the CLI in
particular) can catch one type and print one line. Messages name the offending field, the value
received and what is allowed.
"""
from __future__ import annotations

import math
import numbers
import reprlib


class KlawError(Exception):
    """Base class of every error raised deliberately by klaw_ocp."""


class ConfigError(KlawError, ValueError):
    """A configuration value or API argument is malformed or out of its documented range."""


class GaitLimitError(ConfigError):
    """Locomotion parameters that are well-formed but outside the anatomical limits (section 3),
    or a walk outside the supported envelope (docs/envelope.md). A kind of :class:`ConfigError`:
    ``except ConfigError`` catches every input refused before solving."""


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


def finite_real(value) -> float | None:
    """``value`` as a float if it is a real number (not a bool) that a float holds finitely;
    else None (NaN, infinities, an int beyond 1.8e308, a string, None, ...)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return None
    try:
        value = float(value)
    except (OverflowError, ValueError, TypeError):
        return None
    return value if math.isfinite(value) else None


#: The longest value a message quotes (characters of its repr); longer ones are cut with "…".
MAX_QUOTED = 100

_REPR = reprlib.Repr()
_REPR.maxlevel, _REPR.maxdict, _REPR.maxlist, _REPR.maxtuple, _REPR.maxset = 3, 6, 6, 6, 6
_REPR.maxstring = _REPR.maxother = _REPR.maxlong = 4 * MAX_QUOTED   # reprlib cuts in the middle beyond


def short_repr(value, limit: int = MAX_QUOTED) -> str:
    """``repr(value)`` on one line, at most ``limit`` characters (cut with "…"), whatever the
    value: deeply nested, self-referencing or huge containers are abbreviated, never expanded."""
    try:
        text = _REPR.repr(value)
    except ValueError:  # an int too long to print (sys.get_int_max_str_digits)
        text = f"<an integer of {value.bit_length()} bits>" if isinstance(value, int) else f"<{type(value).__name__}>"
    except Exception:  # noqa: BLE001 - a value whose repr fails is still reported
        text = f"<{type(value).__name__}>"
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 1] + "…"


def out_of_range(field: str, value, allowed: str) -> str:
    """The one-line message format shared by every range check (the value quoted by
    :func:`short_repr`)."""
    return f"{field}: got {short_repr(value)}, allowed {allowed}"
