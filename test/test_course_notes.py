"""
The course notes' worked examples as exact expectations, and their slips pinned numerically.

Jia: "Rotation in the Space"; Cayero: "Relations between Rotation Matrix and Euler axis-angle".
"""

import math_helpers as h
import numpy as np
import pytest
from rot_tools import (
    axis_angle_to_matrix, euler_to_matrix, matrix_to_axis_angle, matrix_to_euler,
    rot_x, rot_y, rot_z, screw_from_transform, skew)

N = 10_000
PI = h.PI


def notes_rot_zyx_eq1(phi, theta, psi):
    """Jia eq. 1, the closed form of Rot_z(phi) Rot_y(theta) Rot_x(psi) as printed."""
    cf, sf = np.cos(phi), np.sin(phi)
    ct, st = np.cos(theta), np.sin(theta)
    cp, sp = np.cos(psi), np.sin(psi)
    return np.stack([
        np.stack([cf * ct, cf * st * sp - sf * cp, cf * st * cp + sf * sp], -1),
        np.stack([sf * ct, sf * st * sp + cf * cp, sf * st * cp - cf * sp], -1),
        np.stack([-st, ct * sp, ct * cp], -1),
    ], -2)


def notes_tracking_matrix(alpha, beta):
    """Jia example 3: R = Rot_z(alpha) Rot_y(beta), closed form as printed."""
    ca, sa, cb, sb = np.cos(alpha), np.sin(alpha), np.cos(beta), np.sin(beta)
    zero = np.zeros_like(ca * cb)
    return np.stack([
        np.stack([ca * cb, -sa + zero, ca * sb], -1),
        np.stack([sa * cb, ca + zero, sa * sb], -1),
        np.stack([-sb + zero, zero, cb + zero], -1),
    ], -2)


def notes_q_eq11(r):
    """Jia eq. 11: l = q = (r23 - r32, r31 - r13, r12 - r21)."""
    return np.stack([r[..., 1, 2] - r[..., 2, 1], r[..., 2, 0] - r[..., 0, 2],
                     r[..., 0, 1] - r[..., 1, 0]], -1)


# Worked examples that are right: exact expectations.


def test_000_eq1_rot_zyx_closed_form():
    rng = np.random.default_rng(60)
    a = rng.uniform(-PI, PI, size=(N, 3))
    printed = notes_rot_zyx_eq1(a[:, 0], a[:, 1], a[:, 2])
    assert h.max_abs(euler_to_matrix(a, 'ZYX') - printed) <= 1e-15 * 4
    product = rot_z(a[:, 0]) @ rot_y(a[:, 1]) @ rot_x(a[:, 2])
    assert h.max_abs(product - printed) <= 1e-15 * 4
    # ... and matrix_to_euler gives the angles back (pitch kept inside (-pi/2, pi/2))
    a[:, 1] = rng.uniform(-1.5, 1.5, N)
    got, degenerate = matrix_to_euler(notes_rot_zyx_eq1(a[:, 0], a[:, 1], a[:, 2]), 'ZYX')
    assert not degenerate.any()
    assert h.angle_error(got, a) <= 1e-12


def test_000_eq7_rodrigues_matrix():
    rng = np.random.default_rng(61)
    axis, angle, _ = h.random_axis_angle(rng, N)
    angle = angle * rng.choice([-2.0, 1.0], N)        # any sign, up to 2 pi
    printed = h.notes_rodrigues_eq7(axis, angle)
    assert h.max_abs(axis_angle_to_matrix(axis, angle) - printed) <= 1e-15 * 4


def test_001_eq18_rodrigues_matrix_and_eq14_vector_form():
    rng = np.random.default_rng(62)
    u = h.random_unit_vectors(rng, N)
    phi = rng.uniform(-2 * PI, 2 * PI, N)
    printed = h.notes_rodrigues_eq18(u, phi)
    got = axis_angle_to_matrix(u, phi)
    assert h.max_abs(got - printed) <= 1e-15 * 4
    # eq. 14: p' = p cos(phi) + (1 - cos(phi)) (p.u) u + sin(phi) (u x p)
    p = rng.normal(size=(N, 3))
    c, s = np.cos(phi)[:, None], np.sin(phi)[:, None]
    p_rot = p * c + (1 - c) * np.sum(p * u, -1, keepdims=True) * u + s * np.cross(u, p)
    assert h.max_abs(np.einsum('nij,nj->ni', got, p) - p_rot) <= 1e-14


