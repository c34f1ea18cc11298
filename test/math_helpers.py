"""Independent references for the math tests: plain NumPy from the notes, never rot_tools."""

import itertools
import re

from hypothesis import strategies as st
import numpy as np

PI = np.pi

# The 12 sequence names; upper case intrinsic, lower case extrinsic.
TAIT_BRYAN = ('XYZ', 'XZY', 'YXZ', 'YZX', 'ZXY', 'ZYX')
PROPER = ('XYX', 'XZX', 'YXY', 'YZY', 'ZXZ', 'ZYZ')
INTRINSIC = TAIT_BRYAN + PROPER
ALL_SEQUENCES = INTRINSIC + tuple(s.lower() for s in INTRINSIC)

# Deterministic, bounded hypothesis settings for every property test.
HYPOTHESIS_SETTINGS = {'derandomize': True, 'max_examples': 60, 'deadline': None, 'database': None}


def max_abs(x):
    """Return max |x| over all elements as a Python float (0 for an empty array)."""
    x = np.asarray(x, dtype=float)
    return float(np.max(np.abs(x))) if x.size else 0.0


def ref_elementary(axis, angle):
    """Return Rot_x / Rot_y / Rot_z (Jia §1) for `axis` in 'xyz', batched over `angle`."""
    a = np.asarray(angle, dtype=float)
    c, s = np.cos(a), np.sin(a)
    one, zero = np.ones_like(a), np.zeros_like(a)
    rows = {
        'x': ((one, zero, zero), (zero, c, -s), (zero, s, c)),
        'y': ((c, zero, s), (zero, one, zero), (-s, zero, c)),
        'z': ((c, -s, zero), (s, c, zero), (zero, zero, one)),
    }[axis.lower()]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def ref_euler(angles, seq):
    """Return Rot_a1(t1) Rot_a2(t2) Rot_a3(t3) (intrinsic, upper case), reversed for lower case."""
    angles = np.asarray(angles, dtype=float)
    mats = [ref_elementary(seq[i], angles[..., i]) for i in range(3)]
    if seq.isupper():
        return mats[0] @ mats[1] @ mats[2]
    return mats[2] @ mats[1] @ mats[0]


def singular_values(seq):
    """Middle-angle values at which the sequence is in gimbal lock."""
    return (-PI / 2, PI / 2) if seq.upper() in TAIT_BRYAN else (0.0, PI)


def middle_range(seq):
    """Return the closed range of the middle angle."""
    return (-PI / 2, PI / 2) if seq.upper() in TAIT_BRYAN else (0.0, PI)


def ref_skew(v):
    """Return [v]x of Cayero eq. 17, batched."""
    v = np.asarray(v, dtype=float)
    z = np.zeros(v.shape[:-1])
    x, y, w = v[..., 0], v[..., 1], v[..., 2]
    return np.stack([np.stack([z, -w, y], -1),
                     np.stack([w, z, -x], -1),
                     np.stack([-y, x, z], -1)], -2)


def notes_rodrigues_eq7(axis, angle):
    """Rot_l(theta), Jia eq. 7, element by element as printed (axis must be unit)."""
    axis = np.asarray(axis, dtype=float)
    t = np.asarray(angle, dtype=float)
    lx, ly, lz = axis[..., 0], axis[..., 1], axis[..., 2]
    c, s = np.cos(t), np.sin(t)
    v = 1.0 - c
    return np.stack([
        np.stack([lx * lx * v + c, lx * ly * v - lz * s, lx * lz * v + ly * s], -1),
        np.stack([lx * ly * v + lz * s, ly * ly * v + c, ly * lz * v - lx * s], -1),
        np.stack([lx * lz * v - ly * s, ly * lz * v + lx * s, lz * lz * v + c], -1),
    ], -2)


def notes_rodrigues_eq18(u, phi):
    """R(u, phi) = I cos(phi) + (1 - cos(phi)) u u^T + sin(phi) [u]x (Cayero eq. 18)."""
    u = np.asarray(u, dtype=float)
    phi = np.asarray(phi, dtype=float)[..., None, None]
    return (np.eye(3) * np.cos(phi) + (1.0 - np.cos(phi)) * (u[..., :, None] * u[..., None, :])
            + np.sin(phi) * ref_skew(u))


def expm(a, squarings=None):
    """
    Matrix exponential by scaling and squaring of a Taylor series (no eigen-decomposition).

    Squaring E = exp(A / 2^s) - I as E <- 2E + E E keeps the small part exact.
    """
    a = np.asarray(a, dtype=float)
    n = a.shape[-1]
    block = a[..., :3, :3]
    norm = float(np.max(np.sum(np.abs(block), axis=-1))) if block.size else 0.0
    if squarings is None:
        squarings = max(0, int(np.ceil(np.log2(norm / 0.5)))) if norm > 0.5 else 0
    x = a / 2.0 ** squarings
    term = np.broadcast_to(np.eye(n), a.shape).copy()
    small = np.zeros_like(a)
    for k in range(1, 30):
        term = term @ x / k
        small = small + term
    for _ in range(squarings):
        small = 2.0 * small + small @ small
    return np.eye(n) + small


def expm_twist(twist):
    """(R, b) = exp of the se(3) matrix [[ [w]x, v ], [0, 0]] for twist = (w, v), batched."""
    twist = np.asarray(twist, dtype=float)
    m = np.zeros(twist.shape[:-1] + (4, 4))
    m[..., :3, :3] = ref_skew(twist[..., :3])
    m[..., :3, 3] = twist[..., 3:]
    e = expm(m)
    return e[..., :3, :3], e[..., :3, 3]


