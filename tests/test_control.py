"""Unit tests of ``klaw_ocp.control``: the torque shapes, curve P, the swing1 end posture, the gains.

Walks exercise these only as a whole; here each is held against its written definition, with
values worked out by hand or recomputed with independent geometry:

- torque shapes (§4.2, §4.3; ERRATA 7 and 8): the F_theta1 step, the decaying exponential, the
  spring-damper with its position actuator, and how the stance and swing laws combine them;
- curve P (§4.3): the five conditions y(0) = a0, y(C) = a_max, y'(C) = 0, y(D) = a_min,
  y'(D) = 0, and the swing1 knee law that keeps the ankle on it;
- the swing1 end posture (§4.3): the toe directly under the knee, clear of the ground;
- the spring and damping constants, k = m_eff (2 pi f)^2 and d = 2 zeta m_eff (2 pi f).
"""
import math

import casadi as ca
import numpy as np
import pytest
from hypothesis import example, given, settings, strategies as st

from klaw_ocp.body import Body
from klaw_ocp.control import curve_p as ds
from klaw_ocp.control.gains import control_gains
from klaw_ocp.control.step import body_context
from klaw_ocp.control.stance_law import PA_KNOTS, STANCE_CONTEXT, STANCE_PARAMETERS, stance_forces
from klaw_ocp.control.swing_law import (RETRACTION_START_SHARE, SWING_CONTEXT, curve_p, swing1_forces, swing1_rhs, swing2_torques,
                                        swing3_torque)
from klaw_ocp.control.torques import (decaying_exponential, hip_height_reference, leg_force, spring_damper,
                                      step_torque)
from klaw_ocp.dynamics.points import foot_points_float
from klaw_ocp.gait import LocomotionAttributes

BODY = Body(1.8, 80)
ATTRS = LocomotionAttributes.defaults()
FAST = settings(max_examples=60, deadline=None)


def unit(angle):
    """(sin a, cos a): the direction of a segment at angle a from the vertical (ERRATA conventions)."""
    return np.array([math.sin(angle), math.cos(angle)])


def as_function(law, *sizes):
    """A numeric CasADi Function of a symbolic law, so that the SX path the solvers use is tested."""
    syms = [ca.SX.sym(f"a{i}", n) for i, n in enumerate(sizes)]
    out = law(*syms)
    outs = list(out) if isinstance(out, tuple) else [out]
    f = ca.Function("law", syms, outs)
    return lambda *args: [np.asarray(v, float).ravel() for v in f.call([ca.DM(a) for a in args])]


# -- torque shapes ------------------------------------------------------------------------------

def test_step_torque_is_on_before_t_off_and_off_from_t_off():
    sx = as_function(step_torque, 1, 1, 1)
    for t, expected in ((0.0, 25.0), (0.239, 25.0), (0.24, 0.0), (0.5, 0.0)):
        assert step_torque(t, 0.24, 25.0) == expected          # float path
        assert sx(t, 0.24, 25.0)[0][0] == expected             # CasADi path, same switch


def test_decaying_exponential_starts_at_its_magnitude_and_falls_by_e_per_time_constant():
    m, t0, tau = -12.0, 0.3, 0.08
    assert decaying_exponential(t0, t0, tau, m) == pytest.approx(m)
    assert decaying_exponential(t0 + tau, t0, tau, m) == pytest.approx(m / math.e)
    # memoryless: each further time constant divides by e again; it dies out without changing sign
    assert decaying_exponential(t0 + 3 * tau, t0, tau, m) == pytest.approx(m / math.e ** 3)
    assert -1e-15 < decaying_exponential(t0 + 40 * tau, t0, tau, m) <= 0
    assert decaying_exponential(t0 + tau, t0, 1e9, m) == pytest.approx(m, rel=1e-9)   # tau -> inf: constant
    sx = as_function(decaying_exponential, 1, 1, 1, 1)
    assert sx(t0 + tau, t0, tau, m)[0][0] == pytest.approx(m / math.e)


