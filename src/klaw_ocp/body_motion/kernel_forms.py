"""The forms the body's compiled kernels share, on CasADi symbols (:mod:`.leg_angles`,
:mod:`.stance_kernel`, :mod:`.swing_kernel`): each is the numpy form it names, the same operations
in the same order, every branch taken per sample (``if_else``), and the mapping of a sample's
function over a block of samples, compiled and cached as the solvers' kernels are."""
from __future__ import annotations

import math
import sys

import casadi as ca
import numpy as np

from ..kernels import KernelLibrary, source_key

TWO_PI = 2 * math.pi


def mod(a, b):
    """numpy's ``np.mod`` for b > 0: C's fmod moved into [0, b)."""
    m = ca.fmod(a, b)
    return ca.if_else(m < 0, m + b, m)


def round_half_even(x):
    """numpy's ``np.round`` (ties to even)."""
    r = ca.floor(x + 0.5)
    return ca.if_else(ca.logic_and(r - x == 0.5, ca.fmod(r, 2) != 0), r - 1, r)


def clamp(x, lo, hi):
    """:func:`klaw_ocp.kinematics.leg_geometry.clamp`."""
    return ca.fmin(ca.fmax(x, lo), hi)


def smoothstep(u):
    """:func:`klaw_ocp.kinematics.leg_geometry.smoothstep`."""
    u = clamp(u, 0.0, 1.0)
    return u * u * (3 - 2 * u)


def _root(v):
    return ca.sqrt(ca.fmax(v, 0.0))


def leg_ik(l3, l4, hip_x, hip_y, ankle_x, ankle_y) -> tuple:
    """:func:`klaw_ocp.kinematics.leg_geometry.leg_ik` of one sample: (θ3, θ4, knee x, knee y,
    the hip-ankle distance before its clip to l1)."""
    dx, dy = ankle_x - hip_x, ankle_y - hip_y
    distance = ca.hypot(dx, dy)
    d = ca.fmin(distance, l3 + l4)
    half, short = (l3 + l4 + d) / 2, (l3 + l4 - d) / 2
    s3, s4 = half - l3, half - l4
    theta3 = ca.atan2(-dx, -dy) - 2 * ca.atan2(_root(s3 * short), _root(half * s4))
    theta4 = 2 * ca.atan2(_root(half * short), _root(s3 * s4))
    return theta3, theta4, hip_x - l3 * ca.sin(theta3), hip_y - l3 * ca.cos(theta3), distance


def knee_flexion_for_reach(l3, l4, d):
    """:func:`klaw_ocp.kinematics.leg_geometry.knee_flexion_for_reach` of one distance."""
    d = ca.fmin(d, l3 + l4)
    half = (l3 + l4 + d) / 2
    return 2 * ca.atan2(ca.sqrt(ca.fmax(half * (l3 + l4 - d) / 2, 0.0)),
                        ca.sqrt(ca.fmax((half - l3) * (half - l4), 0.0)))


def mapped_library(key_parts, sample, blocks: dict) -> KernelLibrary:
    """A library of ``sample`` (a CasADi Function of (row, constants)) mapped over each block size
    of ``blocks`` (name -> samples: a loop in the generated C), the constants shared, its outputs
    stacked in one column a sample (:func:`evaluate` names them again: one array crosses the call,
    not one per output)."""
    def build(compiling: bool) -> list:
        fn = sample()
        # the subexpressions the forms repeat (a schedule asked for twice, a hypot of the same
        # difference) computed once: the same numbers, a fifth fewer instructions
        stacked = ca.Function(fn.name(), fn.sx_in(), [ca.cse(ca.vertcat(*fn(*fn.sx_in())))], fn.name_in(), ["out"])
        functions = []
        for name, size in blocks.items():
            args = [ca.MX.sym("rows", fn.numel_in(0), size), ca.MX.sym("constants", fn.numel_in(1))]
            functions.append(ca.Function(name, args, [stacked.map(size, "serial")(*args)], fn.name_in(), ["out"]))
        return functions
    # (this module's code builds them too: its source is part of every key)
    return KernelLibrary([source_key(sys.modules[__name__]), *key_parts, tuple(blocks.items())], list(blocks), build,
                         what="body kernel")


def evaluate(kernel, block: int, rows: np.ndarray, constants: np.ndarray, outputs: dict) -> dict:
    """``kernel`` (a block of ``block`` samples, :func:`mapped_library`'s) over n rows (n, columns),
    the last block filled with copies of the first row (any valid one) -> output name (``outputs``:
    name -> size, in the sample function's order) -> (n,) or (n, size), views of one array."""
    n, width = len(rows), sum(outputs.values())
    blocks = -(-n // block)
    if blocks * block != n:
        padded = np.empty((blocks * block, rows.shape[1]))
        padded[:n], padded[n:] = rows, rows[0]       # (np.broadcast_to's Python checks cost more)
        rows = padded
    out = [kernel(rows[b * block:(b + 1) * block], constants)[0].reshape(block, width) for b in range(blocks)]
    out = (np.concatenate(out) if len(out) > 1 else out[0])[:n] if out else np.zeros((0, width))
    columns, start = {}, 0
    for name, size in outputs.items():
        columns[name] = out[:, start] if size == 1 else out[:, start:start + size]
        start += size
    return columns
