"""The body's stance legs compiled (body_motion/stance_kernel.py, issue #38): the numbers of the
virtual leg's numpy forms (pitch_rules.rule_pitch and virtual_leg.leg_frames, which the walk
itself uses) to round-off, at every sample the body asks for in walks across the envelope (the
rocker after heel strike, the heel rising, the meta-off band's roots, the double support, starts
from rest and stops), in more than one block of the kernel; CasADi's own evaluation the same."""
from dataclasses import replace

import numpy as np
import pytest

from klaw_ocp.body_motion import motion, stance_kernel, stance_legs
from klaw_ocp.body_motion.kernel_forms import mapped_library
from klaw_ocp.kinematics.leg_geometry import FlatFoot, meta_off_band
from klaw_ocp.kinematics.pitch_rules import RULE_FIELDS, rule_pitch
from klaw_ocp.kinematics.virtual_leg import leg_frames
from klaw_ocp.body import Body
from klaw_ocp.walk import simulate_walk

BODY = Body(height=1.8, mass=80.0)

POINTS = ("hip", "knee", "ankle", "heel", "metatarsal", "toe")
ANGLES = ("theta3", "theta4", "theta5", "theta6", "pitch", "overreach")
#: what the leg's inverse kinematics reads of a last-bit difference in the hip-ankle distance: a
#: few ulps (libm's functions against numpy's own, fused multiply-adds on other CPUs), taken as
#: up to 1e-14 m
DISTANCE_ROUND_OFF = 1e-14
#: the leg's angles and knee, which go as the square root of the distance's shortfall near the
#: straight leg, and the foot's θ5 = f(θ3 + θ4)
STRAIGHT_LEG_SENSITIVE = ("knee", "theta3", "theta4", "theta5")


def straight_leg_allowance(body, theta4) -> np.ndarray:
    """How far two roundings of the same leg's angles (rad) may lie apart at knee flexion
    ``theta4``: near a straight leg θ4² ≈ 2 l1 ε / (l3 l4) for a shortfall ε of the hip-ankle
    distance, so a difference Δd of it moves θ4 by up to sqrt(2 l1 Δd / (l3 l4)) (3e-7 rad), and
    by Δd l1 / (l3 l4 θ4) once bent (5e-13 at 0.1 rad): the lesser, plus 1e-12. Without it the
    comparison held or failed with the last bit of a straight leg's distance."""
    scale = body.l1 / (body.l3 * body.l4)
    theta4 = np.abs(np.asarray(theta4, float))
    with np.errstate(divide="ignore"):
        bent = np.where(theta4 > 0, DISTANCE_ROUND_OFF * scale / theta4, np.inf)
    return 1e-12 + np.minimum(np.sqrt(2 * scale * DISTANCE_ROUND_OFF), bent)


def assert_legs_close(got, want, tolerance: float = 1e-12):
    """The virtual legs ``got`` and ``want`` (VirtualLegFrames) to ``tolerance``, the angles and
    the knee a straight leg's inverse kinematics reads with its allowance (x l3 for the knee)."""
    body = BODY
    allowance = straight_leg_allowance(body, want.theta4)
    for name in POINTS + ANGLES:
        difference = np.abs(np.asarray(getattr(got, name)) - np.asarray(getattr(want, name)))
        if name in STRAIGHT_LEG_SENSITIVE:
            limit = allowance * (body.l3 if name == "knee" else 1.0) + tolerance
            assert (difference.T <= limit).all(), (name, difference.max())
        else:
            assert difference.max() < tolerance, name


def numpy_stance_frames(feet, which, t, hips):
    """The stances' virtual legs by the walk's own numpy forms (the body's form before the kernel)."""
    first = feet[0]
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
    return replace(legs, **{name: getattr(legs, name) + shift for name in POINTS})


@pytest.fixture(scope="module")
def asked():
    """Every stance_frames call the body makes for four short walks (slow, fast, from rest to rest)."""
    calls = []
    walks = [{"speed": 0.5, "steps": 5, "start_from_rest": True, "end_at_rest": True}, {"speed": 5.0, "steps": 4},
             {"speed": 9.0, "steps": 4}, {"speed": 3.0, "steps": 4, "start_from_rest": True}]
    original = stance_legs.stance_frames

    def spy(*args):
        calls.append(args)
        return original(*args)
    stance_legs.stance_frames = spy        # (ground_legs calls it: every stance of the walk at once)
    try:
        for walk in walks:
            motion.body_motion(simulate_walk({"name": "kernel", "body": {"height": 1.8, "mass": 80.0}, "walk": walk}), 100.0)
    finally:
        stance_legs.stance_frames = original
    return calls


def test_the_kernel_gives_the_walks_numpy_virtual_legs(asked):
    samples, in_band, blocks = 0, 0, 0
    for feet, which, t, hips in asked:
        want, got = numpy_stance_frames(feet, which, t, hips), stance_legs.stance_frames(feet, which, t, hips)
        assert_legs_close(got, want)
        assert np.array_equal(got.period, want.period) and np.array_equal(got.t, want.t)
        q = feet[0].meta_off_theta6
        samples += len(t)
        in_band += int((np.abs(want.pitch - q) < meta_off_band(q)).sum())
        blocks = max(blocks, -(-len(t) // stance_kernel.BLOCK))
    # what the comparison covered: the rocker, heels up, the band's roots, several blocks a call
    pitches = np.concatenate([numpy_stance_frames(*call).pitch for call in asked])
    assert (pitches < 0).sum() > 20 and (pitches > 0).sum() > 100 and in_band > 20 and blocks > 2, (samples, in_band)


def test_casadi_evaluation_gives_the_compiled_numbers(asked, monkeypatch):
    feet, which, t, hips = asked[len(asked) // 2]
    compiled = stance_legs.stance_frames(feet, which, t, hips)
    library = mapped_library(["test"], stance_kernel.sample_function, {"body_stance_block": stance_kernel.BLOCK})
    monkeypatch.setenv("KLAW_OCP_JIT", "0")
    monkeypatch.setattr(stance_legs, "stance_at", lambda rows, shared: _with(library, rows, shared))
    by_casadi = stance_legs.stance_frames(feet, which, t, hips)
    assert_legs_close(by_casadi, compiled, 1e-13)


def _with(library, rows, shared):
    kernel = library.functions()["body_stance_block"]
    assert type(kernel).__name__ == "CasadiFunction"
    original = stance_kernel._kernel
    stance_kernel._kernel = lambda: kernel
    try:
        return stance_kernel.stance_at(rows, shared)
    finally:
        stance_kernel._kernel = original
