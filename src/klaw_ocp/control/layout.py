"""Named vectors: how the numeric context of a subphase maps onto a CasADi parameter vector.

A subphase Function is built once with a symbolic context vector ``c``; each step packs its own
numbers into it. Keeping the names in one place documents the layout and catches a missing value
(a KeyError names it) instead of silently shifting entries.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np


class VectorLayout:
    """An ordered list of names for the entries of a vector."""

    def __init__(self, *groups):
        names: list[str] = []
        for group in groups:
            names.extend(group.names if isinstance(group, VectorLayout) else group)
        if len(set(names)) != len(names):
            raise ValueError(f"duplicate names in layout: {names}")
        self.names = tuple(names)
        self.index = {n: i for i, n in enumerate(self.names)}

    def __len__(self) -> int:
        return len(self.names)

    def bind(self, vector) -> SimpleNamespace:
        """Name the entries of a (symbolic) vector laid out this way: ``layout.bind(c).t_step``."""
        return SimpleNamespace(**{n: vector[i] for i, n in enumerate(self.names)})

    def pack(self, values: dict) -> np.ndarray:
        missing = [n for n in self.names if n not in values]
        if missing:
            raise KeyError(f"missing values for {missing}")
        return np.array([float(values[n]) for n in self.names])
