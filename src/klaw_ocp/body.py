"""Anthropometry: Appendix B, Table B-1, of Bruderlin & Calvert (1989).

Lengths are fractions of body height, masses fractions of body mass. Centres of mass ``r_i`` are
measured from the proximal end of a segment, except ``r1`` (the whole leg), which is measured from
the distal end (the ankle), as the table's note says. Moments of inertia about the centre of mass
use the physically correct ``I_i = m_i * (gamma_i * l_i)**2`` (ERRATA section 5), not the printed
``m_i * (l_i * r_i)**2``, whose units are kg*m^4.

Table B-1 has no rows 7 and 10; those symbols do not exist in the model and are not provided.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .errors import ConfigError, finite_real, out_of_range

#: Gravitational acceleration, m/s^2 (the paper never states it; ERRATA "Conventions").
G = 9.81

#: Documented human ranges accepted for body height (m) and mass (kg): from small children to
#: the tallest and heaviest adults recorded in anthropometric surveys.
HEIGHT_RANGE_M = (0.8, 2.5)
MASS_RANGE_KG = (15.0, 250.0)

# Table B-1, relative values: (length, mass, centre of mass, radius of gyration).
_L = {0: 0.10059, 2: 0.47, 3: 0.23669, 4: 0.24556, 5: 0.0858, 6: 0.04734, 8: 0.02959,
      9: 0.03846, 11: 0.04853, 12: 0.08901, 13: 0.0496}
_M = {2: 0.678, 3: 0.1, 4: 0.061}
_R = {1: 0.553, 2: 0.5, 3: 0.433, 4: 0.606}
_GAMMA = {1: 0.326, 2: 0.496, 3: 0.323, 4: 0.416}

#: Order of the dynamic parameter vector handed to the CasADi models (see :meth:`Body.dynamic_parameters`).
DYNAMIC_PARAMETER_NAMES = ("m1", "m2", "m3", "m4", "l1", "l3", "l4",
                           "r1", "r2", "r3", "r4", "I1", "I2", "I3", "I4", "g")


def _derived(compute, doc: str = "") -> cached_property:
    """A quantity computed from height and mass on first use and kept: the models and the body's
    kinematics read them thousands of times a walk (a frozen Body never changes them)."""
    derived = cached_property(compute)
    derived.__doc__ = doc or None
    return derived


@dataclass(frozen=True)
class Body:
    """Absolute anthropometry of a human of the given height (m) and mass (kg).

    Attributes follow the paper's symbols: ``l0``..``l13`` (m, no ``l7``/``l10``), ``m1``..``m4``
    (kg), ``r1``..``r4`` (m), ``gamma1``..``gamma4`` (m, radii of gyration about the centre of mass),
    ``I1``..``I4`` (kg*m^2, about the centre of mass) and ``g`` (m/s^2).

    Segment 1 is the whole leg (thigh + shank, ``l1 = l3 + l4``), 2 the head-arms-trunk, 3 the
    thigh, 4 the shank. The swing leg's mass is not part of the stance model (assumption 4).
    """

    height: float
    mass: float
    g: float = field(default=G)

    def __post_init__(self) -> None:
        for name, value, (lo, hi), unit in (("height", self.height, HEIGHT_RANGE_M, "m"),
                                            ("mass", self.mass, MASS_RANGE_KG, "kg")):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or finite_real(value) is None:
                raise ConfigError(out_of_range(f"body.{name}", value, f"a finite number in {unit}"))
            if not lo <= value <= hi:
                raise ConfigError(out_of_range(f"body.{name}", value, f"{lo} to {hi} {unit}"))
        if not (isinstance(self.g, (int, float)) and self.g > 0):
            raise ConfigError(out_of_range("body.g", self.g, "a positive number in m/s^2"))

    # lengths (m)
    l0 = _derived(lambda s: _L[0] * s.height, doc="pelvis width")
    l2 = _derived(lambda s: _L[2] * s.height, doc="upper body (head-arms-trunk)")
    l3 = _derived(lambda s: _L[3] * s.height, doc="thigh")
    l4 = _derived(lambda s: _L[4] * s.height, doc="shank")
    l1 = _derived(lambda s: s.l3 + s.l4, doc="whole leg, hip to ankle, unloaded")
    l5 = _derived(lambda s: _L[5] * s.height, doc="mid foot")
    l6 = _derived(lambda s: _L[6] * s.height, doc="toe")
    l8 = _derived(lambda s: _L[8] * s.height, doc="hind foot: heel to the ankle's ground projection")
    l9 = _derived(lambda s: _L[9] * s.height, doc="ankle height above the foot base")
    l11 = _derived(lambda s: _L[11] * s.height, doc="heel to ankle distance")
    l12 = _derived(lambda s: _L[12] * s.height, doc="ankle to 1st metatarsal head distance")
    l13 = _derived(lambda s: _L[13] * s.height, doc="1st metatarsal head to toe tip distance")

    # masses (kg)
    m2 = _derived(lambda s: _M[2] * s.mass, doc="head-arms-trunk")
    m3 = _derived(lambda s: _M[3] * s.mass, doc="thigh")
    m4 = _derived(lambda s: _M[4] * s.mass, doc="shank (with foot)")
    m1 = _derived(lambda s: s.m3 + s.m4, doc="whole leg")

    # centres of mass (m); r1 from the ankle, the others from the proximal end
    r1 = _derived(lambda s: _R[1] * s.l1, doc="leg centre of mass, from the ankle")
    r2 = _derived(lambda s: _R[2] * s.l2, doc="upper-body centre of mass, from the hip")
    r3 = _derived(lambda s: _R[3] * s.l3, doc="thigh centre of mass, from the hip")
    r4 = _derived(lambda s: _R[4] * s.l4, doc="shank centre of mass, from the knee")

    # radii of gyration about the centre of mass (m)
    gamma1 = _derived(lambda s: _GAMMA[1] * s.l1)
    gamma2 = _derived(lambda s: _GAMMA[2] * s.l2)
    gamma3 = _derived(lambda s: _GAMMA[3] * s.l3)
    gamma4 = _derived(lambda s: _GAMMA[4] * s.l4)

    # moments of inertia about the centre of mass (kg m^2), ERRATA section 5
    I1 = _derived(lambda s: s.m1 * s.gamma1 ** 2)
    I2 = _derived(lambda s: s.m2 * s.gamma2 ** 2)
    I3 = _derived(lambda s: s.m3 * s.gamma3 ** 2)
    I4 = _derived(lambda s: s.m4 * s.gamma4 ** 2)

    @cached_property
    def metatarsal_reach(self) -> float:
        """How far ahead of the ankle the 1st metatarsal head lies with the foot flat (m):
        sqrt(l12² − l9²), l12 the ankle to the metatarsal head and l9 the ankle's height."""
        return math.sqrt(self.l12 ** 2 - self.l9 ** 2)

    @property
    def omega8(self) -> float:
        """Angle (rad) at the heel between the sole and the heel-ankle line: cos(omega8) = l8/l11 (eq. 3)."""
        return math.acos(min(1.0, self.l8 / self.l11))

    def dynamic_parameters(self) -> np.ndarray:
        """The parameter vector of the CasADi dynamics, in the order :data:`DYNAMIC_PARAMETER_NAMES`."""
        return np.array([getattr(self, n) for n in DYNAMIC_PARAMETER_NAMES], dtype=float)

    def as_dict(self) -> dict:
        """Every absolute quantity, by its paper symbol, for summaries and reports."""
        names = ["height", "mass", "g", "l0", "l1", "l2", "l3", "l4", "l5", "l6", "l8", "l9", "l11",
                 "l12", "l13", "m1", "m2", "m3", "m4", "r1", "r2", "r3", "r4", "I1", "I2", "I3", "I4"]
        return {n: float(getattr(self, n)) for n in names}
