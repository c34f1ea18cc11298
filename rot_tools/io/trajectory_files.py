"""
Trajectory text files: TUM and EuRoC ground truth, read into stamps, rotations and positions.

TUM: ``t x y z qx qy qz qw`` (the ROS order), separated by spaces. EuRoC: ``timestamp [ns],
p_x, p_y, p_z, q_w, q_x, q_y, q_z[, …]``, comma separated. Lines starting with ``#`` are
comments. Every refusal is a TrajectoryFileError naming the file, the line and the value.
"""

from typing import NamedTuple

import numpy as np
from rot_tools.core.so3 import quaternion_to_matrix
from rot_tools.core.stamps import order_stamps, plain
from rot_tools.io.boundary import QUATERNION_TOLERANCE


class TrajectoryFileError(ValueError):
    """A trajectory file that cannot be read: which file, which line, what is wrong."""


class Poses(NamedTuple):
    """
    A stream of poses: stamps (N,) s, R (N, 3, 3), b (N, 3) or None, and its format.

    Stamps strictly increasing; dropped_duplicates and reordered: what putting them in order
    took (order_stamps).
    """

    stamps: np.ndarray
    R: np.ndarray
    b: np.ndarray
    name: str
    dropped_duplicates: int = 0
    reordered: int = 0


def _data_lines(path):
    """[(line number, text)] of the file's lines that are neither blank nor comments."""
    try:
        with open(path, encoding='utf-8-sig') as text:
            lines = text.read().splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise TrajectoryFileError(f'{path}: cannot read it: {getattr(exc, "strerror", exc)}')
    return [(number, line) for number, line in enumerate(lines, 1)
            if line.strip() and not line.lstrip().startswith('#')]


def _table(path, lines, separator, least, exact):
    """(line numbers, numbers (N, least)) of the data lines; TrajectoryFileError if one fails."""
    rows, numbers = [], []
    for number, line in lines:
        cells = line.split(separator) if separator else line.split()
        if len(cells) < least or (exact and len(cells) > least):
            raise TrajectoryFileError(
                f'{path}:{number}: {len(cells)} values, {least}{"" if exact else " or more"} '
                f'expected: {line.strip()[:80]!r}')
        try:
            values = [float(c) for c in cells[:least]]
        except ValueError:
            raise TrajectoryFileError(
                f'{path}:{number}: not a number in {line.strip()[:80]!r}') from None
        if not np.isfinite(values).all():
            raise TrajectoryFileError(f'{path}:{number}: NaN or Inf in {line.strip()[:80]!r}')
        rows.append(number)
        numbers.append(values)
    if not numbers:
        raise TrajectoryFileError(f'{path}: no pose in the file')
    return np.array(rows), np.array(numbers, dtype=float)


def _poses(path, rows, stamps, b, q, name, strict):
    """Poses of one file: its quaternions of unit norm checked, its stamps put in order."""
    norm = np.linalg.norm(q, axis=1)
    off = np.abs(norm - 1)
    if (off > QUATERNION_TOLERANCE).any():
        k = int(np.argmax(off))
        raise TrajectoryFileError(
            f'{path}:{rows[k]}: quaternion of norm {norm[k]:.6g}, off 1 by more than '
            f'{QUATERNION_TOLERANCE:g}')
    back = stamps[1:] <= stamps[:-1]
    if strict and back.any():
        k = int(np.argmax(back)) + 1
        if stamps[k] == stamps[k - 1]:
            problem = f'duplicate stamp {plain(stamps[k])} (as on line {rows[k - 1]})'
        else:
            problem = (f'stamp {plain(stamps[k])} goes back from {plain(stamps[k - 1])} on '
                       f'line {rows[k - 1]}')
        raise TrajectoryFileError(f'{path}:{rows[k]}: {problem}')
    order = order_stamps(stamps)
    keep = order.index
    return Poses(stamps[keep], quaternion_to_matrix(q[keep] / norm[keep, None]), b[keep], name,
                 order.dropped_duplicates, order.reordered)


def read_tum(path, lines=None, strict=False):
    """Poses of a TUM file (``t x y z qx qy qz qw``); lines: its _data_lines when read."""
    rows, table = _table(path, lines or _data_lines(path), None, 8, True)
    return _poses(path, rows, table[:, 0], table[:, 1:4], table[:, 4:8], 'TUM', strict)


def read_euroc(path, lines=None, strict=False):
    """Poses of an EuRoC ground-truth CSV (``ns, x, y, z, qw, qx, qy, qz, …``)."""
    rows, table = _table(path, lines or _data_lines(path), ',', 8, False)
    q = table[:, [5, 6, 7, 4]]  # w x y z → x y z w
    return _poses(path, rows, table[:, 0] / 1e9, table[:, 1:4], q, 'EuRoC', strict)


def read_text(path, strict=False):
    """
    Poses of a TUM or EuRoC file: EuRoC when its first data line holds a comma.

    strict: refuse a stamp that repeats or goes back (TrajectoryFileError) instead of
    putting the lines in order.
    """
    lines = _data_lines(path)
    if not lines:
        raise TrajectoryFileError(f'{path}: no pose in the file')
    read = read_euroc if ',' in lines[0][1] else read_tum
    return read(path, lines, strict)