def test_000_example3_tracking_matrix():
    rng = np.random.default_rng(63)
    alpha = rng.uniform(-PI, PI, N)
    beta = rng.uniform(-PI / 2, PI / 2, N)
    printed = notes_tracking_matrix(alpha, beta)
    angles = np.stack([alpha, beta, np.zeros(N)], -1)
    assert h.max_abs(euler_to_matrix(angles, 'ZYX') - printed) <= 1e-15 * 4
    assert h.max_abs(rot_z(alpha) @ rot_y(beta) - printed) <= 1e-15 * 4
    # its printed cos(theta) = (cos a cos b + cos a + cos b - 1) / 2 is right
    _, theta = matrix_to_axis_angle(printed)
    ca, cb = np.cos(alpha), np.cos(beta)
    assert h.max_abs(np.cos(theta) - (ca * cb + ca + cb - 1) / 2) <= 1e-15 * 4


@pytest.mark.parametrize('lock', [PI / 2, -PI / 2])
def test_000_example3_gimbal_lock_at_elevation_pm_half_pi(lock):
    for alpha in (0.0, 0.7, -2.0, 3.0, PI):
        got, degenerate = matrix_to_euler(notes_tracking_matrix(alpha, lock), 'ZYX')
        assert degenerate
        assert got[2] == 0.0                       # theta3 = 0 ...
        assert h.angle_error(got[0], alpha) <= 1e-12   # ... theta1 carries the free angle
        assert abs(got[1] - lock) <= 1e-12
        assert got[0] > -PI


@pytest.mark.parametrize('eps', [1e-3, 1e-5])
@pytest.mark.parametrize('lock', [PI / 2, -PI / 2])
def test_000_example3_heading_jumps_by_pi_across_the_lock(lock, eps):
    # "alpha instantaneously jumps to alpha + pi" past the lock; theta1 and theta3 have
    # condition ~1/eps.
    inside = lock - np.sign(lock) * eps
    outside = lock + np.sign(lock) * eps
    for alpha in (0.0, 0.7, -2.0, 3.0):
        before, flag_before = matrix_to_euler(notes_tracking_matrix(alpha, inside), 'ZYX')
        after, flag_after = matrix_to_euler(notes_tracking_matrix(alpha, outside), 'ZYX')
        assert not flag_before and not flag_after
        tol = 1e-15 / eps * 10
        assert h.angle_error(before, [alpha, inside, 0.0]) <= tol
        assert h.angle_error(after[0], alpha + PI) <= tol     # heading jumps by pi
        assert abs(after[1] - inside) <= tol                   # pitch folds back
        assert h.angle_error(after[2], PI) <= tol              # roll turns over
        for angles, beta in ((before, inside), (after, outside)):
            assert h.max_abs(euler_to_matrix(angles, 'ZYX')
                             - notes_tracking_matrix(alpha, beta)) <= 1e-12


@pytest.mark.parametrize('lock', [PI / 2, -PI / 2])
def test_000_example3_no_jump_inside_the_flagged_band(lock):
    # Within the documented lock tolerance both sides are flagged, theta3 = 0, and theta1
    # stays at alpha (the heading is continuous there).
    for alpha in (0.0, 0.7, -2.0, 3.0):
        for delta in (-1e-9, 1e-9):
            r = notes_tracking_matrix(alpha, lock + delta)
            got, degenerate = matrix_to_euler(r, 'ZYX')
            assert degenerate and got[2] == 0.0
            assert h.angle_error(got[0], alpha) <= 2e-9 + 1e-12
            assert h.max_abs(euler_to_matrix(got, 'ZYX') - r) <= 2e-9 + 1e-12