def test_spring_damper_hand_values_and_signs():
    # k (q_rest + actuator - q) - d qd = 100 (0.2 + 0.05 - 0.1) - 10 * 0.3 = 12
    assert spring_damper(0.1, 0.3, 100.0, 10.0, 0.2, 0.05) == pytest.approx(12.0)
    assert spring_damper(0.2, 0.0, 100.0, 10.0, 0.2) == 0.0                 # at rest: no force
    assert spring_damper(0.3, 0.0, 100.0, 10.0, 0.2) < 0                    # restoring
    assert spring_damper(0.2, 0.5, 100.0, 10.0, 0.2) == pytest.approx(-5.0)  # damping opposes the rate
    # the actuator shifts the rest position: q_rest + a with no actuator equals q_rest with it
    assert spring_damper(0.1, 0.3, 100.0, 10.0, 0.25) == pytest.approx(spring_damper(0.1, 0.3, 100.0, 10.0, 0.2, 0.05))


def test_the_hip_holds_its_height_into_terminal_stance_and_falls_late():
    """Issue #34's shape: the bump rises over hip_rise of the step, holds, and falls over the last
    hip_fall with its raised cosine run in 1 - (1 - r)^power; the paper's sinusoid is rise = fall =
    1/2, power 1; the rate is the derivative throughout, 0 at both ends."""
    T, y0, y1, exc = 0.6, 0.85, 0.87, 0.03
    paper = lambda t: [float(v) for v in hip_height_reference(t, T, y0, y1, exc)]
    same = lambda t: [float(v) for v in hip_height_reference(t, T, y0, y1, exc, 0.5, 0.5, 1.0)]
    for t in (0.05, 0.2, 0.3, 0.45, 0.58):
        assert same(t) == pytest.approx(paper(t), abs=1e-15)
    ref = lambda t: [float(v) for v in hip_height_reference(t, T, y0, y1, exc, 0.5, 0.45, 1.5)]
    blend = lambda t: y0 + (y1 - y0) * 0.5 * (1 - math.cos(math.pi * t / T))
    assert ref(0.0) == pytest.approx([y0, 0.0], abs=1e-12) and ref(T) == pytest.approx([y1, 0.0], abs=1e-12)
    assert ref(0.31)[0] == pytest.approx(blend(0.31) + exc, abs=1e-12)       # on the plateau (0.5 T to 0.55 T)
    r = (T - 0.5) / (0.45 * T)                                             # the fall ahead at t = 0.5
    assert ref(0.5)[0] == pytest.approx(blend(0.5) + exc * 0.5 * (1 - math.cos(math.pi * (1 - (1 - r) ** 1.5))))
    assert ref(0.5)[0] > paper(0.5)[0] and ref(0.45)[0] > paper(0.45)[0]   # higher into terminal stance
    for t in (0.1, 0.25, 0.34, 0.41, 0.5, 0.59):
        h = 1e-6
        assert ref(t)[1] == pytest.approx((ref(t + h)[0] - ref(t - h)[0]) / (2 * h), rel=1e-6, abs=1e-9)


def test_leg_force_is_errata_8_pa_lengthens_the_spring():
    # F_w = k_w (l1 + pa - w) - v_w wd = 2e4 (0.868 + 0.01 - 0.85) - 500 * 0.1 = 510
    assert leg_force(0.85, 0.1, 2e4, 500.0, 0.868, 0.01) == pytest.approx(510.0)
    # raising pa pushes the hip up (§4.2: pa is increased when the hip drops too low)
    assert leg_force(0.85, 0.0, 2e4, 500.0, 0.868, 0.02) > leg_force(0.85, 0.0, 2e4, 500.0, 0.868, 0.0)


