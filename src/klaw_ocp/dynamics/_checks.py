"""Argument checks of the numeric dynamics API (section 2.3, Appendix A; numpy in, numpy out).

Every check raises :class:`klaw_ocp.errors.ConfigError` with the field name, the value received
and what is allowed; ``assert`` is not used because it vanishes under ``python -O``.
"""
from __future__ import annotations

import numpy as np

from ..body import Body
from ..errors import ConfigError, out_of_range


def check_body(body) -> Body:
    """``body`` must be a :class:`klaw_ocp.body.Body` (its parameters feed every model)."""
    if not isinstance(body, Body):
        raise ConfigError(out_of_range("body", type(body).__name__, "a klaw_ocp.body.Body"))
    return body


def as_vector(name: str, value, n: int) -> np.ndarray:
    """``value`` as a finite float array of shape ``(n,)``; a column ``(n, 1)`` is accepted too."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(out_of_range(name, value, f"{n} finite numbers")) from None
    if arr.shape == (n, 1):
        arr = arr[:, 0]
    if arr.shape != (n,):
        raise ConfigError(out_of_range(name, f"array of shape {arr.shape}", f"shape ({n},)"))
    if not np.isfinite(arr).all():
        raise ConfigError(out_of_range(name, arr.tolist(), f"{n} finite numbers"))
    return arr


def as_flag(name: str, value) -> float:
    """A lock flag: ``True``/``False`` or 0/1, returned as the number the CasADi models expect."""
    if isinstance(value, (bool, np.bool_)):
        return float(value)
    if isinstance(value, (int, float, np.integer, np.floating)) and value in (0, 1):
        return float(value)
    raise ConfigError(out_of_range(name, value, "True/False or 0/1"))


def as_scalar(name: str, value) -> float:
    """A finite real number."""
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise ConfigError(out_of_range(name, value, "a finite number")) from None
    if not np.isfinite(out):
        raise ConfigError(out_of_range(name, value, "a finite number"))
    return out


def choice(name: str, value, allowed: tuple) -> str:
    """``value`` must be one of ``allowed`` (the message lists them)."""
    if value not in allowed:
        raise ConfigError(out_of_range(name, value, "one of " + ", ".join(repr(a) for a in allowed)))
    return value


def to_numpy(dm) -> np.ndarray:
    """A CasADi DM (column) as a flat numpy array."""
    return np.asarray(dm, dtype=float).ravel()