# Slips, pinned.


def test_000_sec1_pitch_range_is_minus_half_pi_to_half_pi():
    # §1 gives the Z-Y-X pitch range as [0, pi]: no pitch there gives a nose-down r31 > 0.
    r = notes_rot_zyx_eq1(0.0, -0.5, 0.0)
    assert r[2, 0] > 0
    got, _ = matrix_to_euler(r, 'ZYX')
    assert abs(got[1] + 0.5) <= 1e-15
    # [0, pi] also double-covers: (phi + pi, pi - theta, psi + pi) is the same rotation.
    assert h.max_abs(notes_rot_zyx_eq1(0.3 + PI, PI - 0.4, 0.2 + PI)
                     - notes_rot_zyx_eq1(0.3, 0.4, 0.2)) <= 1e-15 * 4
    rng = np.random.default_rng(64)
    _, _, rs = h.random_axis_angle(rng, 1000)
    pitch = matrix_to_euler(rs, 'ZYX')[0][:, 1]
    assert pitch.min() < -1.0 and pitch.max() > 1.0
    assert np.all(np.abs(pitch) <= PI / 2)
    # eq. 1 is Z-Y-X, not Z-Y-Z
    assert h.max_abs(euler_to_matrix([0.3, 0.4, 0.2], 'ZYZ')
                     - notes_rot_zyx_eq1(0.3, 0.4, 0.2)) > 0.1


def test_000_eq10_sign_of_the_cross_product():
    # Eq. 10 writes (R - R^T) v as the printed matrix (right) and then as q x v (wrong sign):
    # the printed matrix is -[q]x, so (R - R^T) v = -q x v = v x q.
    rng = np.random.default_rng(65)
    axis, angle, r = h.random_axis_angle(rng, N)
    q = notes_q_eq11(r)
    q1, q2, q3 = q[:, 0], q[:, 1], q[:, 2]
    z = np.zeros(N)
    printed = np.stack([np.stack([z, q3, -q2], -1), np.stack([-q3, z, q1], -1),
                        np.stack([q2, -q1, z], -1)], -2)
    assert h.max_abs(printed - (r - np.swapaxes(r, -1, -2))) <= 1e-15
    v = rng.normal(size=(N, 3))
    lhs = np.einsum('nij,nj->ni', r - np.swapaxes(r, -1, -2), v)
    assert h.max_abs(lhs + np.cross(q, v)) <= 1e-14           # = -q x v
    assert h.max_abs(lhs - np.cross(q, v)) > 1.0              # the printed claim fails
    # The code: the printed matrix is -skew(q), and R - R^T = 2 sin(theta) [l]x with the axis
    # and angle matrix_to_axis_angle returns, so (R - R^T) v = 2 sin(theta) l x v.
    assert h.max_abs(printed + skew(q)) == 0.0
    got_axis, got_angle = matrix_to_axis_angle(r)
    two_sin_l = 2 * np.sin(got_angle)[:, None] * got_axis
    assert h.max_abs(r - np.swapaxes(r, -1, -2) - skew(two_sin_l)) <= 1e-14
    assert h.max_abs(lhs - np.cross(two_sin_l, v)) <= 1e-14


def test_000_eq11_axis_is_minus_two_sin_theta_times_the_axis():
    rng = np.random.default_rng(66)
    _, _, r = h.random_axis_angle(rng, N)
    axis, angle = matrix_to_axis_angle(r)
    q = notes_q_eq11(r)
    assert h.max_abs(q + 2 * np.sin(angle)[:, None] * axis) <= 1e-14
    # so eq. 11 points along -l for angles in (0, pi) ...
    assert np.all(np.sum(q * axis, -1) < 0)
    # ... and vanishes at angle pi, where our axis is still a unit vector (up to sign).
    u = np.array([2.0, -1.0, 2.0]) / 3.0
    half_turn = 2 * np.outer(u, u) - np.eye(3)
    assert h.max_abs(notes_q_eq11(half_turn)) <= 1e-16
    got_axis, got_angle = matrix_to_axis_angle(half_turn)
    assert abs(got_angle - PI) <= 1e-15
    assert min(h.max_abs(got_axis - u), h.max_abs(got_axis + u)) <= 1e-15


