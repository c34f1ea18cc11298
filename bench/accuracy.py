"""
Measured worst-case errors of rot_tools' round trips and cross-checks (quoted in README).

Run: .venv/bin/python bench/accuracy.py   (numpy only; about 15 s)

Random sets (seeded) of 100,000 rotations / transforms plus the adversarial sets the tests use:
angles within 1e-12 of 0 and π, exactly π, gimbal lock ± 1e-9 … 1e-5 in all 24 sequences,
tiny angles with large translations. Each line prints the largest error found. The second
part measures the frames, rigid motions, comparing/fitting and quaternion functions against
plain-NumPy 4×4 products and closed forms.
"""

import numpy as np
import rot_tools as rt

RNG = np.random.default_rng(20261121)
N = 100_000
ELEMENTARY = {'X': rt.rot_x, 'Y': rt.rot_y, 'Z': rt.rot_z}


def random_rotations(n):
    return rt.rotvec_to_matrix(RNG.normal(size=(n, 3)) * RNG.uniform(0, np.pi, (n, 1))
                               / np.sqrt(3))


def adversarial_axis_angles():
    axes = RNG.normal(size=(2000, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    angles = np.concatenate([
        RNG.uniform(0, 1e-12, 500), np.pi - RNG.uniform(0, 1e-12, 500),
        np.full(500, np.pi), np.pi - 1e-9 * RNG.uniform(0.5, 2, 500)])
    return axes, angles


def report(name, value):
    print(f'{name:<58} {value:.2e}')
    return value


def main():
    worst = 0.0
    R = random_rotations(N)
    e = 0.0
    for seq in rt.EULER_SEQUENCES:
        angles, flagged = rt.matrix_to_euler(R, seq)  # (random R near I lock proper ones)
        err = np.abs(rt.euler_to_matrix(angles, seq) - R).max(axis=(1, 2))
        e = max(e, err[~flagged].max())
    worst = max(worst, report('Euler: R → angles → R, 24 sequences, random', e))

    e_lock, lock_ok = 0.0, True
    for seq in rt.EULER_SEQUENCES:
        lock = 0.0 if seq[0].upper() == seq[2].upper() else np.pi / 2
        for delta in (0.0, 1e-9, -1e-9, 1e-7, 1e-5, -1e-5):
            angles = np.column_stack([RNG.uniform(-3, 3, 200), np.full(200, lock + delta),
                                      RNG.uniform(-3, 3, 200)])
            Rl = rt.euler_to_matrix(angles, seq)
            back, flagged = rt.matrix_to_euler(Rl, seq)
            err = np.abs(rt.euler_to_matrix(back, seq) - Rl).max(axis=(1, 2))
            e_lock = max(e_lock, err[~flagged].max(initial=0.0))
            lock_ok &= bool((err[flagged] <= 2 * abs(delta) + 1e-15).all())
    worst = max(worst, report('Euler: near gimbal lock (unflagged), 24 sequences', e_lock))
    print(f'{"Euler: flagged lock reproduces R within 2·distance to lock":<58} {lock_ok}')

    angles = RNG.uniform(-np.pi, np.pi, (N, 3))
    e = 0.0
    for seq in rt.EULER_SEQUENCES:
        a = [ELEMENTARY[c](angles[:, n]) for n, c in enumerate(seq.upper())]
        ref = a[0] @ a[1] @ a[2] if seq.isupper() else a[2] @ a[1] @ a[0]
        e = max(e, np.abs(rt.euler_to_matrix(angles, seq) - ref).max())
    worst = max(worst, report('Euler → R vs product of elementary rotations', e))

    rotvec = rt.matrix_to_rotvec(R)
    worst = max(worst, report('rotation vector: R → θl̂ → R, random',
                              np.abs(rt.rotvec_to_matrix(rotvec) - R).max()))
    axes, angles = adversarial_axis_angles()
    Ra = rt.axis_angle_to_matrix(axes, angles)
    got_axis, got_angle = rt.matrix_to_axis_angle(Ra)
    worst = max(worst, report('axis-angle: angle error near 0, at and near π',
                              np.abs(got_angle - angles).max()))
    sign = np.where(np.einsum('ij,ij->i', got_axis, axes) < 0, -1.0, 1.0)[:, None]
    at_pi = angles == np.pi
    err_vec = np.abs(np.where(at_pi[:, None], sign, 1.0) * got_axis * got_angle[:, None]
                     - axes * angles[:, None]).max()
    worst = max(worst, report('axis-angle: rotation vector error near 0, at and near π',
                              err_vec))
    K = rt.skew(axes[:50] * angles[:50, None])
    series = np.broadcast_to(np.eye(3), K.shape).copy()
    term = series.copy()
    for k in range(1, 40):
        term = term @ K / k
        series += term
    worst = max(worst, report('Rodrigues vs exp series of [θl̂]× (50 hard cases)',
                              np.abs(series - Ra[:50]).max()))

    b = RNG.normal(size=(N, 3)) * 10.0 ** RNG.uniform(-3, 3, (N, 1))
    Rt = np.concatenate([R[:N - len(Ra)], Ra])
    scale = 1.0 + np.linalg.norm(b, axis=1)
    s = rt.screw_from_transform(Rt, b)
    R2, b2 = rt.transform_from_screw(s.direction, s.point, s.angle, s.translation)
    e = max(np.abs(R2 - Rt).max(), (np.abs(b2 - b).max(axis=1) / scale).max())
    worst = max(worst, report('screw: (R, b) → Screw → (R, b), per 1 + |b|', e))
    R3, b3 = rt.screw_exp(rt.screw_log(Rt, b))
    e = max(np.abs(R3 - Rt).max(), (np.abs(b3 - b).max(axis=1) / scale).max())
    worst = max(worst, report('screw: screw_exp(screw_log(R, b)), per 1 + |b|', e))
    moved = np.einsum('nij,nj->ni', Rt, s.point) + b
    along = s.point + s.translation[:, None] * s.direction
    print(f'{"screw: R·c + b = c + d·l̂ (the axis slides along itself), per 1 + |c| + |b|":<58}'
          f' {(np.abs(moved - along).max(axis=1) / (scale + np.abs(s.point).max(1))).max():.2e}')
    print(f'{"worst round trip / cross-check error":<58} {worst:.2e}')
    frames_and_fitting(R, b, axes, angles, Ra)


def homogeneous(R, b):
    T = np.zeros(R.shape[:-2] + (4, 4))
    T[..., :3, :3], T[..., :3, 3], T[..., 3, 3] = R, b, 1.0
    return T


def frames_and_fitting(R, b, axes, angles, Ra):
    """Measure the second-round functions: rigid motions, frames, fitting, quaternions."""
    n = len(R)
    scale = 1.0 + np.linalg.norm(b, axis=1)
    p = RNG.normal(size=(n, 3)) * 10.0 ** RNG.uniform(-3, 3, (n, 1))
    lengths = 10.0 ** RNG.uniform(-3, 3, (n, 3))
    F = rt.frame_to_matrix(*(R[:, :, i] * lengths[:, i:i + 1] for i in range(3)))
    report('frame: (û v̂ ŵ) vs the normalised axes', np.abs(F - R).max())
    ref = np.einsum('nij,nj->ni', homogeneous(R, b), np.c_[p, np.ones(n)])[:, :3]
    report('transform_points vs 4×4 product, per 1 + |b| + |p|',
           (np.abs(rt.transform_points(R, b, p) - ref).max(1)
            / (scale + np.linalg.norm(p, axis=1))).max())
    R2, b2 = R[::-1], b[::-1]
    Rc, bc = rt.compose_transforms(R, b, R2, b2)
    T = homogeneous(R, b) @ homogeneous(R2, b2)
    report('compose vs 4×4 product, per 1 + |b1| + |b2|',
           max(np.abs(Rc - T[:, :3, :3]).max(),
               (np.abs(bc - T[:, :3, 3]).max(1) / (scale + scale[::-1])).max()))
    Ri, bi = rt.compose_transforms(R, b, *rt.invert_transform(R, b))
    report('compose(T, invert(T)) = identity, per 1 + |b|',
           max(np.abs(Ri - np.eye(3)).max(), (np.abs(bi).max(1) / scale).max()))
    Rh, bh = rt.homogeneous_to_transform(rt.transform_to_homogeneous(R, b))
    report('homogeneous → transform round trip', max(np.abs(Rh - R).max(), np.abs(bh - b).max()))

    # distance: R1 = R·Rot(axis, θ) at the adversarial angles, against θ
    d = rt.rotation_distance(R[:len(Ra)], R[:len(Ra)] @ Ra)
    report('rotation_distance near 0, at and near π (vs θ)', np.abs(d - angles).max())
    # mean of rotations about one axis: Rot_z(atan2(Σ w sin θ, Σ w cos θ)) in closed form
    theta = RNG.uniform(-np.pi, np.pi, (20000, 5))
    w = RNG.uniform(0, 1, (20000, 5))
    ref = rt.rot_z(np.arctan2((w * np.sin(theta)).sum(1), (w * np.cos(theta)).sum(1)))
    report('mean_rotation about one axis vs circular mean',
           np.abs(rt.mean_rotation(rt.rot_z(theta), w) - ref).max())
    # align exact data a = R0·b: recovers R0
    vb = RNG.normal(size=(20000, 6, 3)) * 10.0 ** RNG.uniform(-1, 1, (20000, 6, 1))
    R0 = R[:20000]
    va = np.einsum('nij,nkj->nki', R0, vb)
    Rf, rmsd = rt.align_vectors(va, vb)
    report('align_vectors on exact data a = R0·b (vs R0)', np.abs(Rf - R0).max())
    report('align_vectors rmsd on exact data, per max|a|',
           (rmsd / np.abs(va).max(axis=(1, 2))).max())
    # one pair b, a = b turned by π − δ (δ = 0, 1e-15 … 1e-6) about an axis ⊥ b: R·b̂ = â
    ub = RNG.normal(size=(20000, 3))
    ub /= np.linalg.norm(ub, axis=1, keepdims=True)
    perp = np.cross(ub, RNG.normal(size=(20000, 3)))
    perp /= np.linalg.norm(perp, axis=1, keepdims=True)
    delta = np.array([0.0, 1e-15, 1e-12, 1e-9, 1e-6])[RNG.integers(0, 5, 20000)][:, None]
    ua = np.cos(np.pi - delta) * ub + np.sin(np.pi - delta) * np.cross(perp, ub)
    Rp, _ = rt.align_vectors(ua[:, None] * 10.0 ** RNG.uniform(-3, 3, (20000, 1, 1)),
                             ub[:, None] * 10.0 ** RNG.uniform(-3, 3, (20000, 1, 1)))
    ua /= np.linalg.norm(ua, axis=1, keepdims=True)
    report('align_vectors, one (nearly) opposite pair: R·b̂ vs â',
           np.abs(np.einsum('nij,nj->ni', Rp, ub) - ua).max())

    # quaternions: closed form (sin(θ/2)·l̂, cos(θ/2)) at the adversarial angles, round trip
    exact = np.c_[np.sin(angles / 2)[:, None] * axes, np.cos(angles / 2)]
    q = rt.matrix_to_quaternion(Ra)
    report('matrix_to_quaternion vs closed form near 0, at and near π', np.abs(q - exact).max())
    Rall = np.concatenate([R, Ra])
    report('quaternion_to_matrix(matrix_to_quaternion(R))',
           np.abs(rt.quaternion_to_matrix(rt.matrix_to_quaternion(Rall)) - Rall).max())
    # screw_log keeps θ·l̂ at tiny angles (no threshold)
    tiny = 10.0 ** RNG.uniform(-16, -8, 2000)
    tw = rt.screw_log(rt.axis_angle_to_matrix(axes[:2000], tiny), b[:2000])
    report('screw_log: θ·l̂ at θ = 1e-16…1e-8, relative to θ',
           (np.abs(tw[:, :3] - axes[:2000] * tiny[:, None]).max(1) / tiny).max())
    # random_rotations: Kolmogorov–Smirnov distance of the angle to (θ − sin θ)/π
    _, th = rt.matrix_to_axis_angle(rt.random_rotations(N, rng=20261123))
    th.sort()
    cdf = (th - np.sin(th)) / np.pi
    ks = max((np.arange(1, N + 1) / N - cdf).max(), (cdf - np.arange(N) / N).max())
    print(f'{"random_rotations: KS distance to (θ − sin θ)/π, n = 1e5":<58} {ks:.2e}'
          f'  (α = 0.001 limit {1.95 / np.sqrt(N):.2e})')


if __name__ == '__main__':
    main()