def rotate_minus_identity(axis, angle, p):
    """(R - I) p = sin(t) l x p - 2 sin^2(t/2) (p - (p.l) l): exact for tiny t and huge |p|."""
    axis = np.asarray(axis, dtype=float)
    t = np.asarray(angle, dtype=float)[..., None]
    p = np.asarray(p, dtype=float)
    perp = p - np.sum(p * axis, axis=-1, keepdims=True) * axis
    return np.sin(t) * np.cross(axis, p) - 2.0 * np.sin(t / 2.0) ** 2 * perp


def homogeneous(R, b):
    """Return the 4 × 4 matrices [R b; 0 1] of any R (..., 3, 3) and b (..., 3), unchecked."""
    R, b = np.asarray(R, dtype=float), np.asarray(b, dtype=float)
    T = np.zeros(np.broadcast_shapes(R.shape[:-2], b.shape[:-1]) + (4, 4))
    T[..., :3, :3], T[..., :3, 3], T[..., 3, 3] = R, b, 1.0
    return T


def ref_quaternion_to_matrix(q):
    """Textbook unit-quaternion matrix with q = (x, y, z, w), the ROS order."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    x, y, z, w = (q[..., i] for i in range(4))
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def cube_rotations():
    """Return the 24 rotations of the cube: exact signed permutations, at gimbal locks and π."""
    out = []
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1.0, -1.0), repeat=3):
            m = np.zeros((3, 3))
            for row, col in enumerate(perm):
                m[row, col] = signs[row]
            if np.linalg.det(m) > 0:
                out.append(m)
    return np.array(out)


def random_unit_vectors(rng, n):
    """Return n random unit vectors, shape (n, 3)."""
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def random_axis_angle(rng, n):
    """Return (axis (n,3), angle (n,) in [0, pi], R (n,3,3)) built with Jia eq. 7."""
    axis = random_unit_vectors(rng, n)
    angle = rng.uniform(0.0, PI, size=n)
    return axis, angle, notes_rodrigues_eq7(axis, angle)


def random_euler_angles(rng, n, seq):
    """Return n random angle triples in the canonical ranges of `seq`."""
    lo, hi = middle_range(seq)
    return np.stack([rng.uniform(-PI, PI, n), rng.uniform(lo, hi, n),
                     rng.uniform(-PI, PI, n)], axis=-1)


def random_translations(rng, n):
    """Return n translations with norms spread log-uniformly over 1e-3 .. 1e3."""
    return random_unit_vectors(rng, n) * 10.0 ** rng.uniform(-3, 3, size=(n, 1))


def unit(v):
    """Return v / |v|."""
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def screw_motion(direction, point, angle, d):
    """Return (R, b) of the screw: a turn ``angle`` about the line through ``point``, a slide d."""
    u = unit(direction)
    R = notes_rodrigues_eq7(u, angle)
    return R, (np.eye(3) - R) @ np.asarray(point, dtype=float) + d * u


def scipy_rotations(n, seed):
    """Return n rotations (n, 3, 3) drawn by scipy's Rotation.random, an outside sampler."""
    from scipy.spatial.transform import Rotation
    # random_state and a Generator: older SciPy takes no rng=, and both draw the same rotations
    return Rotation.random(n, random_state=np.random.default_rng(seed)).as_matrix()


def wrap(a):
    """Wrap angles to (-pi, pi]."""
    a = np.asarray(a, dtype=float)
    w = np.mod(a + PI, 2 * PI) - PI
    return np.where(w <= -PI, w + 2 * PI, w)


def angle_error(a, b):
    """Max |a - b| taken modulo 2 pi."""
    d = np.abs(np.asarray(a, dtype=float) - np.asarray(b, dtype=float))
    d = np.mod(d, 2 * PI)
    return max_abs(np.minimum(d, 2 * PI - d))


def polar_rotation(m, iterations=60):
    """Orthogonal polar factor by Newton's iteration X <- (X + X^-T) / 2 (no SVD)."""
    x = np.asarray(m, dtype=float)
    for _ in range(iterations):
        x = 0.5 * (x + np.swapaxes(np.linalg.inv(x), -1, -2))
    return x


_NUMBER = re.compile(r'[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?')


def numbers_in(message):
    """All decimal numbers written in a message, as floats."""
    return [float(x) for x in _NUMBER.findall(message)]


def mentions_magnitude(message, value, factor=2.0):
    """Tell whether the message writes a number within `factor` of |value|."""
    value = abs(value)
    return any(value / factor <= abs(x) <= value * factor for x in numbers_in(message))


def _not_tiny(v):
    return np.linalg.norm(v) > 1e-3


def _normalised(v):
    return v / np.linalg.norm(v)


def unit_vectors():
    """Hypothesis strategy: unit 3-vectors (rejecting near-zero draws)."""
    comp = st.floats(-1.0, 1.0, allow_nan=False)
    # (named functions, not lambdas: Hypothesis may look up a lambda's source per draw)
    return st.tuples(comp, comp, comp).map(np.array).filter(_not_tiny).map(_normalised)


def angles_in(lo, hi):
    """Hypothesis strategy: finite floats in [lo, hi]."""
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False)