def test_000_eq12_acos_loses_small_angles_ours_does_not():
    # Eq. 12 (theta = acos((Tr - 1) / 2)) returns 0 for every angle below ~1e-8.
    for angle in (1e-12, 1e-9):
        r = h.notes_rodrigues_eq7([0.0, 0.0, 1.0], angle)
        acos_angle = np.arccos(np.clip((np.trace(r) - 1) / 2, -1, 1))
        assert abs(acos_angle - angle) >= 0.9 * angle
        _, got = matrix_to_axis_angle(r)
        assert abs(got - angle) <= 1e-14 * angle


def test_000_eq13_sin_squared_typo():
    # Eq. 13 prints sin(theta) = +/- sqrt(1 - sin^2 cos(theta)); the identity is
    # 1 - cos^2(theta) = (3 - Tr^2 + 2 Tr) / 4, which its second line states correctly.
    theta = np.linspace(0, PI, 1001)
    tr = 1 + 2 * np.cos(theta)
    assert h.max_abs(np.sin(theta) ** 2 - (3 - tr ** 2 + 2 * tr) / 4) <= 1e-15 * 4
    literal = 1 - np.sin(np.cos(theta)) ** 2
    assert h.max_abs(np.sin(theta) ** 2 - literal) > 0.1
    # The code: sin(theta) = +sqrt((3 - Tr^2 + 2 Tr) / 4); eq. 13 read literally does not give it.
    rng = np.random.default_rng(72)
    axis = h.random_unit_vectors(rng, len(theta))
    r = axis_angle_to_matrix(axis, theta)
    tr = np.trace(r, axis1=-2, axis2=-1)
    _, got = matrix_to_axis_angle(r)
    eq13 = np.sqrt(np.clip(3 - tr ** 2 + 2 * tr, 0, None) / 4)
    far = (theta > 0.01) & (theta < PI - 0.01)  # near 0 and pi eq. 13 keeps only half the digits
    assert h.max_abs((np.sin(got) - eq13)[far]) <= 1e-13
    assert h.max_abs(np.sin(got) - eq13) <= 3e-8
    assert h.max_abs(got - theta) <= 1e-15 * 4
    assert h.max_abs(np.sin(got) - np.sqrt(1 - np.sin(np.cos(got)) ** 2)) > 0.1


def test_000_eq15_divides_by_lz():
    # Eq. 15: sin(theta) = (2 r21 - lx ly (3 - Tr)) / (2 lz) is 0/0 for an axis with lz = 0
    # and loses all digits for lz ~ 1e-12; our recovery works for every axis.
    for axis in ([1.0, 0.0, 0.0], [0.6, 0.8, 0.0], [0.0, -1.0, 0.0]):
        axis = np.array(axis)
        r = h.notes_rodrigues_eq7(axis, 1.0)
        num = 2 * r[1, 0] - axis[0] * axis[1] * (3 - np.trace(r))
        assert abs(num) <= 1e-15 and axis[2] == 0.0                  # 0 / 0
        got_axis, got_angle = matrix_to_axis_angle(r)
        assert abs(got_angle - 1.0) <= 1e-14 and h.max_abs(got_axis - axis) <= 1e-14
    axis = np.array([0.6, 0.8, 1e-12])
    axis /= np.linalg.norm(axis)
    r = h.notes_rodrigues_eq7(axis, 1.0)
    notes_sin = (2 * r[1, 0] - axis[0] * axis[1] * (3 - np.trace(r))) / (2 * axis[2])
    assert abs(notes_sin - np.sin(1.0)) > 1e-6
    got_axis, got_angle = matrix_to_axis_angle(r)
    assert abs(got_angle - 1.0) <= 1e-14 and h.max_abs(got_axis - axis) <= 1e-14


