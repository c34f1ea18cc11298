"""
Simulated hand-eye recordings (T_A(t)·X = Z·T_B(t)), built with scipy's Rotation, not rot_tools.

Noise goes on B's poses in B's own frame: ``noise_deg`` degrees and ``noise_m`` metres per axis.
"""

from typing import NamedTuple

import numpy as np
from scipy.spatial.transform import Rotation


class Recording(NamedTuple):
    """Poses of A and B (stamps, R, b each) and the true X and Z, each (R, b)."""

    stamps_a: np.ndarray
    R_a: np.ndarray
    b_a: np.ndarray
    stamps_b: np.ndarray
    R_b: np.ndarray
    b_b: np.ndarray
    X: tuple
    Z: tuple


def _matrix(rotvec):
    return Rotation.from_rotvec(rotvec).as_matrix()


def _apply(R, b, p):
    return np.einsum('...ij,...j->...i', R, p) + b


def _b_of(R_a, b_a, X, Z):
    """T_B = Z⁻¹·T_A·X for each pose of A."""
    R_ax = R_a @ X[0]
    b_ax = _apply(R_a, b_a, X[1])
    R_b = Z[0].T @ R_ax
    return R_b, (Z[0].T @ (b_ax - Z[1]).T).T


def _noisy(rng, R, b, noise_deg, noise_m):
    """Poses moved by a random small motion in their own frame."""
    n = len(R)
    turn = _matrix(rng.normal(0.0, np.radians(noise_deg), (n, 3)))
    return R @ turn, b + np.einsum('nij,nj->ni', R, rng.normal(0.0, noise_m, (n, 3)))


def _looking_at_origin(position, roll):
    """Rotation of a camera at ``position`` whose z axis points at the origin."""
    z = -position / np.linalg.norm(position)
    x = np.cross([0.0, 0.0, 1.0], z)
    x /= np.linalg.norm(x)
    R = np.column_stack([x, np.cross(z, x), z])
    return R @ _matrix([0.0, 0.0, roll])


def random_mounting(rng, reach=0.1):
    """Return a random X or Z: any rotation, a translation within ±reach per axis."""
    return Rotation.random(random_state=int(rng.integers(1 << 31))).as_matrix(), rng.uniform(
        -reach, reach, 3)


def arm_stations(seed, stations=25, noise_deg=0.05, noise_m=5e-4):
    """Eye in hand: the camera on the hand (X) sees the marker (Z) from ``stations``, 1 s apart."""
    rng = np.random.default_rng(seed)
    X = random_mounting(rng)
    Z = (_matrix([0.0, 0.0, rng.uniform(-np.pi, np.pi)]), np.array([0.6, 0.1, 0.0]))
    R_b, b_b = [], []
    for _ in range(stations):
        elevation = rng.uniform(np.radians(40), np.radians(85))
        azimuth = rng.uniform(-np.pi, np.pi)
        position = rng.uniform(0.4, 0.7) * np.array([
            np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth),
            np.sin(elevation)])
        R_b.append(_looking_at_origin(position, rng.uniform(-np.pi, np.pi))
                   @ _matrix(rng.normal(0.0, np.radians(5.0), 3)))
        b_b.append(position)
    R_b, b_b = np.array(R_b), np.array(b_b)
    R_a = Z[0] @ R_b @ X[0].T
    b_a = _apply(Z[0], Z[1], b_b) - np.einsum('nij,j->ni', R_a, X[1])
    stamps = np.arange(float(stations))
    return Recording(stamps, R_a, b_a, stamps, *_noisy(rng, R_b, b_b, noise_deg, noise_m), X, Z)


def inverted(R, b):
    """Return the inverse motions (Rᵀ, −Rᵀ·b): the marker in the camera from the reverse."""
    Rt = np.swapaxes(R, -1, -2)
    return Rt, -np.einsum('...ij,...j->...i', Rt, b)


def flipped(recording, indices, degrees=25.0, seed=0):
    """Return the recording with the detections at ``indices`` flipped as a planar marker's."""
    rng = np.random.default_rng(seed)
    R_b, b_b = recording.R_b.copy(), recording.b_b.copy()
    for k in indices:
        R_m, t_m = inverted(R_b[k], b_b[k])  # the marker in the camera
        axis = np.cross(t_m, rng.normal(size=3))
        R_m = _matrix(np.radians(degrees) * axis / np.linalg.norm(axis)) @ R_m
        R_b[k], b_b[k] = inverted(R_m, t_m)
    return recording._replace(R_b=R_b, b_b=b_b)