def test_hip_height_reference_ends_low_peaks_mid_step_with_flat_ends():
    T, y0, y1, exc = 0.6, 0.85, 0.87, 0.03
    ref = lambda t: [float(v) for v in hip_height_reference(t, T, y0, y1, exc)]
    assert ref(0.0) == pytest.approx([y0, 0.0], abs=1e-12)
    assert ref(T) == pytest.approx([y1, 0.0], abs=1e-12)      # zero slope: continuous across heel strike
    assert ref(T / 2)[0] == pytest.approx((y0 + y1) / 2 + exc)
    for t in (0.1, 0.25, 0.41):                               # its rate is its derivative
        h = 1e-6
        assert ref(t)[1] == pytest.approx((ref(t + h)[0] - ref(t - h)[0]) / (2 * h), rel=1e-6)


def stance_setup():
    ctx = body_context(BODY)
    ctx.update(k_w=2e4, v_w=500.0, k_t=300.0, d_t=40.0, theta2_ref=0.05, k_y=10.0, c_y=0.05, t_off=0.24,
               t_step=0.6, y_start=0.85, y_end=0.86, excursion=0.03, hip_rise=0.5, hip_fall=0.5, hip_fall_power=1.0, hip_settle=1.0,
               locked=0.0, theta1_target=0.3, w_target=0.87)
    p = dict(F_theta1_magnitude=30.0, pa_offset=0.01, F_theta1_brake=-5.0,
             **{k: 0.001 * i for i, k in enumerate(PA_KNOTS)})
    return ctx, p


def test_stance_forces_match_hand_computed_laws():
    ctx, p = stance_setup()
    forces = as_function(stance_forces, 6, 1, len(STANCE_PARAMETERS), len(STANCE_CONTEXT))
    x = np.array([0.86, 0.1, 0.02, 0.05, 1.2, -0.1])
    w, th1, th2, wd, th1d, th2d = x
    y, yd = w * math.cos(th1), wd * math.cos(th1) - w * math.sin(th1) * th1d   # hip = w (sin th1, cos th1)
    T = ctx["t_step"]
    for t, f_theta1, late, profile in ((0.1, 30.0, 0.0, 0.1 / T * 0.01), (0.45, -5.0, 0.5, 0.75 * 0.01)):
        (f_w, f_th1, f_th2), (pa,) = forces(x, t, STANCE_PARAMETERS.pack(p), STANCE_CONTEXT.pack(ctx))
        s = math.pi * t / T
        y_ref = 0.85 + 0.01 * 0.5 * (1 - math.cos(s)) + 0.03 * 0.5 * (1 - math.cos(2 * s))
        yd_ref = (0.01 * 0.5 * math.sin(s) + 0.03 * math.sin(2 * s)) * math.pi / T
        # pa: offset * late extension + profile + hip-height feedback (raised when the hip is low)
        expected_pa = 0.01 * late + profile + 10.0 * (y_ref - y) + 0.05 * (yd_ref - yd)
        assert pa == pytest.approx(expected_pa, rel=1e-12)
        assert f_w == pytest.approx(2e4 * (BODY.l1 + expected_pa - w) - 500.0 * wd, rel=1e-12)
        assert f_th1 == pytest.approx(f_theta1)        # the step, then the braking level after t_off
        assert f_th2 == pytest.approx(300.0 * (0.05 - th2) - 40.0 * th2d)


def test_only_f_theta1_jumps_at_t_off():
    ctx, p = stance_setup()
    forces = as_function(stance_forces, 6, 1, len(STANCE_PARAMETERS), len(STANCE_CONTEXT))
    x = np.array([0.86, 0.1, 0.02, 0.05, 1.2, -0.1])
    args = STANCE_PARAMETERS.pack(p), STANCE_CONTEXT.pack(ctx)
    eps = 1e-9
    # t_off, where F_theta1 drops from its magnitude to the braking level, and mid-step, where the
    # pa offset sets in smoothly
    for t_jump, f_theta1_jump in ((0.24, -5.0 - 30.0), (0.3, 0.0)):
        before, _ = forces(x, t_jump - eps, *args)
        after, _ = forces(x, t_jump + eps, *args)
        assert after - before == pytest.approx([0.0, f_theta1_jump, 0.0], abs=1e-4)


