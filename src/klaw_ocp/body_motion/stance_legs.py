"""The virtual legs (:mod:`klaw_ocp.kinematics.virtual_leg`) of many stances of one walk evaluated
together: the body (:mod:`.motion`) needs every stance of a walk at its frames, and one
:meth:`StanceFoot.frames` call per stance costs mostly its fixed overhead (about 0.7 ms, with a few
dozen frames each); all of them in one pass of numpy cost some 250 array operations, so the pass
is compiled (:mod:`.stance_kernel`)."""
from __future__ import annotations

import numpy as np

from ..kinematics.pitch_rules import RULE_FIELDS
from ..kinematics.virtual_leg import VirtualLegFrames, leg_periods
from .stance_kernel import COLUMNS, constants, stance_at

_RULES = [COLUMNS.index(name) for name in RULE_FIELDS] + [COLUMNS.index(name) for name in ("rocker_theta6", "ankle_x")]
_T, _HIPS, _DEFICIT = COLUMNS.index("t"), [COLUMNS.index("hip_x"), COLUMNS.index("hip_y")], COLUMNS.index("deficit")


def stance_frames(feet, which: np.ndarray, t: np.ndarray, hips: np.ndarray) -> VirtualLegFrames:
    """:meth:`StanceFoot.frames` of many stances of one body in one pass (the body's frames: one
    call instead of one per stance, whose fixed cost is most of it): sample i is the stance
    ``feet[which[i]]`` at its stance time ``t[i]`` with the hip ``hips[i]``. The foot's geometry
    does not depend on where it stands, so every sample is taken to its own foot's frame (ankle at
    x = 0) and back."""
    first = feet[0]
    shared = (first.foot.body, first.heel_off_theta5, first.meta_off_theta6)
    if any((f.foot.body, f.heel_off_theta5, f.meta_off_theta6) != shared for f in feet):
        raise ValueError("feet: the stances must share the body and the heel-off and meta-off limits")
    which, t = np.asarray(which), np.asarray(t, float)
    rows = np.empty((len(t), len(COLUMNS)))
    # each sample's stance: its rules, rocker toe angle and ankle x, one table row a stance
    rows[:, _RULES] = np.array([[getattr(f, name) for name in RULE_FIELDS] + [f.rocker_theta6, f.foot.ankle_x]
                                for f in feet], float)[which]
    rows[:, _T], rows[:, _HIPS] = t, hips
    # what single support adds to the rules' pitch so that the heel never comes down again
    # (StanceFoot.find_heel_off), at every sample of a stance that has it (the kernel adds it in
    # single support only)
    deficit = rows[:, _DEFICIT]
    deficit[:] = 0.0
    for k in np.unique(which):
        if feet[k].single_t and any(feet[k].single_deficit):
            mine = which == k
            deficit[mine] = np.interp(t[mine], feet[k].single_t, feet[k].single_deficit, right=0.0)
    legs = stance_at(rows, constants(first.foot.body, first.meta_off_theta6))
    pitch = legs["pitch"]
    return VirtualLegFrames(t, legs["hip"], legs["knee"], legs["ankle"], legs["heel"], legs["metatarsal"], legs["toe"],
                            legs["theta3"], legs["theta4"], legs["theta5"], legs["theta6"], pitch,
                            leg_periods(pitch, first.meta_off_theta6), legs["overreach"])