def test_000_eq15_with_eq11_axis_gives_the_angle_two_pi_minus_theta():
    # The notes' own pair (l = q / |q|, theta_notes from eqs. 12 and 15) is consistent: q points
    # along -l, eq. 15 then yields sin(theta_notes) = -sin(theta), i.e. theta_notes = 2 pi - theta.
    rng = np.random.default_rng(67)
    _, _, r = h.random_axis_angle(rng, 1000)
    q = notes_q_eq11(r)
    l_notes = q / np.linalg.norm(q, axis=-1, keepdims=True)
    tr = np.trace(r, axis1=-2, axis2=-1)
    cos_notes = (tr - 1) / 2
    keep = np.abs(l_notes[:, 2]) > 0.1
    sin_notes = ((2 * r[:, 1, 0] - l_notes[:, 0] * l_notes[:, 1] * (3 - tr)) / (2 * l_notes[:, 2]))
    theta_notes = np.mod(np.arctan2(sin_notes, cos_notes), 2 * PI)
    axis, angle = matrix_to_axis_angle(r)
    assert h.max_abs((theta_notes - (2 * PI - angle))[keep]) <= 1e-12
    assert h.max_abs((l_notes + axis)[keep]) <= 1e-12
    # (eq. 15 amplifies rounding by 1 / |l_z| <= 10, so this pins consistency, not accuracy)
    assert h.max_abs((axis_angle_to_matrix(l_notes, theta_notes) - r)[keep]) <= 1e-12


def test_000_eq16_half_angle_vector_points_along_minus_axis():
    # Eq. 16's half-angle form points along -l: it is sin(theta'/2) l' for l' = -l and
    # theta' = 2 pi - theta.
    rng = np.random.default_rng(68)
    alpha = rng.uniform(-PI + 1e-3, PI - 1e-3, N)
    beta = rng.uniform(-PI / 2, PI / 2, N)
    r = notes_tracking_matrix(alpha, beta)
    sa, ca, sb, cb = np.sin(alpha), np.cos(alpha), np.sin(beta), np.cos(beta)
    printed_q = np.stack([sa * sb, -ca * sb - sb, -sa * cb - sa], -1)
    assert h.max_abs(printed_q - notes_q_eq11(r)) <= 1e-15 * 4
    s2a, c2a, s2b, c2b = (np.sin(alpha / 2), np.cos(alpha / 2), np.sin(beta / 2),
                          np.cos(beta / 2))
    half = np.stack([s2a * s2b, -c2a * s2b, -s2a * c2b], -1)
    assert h.max_abs(printed_q - 4 * (c2a * c2b)[:, None] * half) <= 1e-14
    axis, angle = matrix_to_axis_angle(r)
    assert h.max_abs(half + np.sin(angle / 2)[:, None] * axis) <= 1e-14
    theta_prime = 2 * PI - angle
    assert h.max_abs(half - np.sin(theta_prime / 2)[:, None] * (-axis)) <= 1e-14
    assert h.max_abs(axis_angle_to_matrix(-axis, theta_prime) - r) <= 1e-14


def transform_set(rng, n):
    axis, angle, r = h.random_axis_angle(rng, n)
    keep = (angle > 1e-3) & (angle < PI - 1e-3)
    b = rng.normal(size=(n, 3)) * 10
    return axis[keep], angle[keep], r[keep], b[keep]


def test_000_sec5_i_minus_r_is_singular_and_the_axis_point():
    # §5 writes c = (I - R)^-1 b_perp; (I - R) kills the axis (rank 2). In the plane
    # perpendicular to the axis the solution is c = (b_perp + cot(theta/2) l x b_perp) / 2.
    rng = np.random.default_rng(69)
    axis, angle, r, b = transform_set(rng, N)
    i_minus_r = np.eye(3) - r
    assert h.max_abs(np.einsum('nij,nj->ni', i_minus_r, axis)) <= 1e-15 * 4
    assert np.all(np.linalg.svd(i_minus_r, compute_uv=False)[:, -1] <= 1e-15 * 4)
    bperp = b - np.sum(b * axis, -1, keepdims=True) * axis
    c = 0.5 * (bperp + np.cross(axis, bperp) / np.tan(angle / 2)[:, None])
    # c = R c + b_perp
    assert h.max_abs(np.einsum('nij,nj->ni', r, c) + bperp - c) <= 1e-12 * (1 + h.max_abs(b))
    # the minimum-norm solution (pseudo-inverse) is the same point, and so is ours
    pinv = np.einsum('nij,nj->ni', np.linalg.pinv(i_minus_r, rcond=1e-9), bperp)
    sin_half = np.sin(angle / 2)
    bnorm = np.linalg.norm(b, axis=-1)
    assert np.all(np.abs(pinv - c).max(-1) <= 1e-13 * (1 + bnorm / sin_half ** 2))
    scr = screw_from_transform(r, b)
    assert np.all(np.abs(scr.point - c).max(-1) <= 1e-13 * (1 + bnorm / sin_half))