def swing_context(**values):
    ctx, p = stance_setup()
    ctx.update({f"stance_{k}": v for k, v in p.items()})
    ctx.update(origin_x=0.2, origin_y=BODY.l9, l8=BODY.l8, l9=BODY.l9, l12=BODY.l12, l13=BODY.l13,
               toe_off_time=0.1, swing_end_time=0.6, foot_t_toe_off=0.1, foot_t1=0.35, foot_t2=0.5, foot_t_heel_strike=0.6,
               foot_theta5_toe_off=1.4, foot_theta6_toe_off=0.5, foot_theta5_t1=1.6, foot_theta5_heel_strike=1.57,
               foot_theta6_heel_strike=0.0, foot_theta5_rate_toe_off=0.0, foot_theta4_t1=0.9, k_h=80.0, d_h=9.0, theta3_target=-0.3, theta3_peak=-0.33, tau3=0.05,
               exp3_mean=0.2, exp4_mean=0.3,
               P0=0.0, P1=0.0, P2=0.0, P3=0.0, P4=0.1, curve_x0=0.0, baumgarte=50.0, swing2_start=0.35, tau4=0.04,
               pelvis_width=0.18, pelvis_rotation_start=0.0, pelvis_rotation_end=0.0, pelvis_list=0.0, hold_offset=0.0)
    ctx.update(values)
    return SWING_CONTEXT.pack(ctx)


def test_swing_torques_are_the_paper_shapes():
    c = swing_context()
    nc = len(SWING_CONTEXT)
    # swing1: F_theta3 (ERRATA 7) is a decaying exponential from toe-off, time constant tau3, about
    # its mean: mean + fall (exp(-(t - t_to) / tau3) - exp3_mean)
    s1 = as_function(swing1_forces, 9, 1, 2, nc)
    x1 = np.array([0.86, 0.1, 0.02, 0.05, 1.2, -0.1, 0.2, 0.5, -2.0])
    assert s1(x1, 0.1, [7.0, 0.0], c)[0][4] == pytest.approx(7.0 * (1 - 0.2))
    assert s1(x1, 0.15, [7.0, 0.0], c)[0][4] == pytest.approx(7.0 * (1 / math.e - 0.2))
    assert s1(x1, 0.15, [7.0, 3.0], c)[0][4] == pytest.approx(3.0 + 7.0 * (1 / math.e - 0.2))
    assert s1(x1, 0.15, [7.0, 3.0], c)[0][5] == 0.0               # the knee is driven, not torqued
    # ... and the dynamics feel the same torque: with the knee locked (eq. 5) theta3's acceleration
    # gains F_theta3 / a11, a11 = I3 + I4 + m3 r3^2 + m4 (l3^2 + r4^2 + 2 l3 r4 cos theta4) (A.2)
    rhs = as_function(swing1_rhs, 9, 1, 2, nc)
    gain = lambda t: rhs(x1, t, [7.0 / 0.8, 0.0], c)[0][8] - rhs(x1, t, [0.0, 0.0], c)[0][8]
    b = BODY
    a11 = b.I3 + b.I4 + b.m3 * b.r3 ** 2 + b.m4 * (b.l3 ** 2 + b.r4 ** 2 + 2 * b.l3 * b.r4 * math.cos(0.5))
    assert gain(0.1) == pytest.approx(7.0 / a11)
    assert gain(0.15) == pytest.approx(7.0 / 0.8 * (1 / math.e - 0.2) / a11)
    # swing2: hold spring-damper about the thigh's peak + actuator; F_theta4 decays from t1 with tau4
    s2 = as_function(swing2_torques, 10, 1, 3, nc)
    x2 = np.r_[x1[:6], -0.25, 0.9, 0.4, -3.0]
    f3, f4 = s2(x2, 0.39, [-4.0, -0.02, 1.5], c)
    assert f3[0] == pytest.approx(80.0 * (-0.33 - 0.02 + 0.25) - 9.0 * 0.4)
    assert f4[0] == pytest.approx(1.5 - 4.0 * (1 / math.e - 0.3))
    # swing3: the hold (no actuator) plus the constant moment, about the thigh's reference: the
    # peak until RETRACTION_START_SHARE of t1 -> heel strike, then to the heel-strike angle on
    # 3s^2 - 2s^3, the damper on the rate against the reference's
    s3 = as_function(swing3_torque, 8, 1, 1, nc)
    x3 = np.r_[x1[:6], -0.28, 0.3]
    t_r = 0.35 + RETRACTION_START_SHARE * (0.6 - 0.35)
    s = (0.55 - t_r) / (0.6 - t_r)
    ref, rate = -0.33 + 0.03 * (3 * s ** 2 - 2 * s ** 3), 0.03 * 6 * s * (1 - s) / (0.6 - t_r)
    assert s3(x3, 0.55, [1.5], c)[0][0] == pytest.approx(80.0 * (ref + 0.28) - 9.0 * (0.3 - rate) + 1.5)
    # swing2's recovery shift fades out over the retraction window, into swing3 (hold_offset)
    with_shift = swing_context(hold_offset=-0.02)
    assert s3(x3, 0.55, [1.5], with_shift)[0][0] == pytest.approx(
        80.0 * (ref - 0.02 * (1 - (3 * s ** 2 - 2 * s ** 3)) + 0.28) - 9.0 * (0.3 - rate - 0.02 * 6 * s * (1 - s) / (0.6 - t_r)) + 1.5)
    f3_late, _ = s2(x2, 0.47, [-4.0, -0.02, 1.5], c)
    q = (0.47 - t_r) / (0.6 - t_r)
    ref2, rate2 = -0.33 + 0.03 * (3 * q ** 2 - 2 * q ** 3), 0.03 * 6 * q * (1 - q) / (0.6 - t_r)
    shift, shift_rate = -0.02 * (1 - (3 * q ** 2 - 2 * q ** 3)), 0.02 * 6 * q * (1 - q) / (0.6 - t_r)
    assert f3_late[0] == pytest.approx(80.0 * (ref2 + shift + 0.25) - 9.0 * (0.4 - rate2 - shift_rate))
    # the peak at the heel-strike angle: the paper's hold about it
    assert s3(x3, 0.55, [1.5], swing_context(theta3_peak=-0.3))[0][0] == pytest.approx(80.0 * (-0.3 + 0.28) - 9.0 * 0.3 + 1.5)
    assert s2(x2, 0.42, [-4.0, -0.02, 1.5], swing_context(theta3_peak=-0.3))[0][0] == \
        pytest.approx(80.0 * (-0.3 - 0.02 + 0.25) - 9.0 * 0.4)


