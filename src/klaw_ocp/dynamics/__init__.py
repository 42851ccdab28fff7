"""Low level: the Lagrangian stance and swing models (section 2.3, Appendix A), their locked
variants (section 4.2, eq. 5), hip kinematics, the models' points (their forward kinematics,
:mod:`.points`), the heel-strike map (section 4) and the lock maps.

Symbolic builders (``*_sx``, ``*_functions``) are for the solvers; the numpy functions are the
public numeric API. docs/paper-map.md maps each paper item to its function.
"""
from .api import (hip_kinematics, stance_accelerations, stance_bias, stance_energy, stance_mass_matrix,
                  swing_accelerations, swing_bias, swing_energy, swing_mass_matrix)
from .impacts import (CONSERVED, LOCK_RULES, NOT_CONSERVED, heel_strike_conserved, heel_strike_map,
                      heel_strike_map_sx, impact_functions, knee_lock_map, momentum_lock_sx,
                      stance_lock_map)
from .points import (foot_points, foot_points_float, foot_points_sx, stance_hip, stance_hips, swing_leg_points,
                     upper_body_com)
from .stance import (apply_lock, hip_kinematics_sx, stance_accelerations_sx, stance_energies,
                     stance_functions, stance_mass_bias, stance_points)
from .swing import swing_accelerations_sx, swing_energies, swing_functions, swing_mass_bias, swing_points

__all__ = [
    # numeric API
    "stance_accelerations", "swing_accelerations", "stance_mass_matrix", "swing_mass_matrix",
    "stance_bias", "swing_bias", "stance_energy", "swing_energy", "hip_kinematics",
    # impacts
    "heel_strike_map", "heel_strike_conserved", "stance_lock_map", "knee_lock_map",
    "heel_strike_map_sx", "momentum_lock_sx", "impact_functions", "LOCK_RULES", "CONSERVED",
    "NOT_CONSERVED",
    # the models' points
    "foot_points", "foot_points_float", "foot_points_sx", "swing_leg_points", "stance_hip", "stance_hips",
    "upper_body_com",
    # symbolic models
    "stance_functions", "swing_functions", "stance_accelerations_sx", "swing_accelerations_sx",
    "hip_kinematics_sx", "apply_lock", "stance_mass_bias", "swing_mass_bias", "stance_energies",
    "swing_energies", "stance_points", "swing_points",
]
