"""Measured worst-case errors of rot_tools' round trips and cross-checks (quoted in README).

Run: .venv/bin/python bench/accuracy.py   (numpy only; about 10 s)

Random sets (seeded) of 100,000 rotations / transforms plus the adversarial sets the tests use:
angles within 1e-12 of 0 and π, exactly π, gimbal lock ± 1e-9 … 1e-5 in all 24 sequences,
tiny angles with large translations. Each line prints the largest error found.
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


if __name__ == '__main__':
    main()