# -- curve P ------------------------------------------------------------------------------------

def check_five_conditions(a0, a_max, a_min, c, d, end_slope=0.0):
    coeffs = ds.curve_p_coefficients(a0, a_max, a_min, c, d, end_slope)
    slope = np.polyder(coeffs)
    assert [np.polyval(coeffs, s) for s in (0.0, c, d)] == pytest.approx([a0, a_max, a_min], abs=1e-9)
    # flat at C; at D the paper's flat end or the slope that has the knee extending at t1
    assert [np.polyval(slope, s) for s in (c, d)] == pytest.approx([0.0, end_slope], abs=1e-8 / d)


def test_curve_p_coefficients_by_hand():
    # y(0) = 0, y(1) = 1, y'(1) = 0, y(2) = 0, y'(2) = 0: y = s^2 (s - 2)^2 = s^4 - 4 s^3 + 4 s^2,
    # coefficients highest power first as swing_law.curve_p reads them (P0 = A0 multiplies s^4)
    assert ds.curve_p_coefficients(0.0, 1.0, 0.0, 1.0, 2.0) == pytest.approx([1, -4, 4, 0, 0], abs=1e-12)


@FAST
@given(a0=st.floats(0.0, 0.3), a_min=st.floats(0.0, 0.3), rise=st.floats(0.005, 0.3),
       d=st.floats(0.02, 1.5), frac=st.floats(0.1, 0.7))
