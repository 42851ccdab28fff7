"""The symbolic body-parameter vector shared by every CasADi model.

The body enters the models as a parameter, so one compiled Function serves every height and mass
(the order is :data:`klaw_ocp.body.DYNAMIC_PARAMETER_NAMES`).
"""
from __future__ import annotations

from types import SimpleNamespace

import casadi as ca

from ..body import DYNAMIC_PARAMETER_NAMES

N_BODY_PARAMETERS = len(DYNAMIC_PARAMETER_NAMES)


def body_symbols(p: ca.SX) -> SimpleNamespace:
    """Name the entries of an SX parameter vector ``p`` by their paper symbols (``s.m1``, ``s.g``...)."""
    if p.numel() != N_BODY_PARAMETERS:
        raise ValueError(f"body parameter vector must have {N_BODY_PARAMETERS} entries, got {p.numel()}")
    return SimpleNamespace(**{name: p[i] for i, name in enumerate(DYNAMIC_PARAMETER_NAMES)})
