"""The virtual legs (:mod:`klaw_ocp.kinematics.virtual_leg`) of many stances of one walk evaluated
together: the body (:mod:`.motion`) needs every stance of a walk at its frames, and one
:meth:`StanceFoot.frames` call per stance costs mostly its fixed overhead (about 0.7 ms, with a few
dozen frames each)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..kinematics.leg_geometry import FlatFoot
from ..kinematics.pitch_rules import RULE_FIELDS, rule_pitch
from ..kinematics.virtual_leg import VirtualLegFrames, leg_frames


def stance_frames(feet, which: np.ndarray, t: np.ndarray, hips: np.ndarray) -> VirtualLegFrames:
    """:meth:`StanceFoot.frames` of many stances of one body in one vectorised pass (the body's
    frames: one call instead of one per stance, whose fixed cost is most of it): sample i is the
    stance ``feet[which[i]]`` at its stance time ``t[i]`` with the hip ``hips[i]``. The foot's
    geometry does not depend on where it stands, so every sample is taken to its own foot's
    frame (ankle at x = 0) and back."""
    first = feet[0]
    shared = (first.foot.body, first.heel_off_theta5, first.meta_off_theta6)
    if any((f.foot.body, f.heel_off_theta5, f.meta_off_theta6) != shared for f in feet):
        raise ValueError("feet: the stances must share the body and the heel-off and meta-off limits")
    which, t = np.asarray(which), np.asarray(t, float)
    # each sample's stance: its rules, ankle x and rocker toe angle, one table row a stance
    table = np.array([[getattr(f, name) for name in RULE_FIELDS] + [f.foot.ankle_x, f.rocker_theta6] for f in feet],
                     float)[which].T
    shift = np.zeros((len(t), 2))
    shift[:, 0] = table[-2]
    local = np.asarray(hips, float) - shift
    geometry = replace(first, foot=FlatFoot(first.foot.body, 0.0))
    rules = dict(zip(RULE_FIELDS, table))

    def deficit(t, rows):
        kept, stance = np.zeros(int(rows.sum())), which[rows]
        for k in np.unique(stance):
            if feet[k].single_t and any(feet[k].single_deficit):
                mine = stance == k
                kept[mine] = np.interp(t[rows][mine], feet[k].single_t, feet[k].single_deficit, right=0.0)
        return kept
    pitch, fraction = rule_pitch(rules, t, local, geometry, deficit)
    legs = leg_frames(geometry, t, local, pitch, fraction, table[-1], rules["t_flat"])
    moved = {name: getattr(legs, name) + shift for name in ("hip", "knee", "ankle", "heel", "metatarsal", "toe")}
    return replace(legs, **moved)