@example(a0=0.12, a_min=0.10, rise=0.05, d=0.5, frac=0.3)      # a steady step: C = 0.3 D
@example(a0=0.16, a_min=0.09, rise=0.02, d=0.16, frac=0.5)     # short travel, toe-off ankle high
@example(a0=0.05, a_min=0.20, rise=0.10, d=1.2, frac=0.7)      # the peak late in the travel
def test_curve_p_meets_its_five_conditions(a0, a_min, rise, d, frac):
    check_five_conditions(a0, max(a0, a_min) + rise, a_min, frac * d, d)
    check_five_conditions(a0, max(a0, a_min) + rise, a_min, frac * d, d, end_slope=-0.3)


@FAST
@given(a0=st.floats(0.0, 0.3), a_min=st.floats(0.0, 0.3), rise=st.floats(0.005, 0.3), d=st.floats(0.02, 1.5))
def test_curve_p_with_the_papers_c_peaks_at_a_max_and_never_dips(a0, a_min, rise, d):
    # §4.3: "At a distance C, the ankle reaches the maximum height a_max"; with C = 0.3 D (the
    # default swing_peak_position) the ankle also never sinks below its lower end on the way
    a_max = max(a0, a_min) + rise
    y = np.polyval(ds.curve_p_coefficients(a0, a_max, a_min, 0.3 * d, d), np.linspace(0, d, 301))
    assert y.max() <= a_max + 1e-9
    assert y.min() >= min(a0, a_min) - 1e-9


def test_swing_law_evaluates_curve_p_from_the_coefficients_in_order():
    coeffs = ds.curve_p_coefficients(0.12, 0.17, 0.10, 0.15, 0.5)
    c = swing_context(**{f"P{i}": v for i, v in enumerate(coeffs)})
    for s in (0.0, 0.15, 0.33, 0.5):
        assert float(curve_p(c, s)) == pytest.approx(np.polyval(coeffs, s), abs=1e-14)


def test_swing1_knee_law_keeps_the_ankle_on_curve_p():
    """theta4's rate makes d/dt (ankle_y - P(ankle_x - x0)) = -baumgarte * (that error)."""
    coeffs = ds.curve_p_coefficients(0.12, 0.17, 0.10, 0.15, 0.5)
    c = swing_context(curve_x0=-0.3, **{f"P{i}": v for i, v in enumerate(coeffs)})
    rhs = as_function(swing1_rhs, 9, 1, 2, len(SWING_CONTEXT))
    x = np.array([0.86, 0.1, 0.02, 0.05, 1.2, -0.1, 0.25, 0.6, -2.0])
    w, th1, _, wd, th1d, _, th3, th4, th3d = x
    xdot = rhs(x, 0.2, [5.0, 1.0], c)[0]
    assert xdot[6] == th3d and list(xdot[:3]) == list(x[3:6])   # rates carried through
    th4d = xdot[7]
    hip = np.array([0.2, BODY.l9]) + w * unit(th1)
    hip_vel = wd * unit(th1) + w * th1d * np.array([math.cos(th1), -math.sin(th1)])
    ankle = hip - BODY.l3 * unit(th3) - BODY.l4 * unit(th3 + th4)
    d_unit = lambda a: np.array([math.cos(a), -math.sin(a)])
    ankle_vel = hip_vel - BODY.l3 * d_unit(th3) * th3d - BODY.l4 * d_unit(th3 + th4) * (th3d + th4d)
    s = ankle[0] + 0.3
    error = ankle[1] - np.polyval(coeffs, s)
    assert abs(error) > 1e-3                    # the test state is off the curve: the correction acts
    error_rate = ankle_vel[1] - np.polyval(np.polyder(coeffs), s) * ankle_vel[0]
    assert error_rate == pytest.approx(-50.0 * error, rel=1e-9)


@pytest.mark.parametrize("theta3, theta4, hip_vel, rate", [(-0.41, 0.92, (1.34, 0.08), -5.2),
                                                          (-0.25, 0.80, (0.25, 0.03), -1.0),
                                                          (-0.45, 0.95, (2.0, -0.1), 0.0)])