def test_000_eq17_eq18_moment_sign():
    # Eq. 18: m = -(R^T + I) b_perp is -2 sin(theta) times the Pluecker moment; eq. 17's
    # l x c is +2 sin(theta) times it (eq. 10's sign slip).
    rng = np.random.default_rng(70)
    axis, angle, r, b = transform_set(rng, N)
    rt = np.swapaxes(r, -1, -2)
    scr = screw_from_transform(r, b)
    assert h.max_abs(scr.direction - axis) <= 1e-12
    bperp = b - np.sum(b * axis, -1, keepdims=True) * axis
    m18 = -np.einsum('nij,nj->ni', rt + np.eye(3), bperp)
    two_sin = 2 * np.sin(angle)[:, None]
    scale = 1 + np.linalg.norm(b, axis=-1)
    assert np.all(np.abs(m18 + two_sin * scr.moment).max(-1) <= 1e-12 * scale)
    q = notes_q_eq11(r)
    l_cross_c = np.cross(q, scr.point)
    assert np.all(np.abs(l_cross_c - two_sin * scr.moment).max(-1) <= 1e-12 * scale)
    assert np.all(np.abs(l_cross_c + m18).max(-1) <= 1e-12 * scale)
    r_minus_rt_c = np.einsum('nij,nj->ni', r - rt, scr.point)
    assert np.all(np.abs(r_minus_rt_c - m18).max(-1) <= 1e-12 * scale)
    assert h.max_abs((rt + np.eye(3)) @ (np.eye(3) - r) - (rt - r)) <= 1e-15 * 8
    # moment = point x direction
    assert np.all(np.abs(scr.moment - np.cross(scr.point, scr.direction)).max(-1)
                  <= 1e-14 * scale)


def test_001_eq16_should_read_u_u_transpose():
    # Eq. 16 prints (p^T u) u = (u^T u) p, which is p for a unit u: false. The equality
    # used in eq. 15 is (p^T u) u = (u u^T) p.
    rng = np.random.default_rng(71)
    u = h.random_unit_vectors(rng, N)
    p = rng.normal(size=(N, 3))
    lhs = np.sum(p * u, -1, keepdims=True) * u
    printed = np.sum(u * u, -1, keepdims=True) * p
    right = np.einsum('ni,nj,nj->ni', u, u, p)
    assert h.max_abs(lhs - right) <= 1e-14
    assert np.median(np.linalg.norm(lhs - printed, axis=-1)) > 0.1
    # The code: Rodrigues' vector form (eq. 14/15) with (u u^T) p is what
    # axis_angle_to_matrix(u, phi) does to p; with the printed (u^T u) p = p it is not.
    phi = rng.uniform(-PI, PI, N)[:, None]
    moved = np.einsum('nij,nj->ni', axis_angle_to_matrix(u, phi[:, 0]), p)
    with_right = np.cos(phi) * p + (1 - np.cos(phi)) * right + np.sin(phi) * np.cross(u, p)
    with_printed = np.cos(phi) * p + (1 - np.cos(phi)) * printed + np.sin(phi) * np.cross(u, p)
    assert h.max_abs(moved - with_right) <= 1e-14
    assert np.median(np.linalg.norm(moved - with_printed, axis=-1)) > 0.1
