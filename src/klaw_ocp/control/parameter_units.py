"""The unit of every torque-profile parameter a subphase solves for (section 4, the paper's
torque shapes), so that results, comparisons and plots can name them without knowing the laws.

Stance (control/stance_law.py): the F_theta1 step magnitude, the pa offset of the late extension,
the closing step's braking level and, in the tracking formulation, the pa profile's knots.
Swing (control/swing_spec.py): swing1's F_theta3 fall and mean, swing2's F_theta4 fall and mean and the
recovery loop's hip actuator (a shift of the held thigh angle), in a closing step instead the
coefficients a, b of the hip torque a s + b s² added to the hold, swing3's constant hip moment.
"""
from __future__ import annotations

from .stance_law import PA_KNOTS

PARAMETER_UNITS: dict[str, str] = {
    "F_theta1_magnitude": "N m",
    "pa_offset": "m",
    "F_theta1_brake": "N m",
    **{knot: "m" for knot in PA_KNOTS},
    "F_theta3_fall": "N m",
    "F_theta3_mean": "N m",
    "F_theta4_fall": "N m",
    "F_theta4_mean": "N m",
    "hip_actuator": "rad",
    "F_theta3_linear": "N m",
    "F_theta3_quadratic": "N m",
    "F_theta3_moment": "N m",
}


def parameter_unit(name: str) -> str:
    """The unit of a subphase parameter ("" for a name this table does not know)."""
    return PARAMETER_UNITS.get(name, "")