def test_curve_p_s_end_slope_gives_the_knee_its_rate_at_t1(theta3, theta4, hip_vel, rate):
    """At t1 the thigh is at rest: with curve P's slope at D from end_slope_for_knee_rate and the
    ankle at D on the curve, swing1's knee law (the ankle kept on the curve) turns the knee at the
    asked rate (issue #36: the knee extending at t1, not at rest as with the paper's y'(D) = 0)."""
    hip = np.array([0.0, 0.93])
    ankle = hip - BODY.l3 * unit(theta3) - BODY.l4 * unit(theta3 + theta4)
    slope = ds.end_slope_for_knee_rate(BODY, theta3 + theta4, np.array(hip_vel), rate)
    assert slope >= -ds.END_SLOPE_SHARE * math.tan(theta3 + theta4)      # not capped in these cases
    d = 0.6
    coeffs = ds.curve_p_coefficients(0.2, 0.25, float(ankle[1]), 0.3 * d, d, slope)
    x0 = float(ankle[0]) - d
    # the stance state with the hip there moving at hip_vel (w along the leg, theta1 from vertical)
    th1 = math.atan2(hip[0] - 0.2, hip[1] - BODY.l9)
    w = math.hypot(hip[0] - 0.2, hip[1] - BODY.l9)
    # hip_vel = wd unit(th1) + w th1d (cos th1, -sin th1)
    wd, th1d = np.linalg.solve(np.column_stack([unit(th1), w * np.array([math.cos(th1), -math.sin(th1)])]), hip_vel)
    c = swing_context(curve_x0=x0, **{f"P{i}": v for i, v in enumerate(coeffs)})
    rhs = as_function(swing1_rhs, 9, 1, 2, len(SWING_CONTEXT))
    x = np.array([w, th1, 0.0, wd, th1d, 0.0, theta3, theta4, 0.0])
    assert rhs(x, 0.2, [0.0, 0.0], c)[0][7] == pytest.approx(rate, abs=1e-9)


# -- swing1 end posture ------------------------------------------------------------------------

@pytest.mark.parametrize("hip_y, theta3, dorsiflexed", [(0.93, -0.3, True), (0.88, -0.4, True),
                                                       (0.93, -0.8, False), (1.0, -0.5, False)])
def test_swing1_end_posture_puts_the_toe_under_the_knee_clear_of_the_ground(hip_y, theta3, dorsiflexed):
    clearance = ATTRS.toe_clearance + 0.01 * BODY.l1
    knee = np.array([0.0, hip_y]) - BODY.l3 * unit(theta3)
    ankle, phi, theta5 = ds.swing1_end_posture(BODY, knee, math.pi / 2, 0.0, clearance)
    assert ankle == pytest.approx(knee - BODY.l4 * unit(phi), abs=1e-12)   # shank of length l4
    toe = foot_points_float(*ankle, phi, theta5, 0.0, BODY.l8, BODY.l9, BODY.l12, BODY.l13)[2]
    assert toe[0] == pytest.approx(knee[0], abs=1e-9)                         # toe directly under the knee
    if dorsiflexed:     # only as much dorsiflexion as the clearance needs
        assert theta5 > math.pi / 2 and toe[1] == pytest.approx(clearance, abs=1e-9)
    else:               # the interpolated ankle angle is kept when its toe already clears
        assert theta5 == math.pi / 2 and toe[1] > clearance


# -- gains --------------------------------------------------------------------------------------

def effective_inertias(body):
    """The inertia each spring acts on (gains.py docstring), from Table B-1 fractions."""
    h, m = body.height, body.mass
    l3, l4 = 0.23669 * h, 0.24556 * h
    trunk = 0.678 * m * ((0.496 * 0.47 * h) ** 2 + (0.5 * 0.47 * h) ** 2)          # I2 + m2 r2^2
    leg = 0.1 * m * ((0.323 * l3) ** 2 + (0.433 * l3) ** 2) \
        + 0.061 * m * ((0.416 * l4) ** 2 + (l3 + 0.606 * l4) ** 2)                    # straight leg about the hip
    return 0.678 * m, trunk, leg