def _smooth_motion(rng, t, turn=0.6, reach=0.12):
    """Orientations and positions of a hand waving over a table: sums of slow sines."""
    freq = rng.uniform(0.08, 0.35, (2, 3, 3))
    phase = rng.uniform(0.0, 2 * np.pi, (2, 3, 3))
    waves = np.sin(2 * np.pi * freq[..., None] * t + phase[..., None]).sum(axis=2) / 3
    R = _matrix([np.pi, 0.0, 0.0]) @ _matrix(turn * waves[0].T)
    b = np.array([0.5, 0.0, 0.4]) + reach * waves[1].T
    return R, b


def arm_streams(seed, seconds=60.0, rate_a=100.0, rate_b=30.0, shift=0.12, noise_deg=0.05,
                noise_m=5e-4):
    """Eye in hand in motion: A at rate_a Hz, B at rate_b Hz stamped ``shift`` s early."""
    rng = np.random.default_rng(seed)
    X = random_mounting(rng)
    Z = random_mounting(rng, 0.5)
    stamps_a = np.arange(0.0, seconds, 1.0 / rate_a)
    true_b = np.arange(rng.uniform(0, 1.0 / rate_b), seconds, 1.0 / rate_b)
    R_a, b_a = _smooth_motion(np.random.default_rng(seed + 1), stamps_a)
    R_bt, b_bt = _smooth_motion(np.random.default_rng(seed + 1), true_b)
    R_b, b_b = _noisy(rng, *_b_of(R_bt, b_bt, X, Z), noise_deg, noise_m)
    return Recording(stamps_a, R_a, b_a, true_b - shift, R_b, b_b, X, Z)


def mobile_base(seed, seconds=120.0, rate=10.0, noise_deg=0.05, noise_m=5e-4):
    """Drive a robot on a floor: A its odometry (x, y, yaw), B its camera's visual odometry."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, 1.0 / rate)
    yaw = 1.2 * np.sin(2 * np.pi * 0.03 * t) + 0.4 * np.sin(2 * np.pi * 0.11 * t + 1.0)
    speed = 0.4 + 0.2 * np.sin(2 * np.pi * 0.05 * t)
    heading = np.column_stack([np.cos(yaw), np.sin(yaw), np.zeros_like(yaw)])
    b_a = np.cumsum(speed[:, None] * heading / rate, axis=0)
    R_a = _matrix(np.column_stack([np.zeros((len(t), 2)), yaw]))
    forward = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])  # z ahead, x right
    X = (forward @ _matrix(np.radians([2.0, -3.0, 4.0])), np.array([0.3, 0.05, 0.5]))
    Z = (R_a[0] @ X[0], _apply(R_a[0], b_a[0], X[1]))  # the camera's first pose
    R_b, b_b = _noisy(rng, *_b_of(R_a, b_a, X, Z), noise_deg, noise_m)
    return Recording(t, R_a, b_a, t, R_b, b_b, X, Z)


def eye_to_hand(seed, stations=20, noise_deg=0.05, noise_m=5e-4):
    """Eye to hand: X is the marker on the hand, Z the fixed camera in the base."""
    rng = np.random.default_rng(seed)
    X = (_matrix(rng.normal(0.0, 0.3, 3)), np.array([0.0, 0.02, 0.08]))
    Z = (_looking_at_origin(np.array([0.0, -0.8, 0.9]), 0.3), np.array([0.5, -0.8, 0.9]))
    rotvec = rng.normal(0.0, 0.35, (stations, 3)) + [np.pi, 0.0, 0.0]
    R_a = _matrix(rotvec)
    b_a = np.array([0.5, 0.0, 0.3]) + rng.uniform(-0.15, 0.15, (stations, 3))
    R_b, b_b = _noisy(rng, *_b_of(R_a, b_a, X, Z), noise_deg, noise_m)
    stamps = np.arange(float(stations))
    return Recording(stamps, R_a, b_a, stamps, R_b, b_b, X, Z)


def rotation_error(R, R_true):
    """Return the angle (rad) between two rotations, by scipy."""
    return float(Rotation.from_matrix(R @ R_true.T).magnitude())


def write_tum(path, stamps, R, b):
    """Write poses as a TUM file (t x y z qx qy qz qw), every digit of float64 kept."""
    q = Rotation.from_matrix(R).as_quat()
    with open(path, 'w', encoding='utf-8') as out:
        for row in np.column_stack([stamps, b, q]):
            out.write(' '.join(repr(float(x)) for x in row) + '\n')
    return path