def test_gains_hand_values_for_the_reference_body():
    g = control_gains(BODY, ATTRS)
    omega = lambda f: 2 * math.pi * f
    assert g.k_w == pytest.approx(54.24 * omega(3.0) ** 2)             # m2 (2 pi 3 Hz)^2 = 19272 N/m
    assert g.k_w == pytest.approx(19271.7, rel=1e-5)
    assert g.v_w == pytest.approx(2 * 0.3 * 54.24 * omega(3.0))
    assert (g.theta2_ref, g.k_y, g.c_y) == (0.0, 10.0, 0.05)
    leaned = control_gains(BODY, ATTRS.with_overrides({"trunk_lean": 6.0, "hip_height_gain": 3.0,
                                                       "hip_height_rate_gain": 0.2}))
    assert (leaned.theta2_ref, leaned.k_y, leaned.c_y) == pytest.approx((math.radians(6.0), 3.0, 0.2))


@pytest.mark.parametrize("height", [1.4, 1.75, 2.1])
@pytest.mark.parametrize("mass", [40.0, 95.0, 150.0])
def test_gains_follow_frequency_and_damping_ratio_over_the_supported_bodies(height, mass):
    body = Body(height, mass)
    attrs = ATTRS.with_overrides({"leg_frequency": 2.5, "trunk_damping_ratio": 0.6, "hip_hold_frequency": 1.7})
    g = control_gains(body, attrs)
    pairs = {"leg": (g.k_w, g.v_w), "trunk": (g.k_t, g.d_t), "hip_hold": (g.k_h, g.d_h)}
    for (name, (k, d)), m_eff in zip(pairs.items(), effective_inertias(body)):
        assert math.isfinite(k) and math.isfinite(d) and k > 0 and d > 0
        # k = m_eff w^2 and d = 2 zeta m_eff w: the spring rings at f with damping ratio zeta
        assert math.sqrt(k / m_eff) / (2 * math.pi) == pytest.approx(attrs.get(f"{name}_frequency"), rel=1e-12)
        assert d / (2 * math.sqrt(k * m_eff)) == pytest.approx(attrs.get(f"{name}_damping_ratio"), rel=1e-12)


def test_gains_scale_with_mass_and_height_squared():
    ref = control_gains(Body(1.5, 50), ATTRS)
    big = control_gains(Body(2.1, 140), ATTRS)
    assert big.k_w / ref.k_w == pytest.approx(140 / 50)                  # the leg carries a mass
    assert big.v_w / ref.v_w == pytest.approx(140 / 50)
    for k in ("k_t", "d_t", "k_h", "d_h"):                             # rotations: inertias, m h^2
        assert getattr(big, k) / getattr(ref, k) == pytest.approx(140 / 50 * (2.1 / 1.5) ** 2)


def test_the_toe_under_the_knee_is_solved_in_closed_form():
    """curve_p.toe_under_knee: the shank angle at which the toe tip (dynamics.foot_points_float) is
    directly under the knee, for ankle angles 60-160° and toe angles 0-40°, to round-off."""
    import math
    from klaw_ocp.dynamics.points import foot_points_float
    body = Body(height=1.8, mass=80.0)
    rng = np.random.default_rng(7)
    for _ in range(500):
        knee = rng.uniform(-1.0, 1.0, 2)
        theta5, theta6 = math.radians(rng.uniform(60, 160)), math.radians(rng.uniform(0, 40))
        ankle, phi = ds.toe_under_knee(body, knee, theta5, theta6)
        assert -0.5 <= phi <= math.pi / 2
        assert np.hypot(*(ankle - knee)) == pytest.approx(body.l4, abs=1e-15)
        toe = foot_points_float(ankle[0], ankle[1], phi, theta5, theta6, body.l8, body.l9, body.l12, body.l13)[2]
        assert toe[0] == pytest.approx(knee[0], abs=1e-14)
