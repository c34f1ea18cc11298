"""
TransformTree: a tree of frames joined by rigid motions, looked up at any time (TF's job).

An edge is the motion from a child frame to its parent, p_parent = R·p_child + b, static or
sampled in time; a lookup composes the edges between two frames, each dynamic one
interpolated by its constant screw. doc/tf.md has the rules of time, refusals and memory.
"""

__all__ = ['TransformLookupError', 'TransformTree', 'TransformTreeError']

import math
import numbers
import threading
from typing import NamedTuple

import numpy as np
from rot_tools.core._arrays import as_float_array
from rot_tools.core.errors import RotationError
from rot_tools.core.rigid import Motion
from rot_tools.core.screw import screw_interpolate
from rot_tools.core.so3 import validate_rotation

UNKNOWN_FRAME = 'unknown_frame'
NOT_CONNECTED = 'not_connected'
EXTRAPOLATION = 'extrapolation'
LOOKUP_REASONS = (UNKNOWN_FRAME, NOT_CONNECTED, EXTRAPOLATION)
"""Reasons a lookup is refused for (TransformLookupError.reason)."""

BAD_FRAME = 'bad_frame'
LOOP = 'loop'
NON_FINITE = 'non_finite'
NOT_ROTATION = 'not_rotation'
BAD_VALUE = 'bad_value'
TOO_MANY_FRAMES = 'too_many_frames'

DEFAULT_MAX_SAMPLES = 100_000
"""Samples kept per dynamic edge at most: 10 s at 10 kHz (each sample is 13 float64)."""

DEFAULT_MAX_FRAMES = 10_000
"""Frames a tree holds at most (a few kB each); a transform that would add more is refused."""

MAX_FRAME_NAME = 256
"""Characters a frame name has at most (ROS frame names are a few dozen); longer: bad_frame."""

SHOWN_NAME = 40
"""Characters of a frame name shown in a message at most (a name may be long junk)."""

_MIN_CAPACITY = 16
_IDENTITY = np.eye(3)
_ZERO = np.zeros(3)


class TransformTreeError(RotationError):
    """A refusal of the transform tree; ``reason`` is a short key for counting."""

    def __init__(self, reason, message):
        super().__init__(message)
        self.reason = reason


class TransformLookupError(TransformTreeError):
    """
    A lookup that cannot be answered; ``reason`` is one of LOOKUP_REASONS.

    For ``extrapolation``, ``edge`` is the (parent, child) pair whose data does not reach the
    time asked and ``seconds`` (> 0) how far outside it that time is; else both are None.
    """

    def __init__(self, reason, message, edge=None, seconds=None):
        super().__init__(reason, message)
        self.edge = edge
        self.seconds = seconds


class Lookup(NamedTuple):
    """A lookup's answer: p_reference = R·p_body + b at ``stamp`` (see TransformTree.lookup)."""

    R: np.ndarray
    b: np.ndarray
    stamp: object
    """The time looked up at: a float, or the array of stamps asked for."""


class TimeRange(NamedTuple):
    """The times at which a chain can be looked up, ``first`` to ``last`` (seconds)."""

    first: float
    last: float


class Transforms(NamedTuple):
    """
    Transforms as recorded, for follow.

    parent, child (n frame names each), R (n, 3, 3) and b (n, 3) of p_parent = R·p_child + b,
    stamp (n,) seconds, static (n,) bool (from /tf_static).
    """

    parent: object
    child: object
    R: np.ndarray
    b: np.ndarray
    stamp: np.ndarray
    static: np.ndarray


class Followed(NamedTuple):
    """
    A frame followed over a recording (TransformTree.follow).

    The lookups' stamp (m,), R (m, 3, 3) and b (m, 3), in time order; chains: the chains of
    frames looked up through, in time order (one unless a frame was re-parented); refused:
    {index of a transform: the TransformTreeError that refused it}.
    """

    stamp: np.ndarray
    R: np.ndarray
    b: np.ndarray
    chains: list
    refused: dict


class _Branches(NamedTuple):
    """The frames from reference, and from body, up to (not including) their common ancestor."""

    up: list
    down: list


def shown(frame):
    """Return repr(frame) cut to SHOWN_NAME characters ('…' marking the cut): for messages."""
    text = repr(frame)
    return text if len(text) <= SHOWN_NAME else text[:SHOWN_NAME - 1] + '…'


def _frame_name(frame, what):
    if not isinstance(frame, str) or not frame:
        raise TransformTreeError(
            BAD_FRAME, f'{what} frame must be a non-empty string, got {shown(frame)}')
    if len(frame) > MAX_FRAME_NAME:
        raise TransformTreeError(
            BAD_FRAME, f'{what} frame {shown(frame)} has {len(frame):,} characters, at most '
            f'MAX_FRAME_NAME = {MAX_FRAME_NAME}')
    return frame


def _number(value, name):
    """Return a real number as a float (bools and values beyond float64 refused)."""
    if isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_)):
        try:
            return float(value)
        except OverflowError:
            raise RotationError(f"{name} is beyond float64's range") from None
    raise RotationError(f'{name} must be a number, got {value!r}')


class _Edge:
    """
    One frame's edge to its parent: samples sorted by stamp, in a window of arrays.

    The samples are stamps[start:end], R[start:end], b[start:end]; a static edge has one.
    Appending in time order writes at ``end`` (amortised O(1), no reallocation per sample);
    the window slides forward as old samples expire.
    """

    __slots__ = ('parent', 'static', 'stamps', 'R', 'b', 'start', 'end')

    def __init__(self, parent, static, capacity):
        self.parent, self.static = parent, static
        self.stamps = np.empty(capacity)
        self.R = np.empty((capacity, 3, 3))
        self.b = np.empty((capacity, 3))
        self.start = self.end = 0

    @property
    def count(self):
        return self.end - self.start

    @property
    def oldest(self):
        return float(self.stamps[self.start])

    @property
    def newest(self):
        return float(self.stamps[self.end - 1])

    def _room(self, needed, max_samples):
        """Make room for ``needed`` samples after ``end``: arrays doubled, to max_samples + 1."""
        capacity = len(self.stamps)
        if self.end + needed <= capacity:
            return
        wanted = self.count + needed
        if wanted > capacity // 2:
            capacity = max(wanted, min(2 * capacity, max_samples + 1))
        self._move(capacity)

    def _move(self, capacity):
        """Move the samples to the front of arrays of ``capacity`` (new ones if it changes)."""
        count = self.count
        window = slice(self.start, self.end)
        stamps, R, b = self.stamps[window], self.R[window], self.b[window]
        if capacity != len(self.stamps):
            self.stamps = np.empty(capacity)
            self.R = np.empty((capacity, 3, 3))
            self.b = np.empty((capacity, 3))
        # Moving to the front of the same arrays: the regions may overlap, so copy first.
        self.stamps[:count], self.R[:count], self.b[:count] = stamps.copy(), R.copy(), b.copy()
        self.start, self.end = 0, count

    def add(self, stamp, R, b, cache_seconds, max_samples):
        """Store one sample; 0 if it is older than the cache window, else 1."""
        if self.count and stamp <= self.newest:
            if stamp < self.newest - cache_seconds:
                return 0
            i = self.start + int(np.searchsorted(self.stamps[self.start:self.end], stamp))
            if self.stamps[i] != stamp:  # out of order: shift the newer samples by one
                self._room(1, max_samples)
                i = self.start + int(np.searchsorted(self.stamps[self.start:self.end], stamp))
                for array in (self.stamps, self.R, self.b):
                    array[i + 1:self.end + 1] = array[i:self.end].copy()
                self.end += 1
        else:
            self._room(1, max_samples)
            i = self.end
            self.end += 1
        self.stamps[i], self.R[i], self.b[i] = stamp, R, b
        self._expire(cache_seconds, max_samples)
        return 1

    def add_many(self, stamps, R, b, cache_seconds, max_samples):
        """Store samples (any order; at equal stamps the last given wins); the number kept."""
        window = slice(self.start, self.end)
        old = self.count
        all_stamps = np.concatenate([self.stamps[window], stamps])
        order = np.argsort(all_stamps, kind='stable')
        all_stamps = all_stamps[order]
        last = np.append(all_stamps[1:] != all_stamps[:-1], True)  # last of each equal run
        keep = order[last]
        merged = all_stamps[last]
        kept = int(np.count_nonzero(keep[merged >= merged[-1] - cache_seconds][-max_samples:]
                                    >= old))
        all_R = np.concatenate([self.R[window], R])[keep]
        all_b = np.concatenate([self.b[window], b])[keep]
        self.start = self.end = 0
        self._room(len(merged), max_samples)
        n = len(merged)
        self.stamps[:n], self.R[:n], self.b[:n] = merged, all_R, all_b
        self.end = n
        self._expire(cache_seconds, max_samples)
        return kept

    def _expire(self, cache_seconds, max_samples):
        cutoff = self.stamps[self.end - 1] - cache_seconds
        if self.stamps[self.start] < cutoff:
            self.start += int(np.searchsorted(self.stamps[self.start:self.end], cutoff))
        self.start = max(self.start, self.end - max_samples)
        capacity = len(self.stamps)
        if capacity > _MIN_CAPACITY and self.count <= capacity // 4:  # give memory back
            self._move(max(_MIN_CAPACITY, 2 * self.count))

    def at(self, t, child, query):
        """(R, b) of the edge at times t (a float64 array), interpolated; or refused."""
        if self.static:
            shape = t.shape
            return Motion(np.broadcast_to(self.R[self.start], shape + (3, 3)),
                          np.broadcast_to(self.b[self.start], shape + (3,)))
        stamps = self.stamps[self.start:self.end]
        low, high = t.min(), t.max()
        if low < stamps[0] or high > stamps[-1]:
            self._refuse(low, high, child, query)
        Rs, bs = self.R[self.start:self.end], self.b[self.start:self.end]
        i1 = np.searchsorted(stamps, t)  # stamps[i1] ≥ t, and i1 > 0 unless t = stamps[0]
        exact = stamps[i1] == t
        R, b = Rs[i1], bs[i1]
        if not exact.all():
            between = ~exact
            j = i1[between]
            t0, t1 = stamps[j - 1], stamps[j]
            s = (t[between] - t0) / (t1 - t0)
            if len(j) == 1:  # one item: screw_interpolate's own one-item path, not a batch of 1
                j, s = j[0], s[0]
            R[between], b[between] = screw_interpolate(Rs[j - 1], bs[j - 1], Rs[j], bs[j], s,
                                                       check=False)
        return Motion(R, b)

    def _refuse(self, low, high, child, query):
        first, last = self.oldest, self.newest
        if low < first:
            seconds, side, asked = first - low, 'before the oldest sample', low
        else:
            seconds, side, asked = high - last, 'after the newest sample', high
        held = (f'it has one sample, at {first:.9g} s' if self.count == 1
                else f'it has samples from {first:.9g} to {last:.9g} s')
        raise TransformLookupError(
            EXTRAPOLATION,
            f'{query} at t = {asked:.9g} s would extrapolate {seconds:.6g} s {side} of the '
            f'edge {shown(self.parent)} → {shown(child)} ({held})',
            edge=(self.parent, child), seconds=float(seconds))


class TransformTree:
    """
    Frames joined by static and dynamic rigid motions; lookups at any time, across the tree.

    cache_seconds: how long a dynamic edge keeps its samples (before its newest), > 0, inf
    allowed (a bag read whole). max_samples: the most samples a dynamic edge keeps.
    max_frames: the most frames the tree holds (a transform adding more is refused).

    Each frame but a root has one parent; its edge (set_transform) is the motion from the
    child to the parent, a ROS TransformStamped with header.frame_id = parent. A lookup goes
    up from ``body`` to the common ancestor and down to ``reference``, each edge walked down
    inverted. At a time t a dynamic edge is interpolated between its samples around t by
    the constant screw, T(t) = T0·exp(s·log(T0⁻¹·T1)), s = (t − t0)/(t1 − t0), exact in
    SE(3); a t outside its samples is refused (TransformLookupError, reason
    ``extrapolation``); no t means the latest common time of the chain's dynamic edges.
    A dynamic edge keeps its last ``cache_seconds`` of samples, at most ``max_samples``.
    The tree is safe to share between threads.
    """

    def __init__(self, cache_seconds=10.0, *, max_samples=DEFAULT_MAX_SAMPLES,
                 max_frames=DEFAULT_MAX_FRAMES):
        cache_seconds = _number(cache_seconds, 'cache_seconds')
        if not cache_seconds > 0:
            raise RotationError(f'cache_seconds must be > 0, got {cache_seconds!r}')
        if (not isinstance(max_samples, numbers.Integral) or isinstance(max_samples, bool)
                or max_samples < 2):
            raise RotationError(f'max_samples must be an integer ≥ 2, got {max_samples!r}')
        if (not isinstance(max_frames, numbers.Integral) or isinstance(max_frames, bool)
                or max_frames < 2):
            raise RotationError(f'max_frames must be an integer ≥ 2, got {max_frames!r}')
        self.max_frames = int(max_frames)
        self.cache_seconds = cache_seconds
        self.max_samples = int(max_samples)
        self._edges = {}  # child -> _Edge
        self._frames = set()
        self._lock = threading.RLock()

    # -- feeding ------------------------------------------------------------------------

    def set_transform(self, parent, child, R, b, stamp, static=False):
        """
        Set the edge child → parent: p_parent = R·p_child + b at ``stamp`` (seconds).

        R (3, 3) and b (3,) for one sample, or R (n, 3, 3), b (n, 3) and stamp (n,) for many
        samples of one dynamic edge. A static edge holds at every time (its stamp is kept for
        the latest common time of all-static chains). Returns the number of samples stored
        (0 for samples older than the edge's cache window). Raises TransformTreeError with
        reason bad_frame, loop, non_finite, not_rotation or bad_value; the tree is then
        unchanged.
        """
        parent = _frame_name(parent, 'parent')
        child = _frame_name(child, 'child')
        try:
            R = as_float_array(R, (3, 3), 'R')
            b = as_float_array(b, (3,), 'translation b')
            stamps = as_float_array(stamp, (), 'stamp')
        except RotationError as exc:
            raise TransformTreeError(BAD_VALUE, str(exc)) from None
        many = stamps.ndim > 0
        if R.ndim != 2 + many or b.ndim != 1 + many or stamps.ndim > 1 or (
                many and not len(R) == len(b) == len(stamps) > 0):
            raise TransformTreeError(BAD_VALUE, (
                'set_transform takes R (3, 3), b (3,) and a stamp, or R (n, 3, 3), b (n, 3) '
                f'and stamps (n,) with n > 0; got R {R.shape}, b {b.shape}, stamp '
                f'{stamps.shape}'))
        if many and static:
            raise TransformTreeError(BAD_VALUE, 'a static edge takes one transform, not '
                                                f'{len(stamps)}')
        for name, value in (('R', R), ('translation b', b), ('stamp', stamps)):
            finite = np.isfinite(value)
            if not finite.all():
                first = tuple(int(i) for i in np.argwhere(~finite)[0])
                raise TransformTreeError(
                    NON_FINITE, f'the transform {shown(parent)} → {shown(child)} is not '
                    f'finite: {name} has {value[first]} at index {first}')
        try:
            validate_rotation(R)
        except RotationError as exc:
            raise TransformTreeError(
                NOT_ROTATION, f'the transform {shown(parent)} → {shown(child)}: {exc}') from None
        with self._lock:
            self._refuse_loop(parent, child)
            new = len({parent, child} - self._frames)
            if new and len(self._frames) + new > self.max_frames:
                raise TransformTreeError(
                    TOO_MANY_FRAMES, f'the transform {shown(parent)} → {shown(child)} would add '
                    f'{new} frame(s) to a tree that holds {len(self._frames)}, at most '
                    f'max_frames = {self.max_frames}')
            edge = self._edges.get(child)
            if edge is None or edge.parent != parent or edge.static != bool(static):
                edge = _Edge(parent, bool(static), 1 if static else _MIN_CAPACITY)
            if static:
                edge.stamps[0], edge.R[0], edge.b[0] = stamps, R, b
                edge.end = stored = 1
            elif many:
                stored = edge.add_many(stamps, R, b, self.cache_seconds, self.max_samples)
            else:
                stored = edge.add(float(stamps), R, b, self.cache_seconds, self.max_samples)
            if edge.count:
                self._edges[child] = edge
                self._frames.update((parent, child))
            return stored

    def _refuse_loop(self, parent, child):
        frame, path = parent, [parent]
        while frame != child:
            edge = self._edges.get(frame)
            if edge is None:
                return
            frame = edge.parent
            path.append(frame)
        cycle = ' → '.join(map(shown, [child] + path))
        raise TransformTreeError(
            LOOP, f'the transform {shown(parent)} → {shown(child)} would make {shown(child)} '
            f'its own ancestor (a loop: {cycle}); refused')

    def forget(self, frame):
        """
        Drop the edge of ``frame`` to its parent, with its samples; nothing if it has none.

        The frame, and its parent, stay known while an edge names them (a frame with
        children stays, as a root); else they are forgotten (unknown_frame, and no longer
        counted against max_frames).
        """
        with self._lock:
            edge = self._edges.pop(frame, None)
            if edge is None:
                return
            named = set(self._edges)
            named.update(e.parent for e in self._edges.values())
            self._frames.difference_update({frame, edge.parent} - named)

    # -- the shape of the tree ---------------------------------------------------------

    @property
    def frames(self):
        """Every frame seen so far, sorted."""
        with self._lock:
            return sorted(self._frames)

    def parent(self, frame):
        """Return the parent of ``frame`` (None for a root); TransformLookupError if unknown."""
        with self._lock:
            self._require_known(frame)
            edge = self._edges.get(frame)
            return None if edge is None else edge.parent

    def _require_known(self, frame):
        if not isinstance(frame, str):
            raise RotationError(f'a frame name must be a string, got {shown(frame)}')
        if frame not in self._frames:
            known = ', '.join(map(shown, sorted(self._frames)[:20])) or 'none yet'
            raise TransformLookupError(
                UNKNOWN_FRAME, f'frame {shown(frame)} is unknown (known frames: {known})')

    def _path(self, reference, body):
        """Return the _Branches of reference and body; TransformLookupError if none join."""
        self._require_known(reference)
        self._require_known(body)
        ancestors, frame = {}, reference
        while True:
            ancestors[frame] = len(ancestors)
            edge = self._edges.get(frame)
            if edge is None:
                break
            frame = edge.parent
        down, frame = [], body
        while frame not in ancestors:
            down.append(frame)
            edge = self._edges.get(frame)
            if edge is None:
                root = next(reversed(ancestors))
                raise TransformLookupError(
                    NOT_CONNECTED, f'frames {shown(reference)} and {shown(body)} are not '
                    f'connected: {shown(reference)} is in the tree of {shown(root)}, '
                    f'{shown(body)} in the tree of {shown(frame)}')
            frame = edge.parent
        return _Branches(list(ancestors)[:ancestors[frame]], down)

    def chain(self, reference, body):
        """
        Return the frames from ``reference`` to ``body``, both ends included.

        Through their common ancestor: ['odom', 'base_link', 'camera']; [f] for f in itself.
        """
        with self._lock:
            up, down = self._path(reference, body)
            common = self._edges[up[-1]].parent if up else reference
            return up + [common] + down[::-1]

    def time_range(self, reference, body):
        """
        Return TimeRange (first, last): when every dynamic edge of the chain has data.

        (-inf, inf) for a chain of static edges only.
        """
        with self._lock:
            up, down = self._path(reference, body)
            dynamic = [e for e in map(self._edges.get, up + down) if not e.static]
            if not dynamic:
                return TimeRange(-math.inf, math.inf)
            return TimeRange(max(e.oldest for e in dynamic), min(e.newest for e in dynamic))

    def latest_common_time(self, reference, body):
        """
        Return the time ``lookup(reference, body)`` answers at: the latest common time.

        The newest time at which every dynamic edge of the chain has data (tf2's "time 0");
        with static edges only, the newest stamp they were set with; a frame in itself, the
        newest stamp of its own edge (0 for a root).
        """
        with self._lock:
            return self._latest(*self._path(reference, body), reference)

    def _latest(self, up, down, frame):
        edges = [self._edges[f] for f in up + down]
        dynamic = [e.newest for e in edges if not e.static]
        if dynamic:
            return min(dynamic)
        if edges:
            return max(e.newest for e in edges)
        edge = self._edges.get(frame)
        return 0.0 if edge is None else edge.newest

    # -- lookups -------------------------------------------------------------------------

    def lookup(self, reference, body, stamp=None):
        """
        Return a Lookup (R, b, stamp): ``body`` in ``reference``, p_reference = R·p_body + b.

        stamp: seconds (float) or an array of them (then R (..., 3, 3), b (..., 3) and the
        stamps (...) come back as arrays); None for the latest common time. Each dynamic
        edge is interpolated by the constant-screw motion. TransformLookupError with reason
        unknown_frame, not_connected or extrapolation.
        """
        with self._lock:
            up, down = self._path(reference, body)
            if stamp is None:
                t = self._latest(up, down, reference)
                times = np.array(t)
            else:
                times = as_float_array(stamp, (), 'stamp')
                if not np.isfinite(times).all():
                    raise RotationError(f'the lookup stamp must be finite, got {stamp!r}')
                if times.size == 0:
                    raise RotationError(f'the lookup stamps are empty (shape {times.shape})')
                t = times.copy() if times.ndim else float(times)
            query = f'lookup of {shown(body)} in {shown(reference)}'
            flat = times.reshape(-1)
            R_up, b_up = self._compose(up, flat, query)
            R_down, b_down = self._compose(down, flat, query)
        # T_reference_body = T_common_reference⁻¹ · T_common_body.
        Rt = np.swapaxes(R_up, -1, -2)
        R = Rt @ R_down
        b = np.einsum('...ij,...j->...i', Rt, b_down - b_up)
        shape = times.shape
        return Lookup(R.reshape(shape + (3, 3)), b.reshape(shape + (3,)), t)

    def _compose(self, frames, t, query):
        """
        Return T_common_x of the first frame x of ``frames`` at times t (n,).

        ``frames``: x's chain up to the common ancestor; E(x_k)···E(x), the identity for none.
        """
        R = np.broadcast_to(_IDENTITY, t.shape + (3, 3))
        b = np.broadcast_to(_ZERO, t.shape + (3,))
        for frame in frames:  # from x up: T ← E(y)·T
            edge = self._edges[frame]
            Re, be = edge.at(t, frame, query)
            b = np.einsum('...ij,...j->...i', Re, b) + be
            R = Re @ R
        return Motion(R, b)

    # -- a recording ---------------------------------------------------------------------

    def follow(self, reference, body, transforms):
        """
        Look ``body`` up in ``reference`` over a recording of transforms (TF over a bag).

        transforms: Transforms, in the order they were recorded. The tree is fed as the
        recording goes: a frame's samples under one parent (and static or dynamic) are one
        batch (set_transform), given when the first of them comes, which replaces the
        frame's edge to an earlier parent. Between two such re-parentings the chain is looked
        up as one batch at every stamp of its dynamic edges at which all of them have data
        (and once, at the latest common time, where its edges are static). The tree's cache
        must hold the recording: ``TransformTree(math.inf, max_samples=len(transforms))``.

        Returns Followed; a batch the tree refuses is in ``refused`` and the rest goes on.
        Raises TransformLookupError when no lookup could be made at all.
        """
        stamps = np.asarray(transforms.stamp, dtype=np.float64)
        static = np.asarray(transforms.static, dtype=bool)
        names = {}  # frame -> a number, to sort and cut by
        parent = np.array([names.setdefault(f, len(names)) for f in transforms.parent], np.intp)
        child = np.array([names.setdefault(f, len(names)) for f in transforms.child], np.intp)
        # Runs: one child's samples in stamp order (then as recorded), cut where its parent or
        # its kind (static or dynamic) changes: each is one set_transform.
        order = np.lexsort((np.arange(len(stamps)), stamps, child))
        key = np.stack([child[order], parent[order], static[order]], axis=1)
        cuts = np.flatnonzero((key[1:] != key[:-1]).any(axis=1)) + 1
        runs = sorted(np.split(order, cuts) if len(order) else [],
                      key=lambda rows: (stamps[rows[0]], rows.min()))
        feeds, seen = {}, set()  # when a run is given -> the runs; a frame's first at once
        for rows in runs:
            frame = child[rows[0]]
            feeds.setdefault(stamps[rows[0]] if frame in seen else -math.inf, []).append(rows)
            seen.add(frame)
        times = sorted(feeds) + [math.inf]
        found, refused, chains, error = [], {}, [], None
        for lo, hi in zip(times[:-1], times[1:]):
            for rows in feeds[lo]:
                self._feed(transforms, rows, stamps, static, refused)
            try:
                at = self._chain_stamps(reference, body, lo, hi)
                chain = self.chain(reference, body)
                if len(at):
                    found.append(self.lookup(reference, body, at))
                    chains += [chain] if chain not in chains else []
            except TransformLookupError as exc:
                error = exc
        if not found:
            raise error or TransformLookupError(
                EXTRAPOLATION, f'no time at which every edge between {shown(reference)} and '
                f'{shown(body)} has data')
        return Followed(np.concatenate([f.stamp for f in found]),
                        np.concatenate([f.R for f in found]),
                        np.concatenate([f.b for f in found]), chains, refused)

    def _feed(self, transforms, rows, stamps, static, refused):
        """set_transform of one run (rows); a refusal is noted for each of its rows."""
        first, last = int(rows[0]), int(rows[-1])
        parent, child = str(transforms.parent[first]), str(transforms.child[first])
        try:
            if static[first]:  # a static edge holds one transform: the last given
                self.set_transform(parent, child, transforms.R[last], transforms.b[last],
                                   stamps[last], static=True)
            else:
                self.set_transform(parent, child, transforms.R[rows], transforms.b[rows],
                                   stamps[rows])
        except TransformTreeError as exc:
            refused.update(dict.fromkeys(rows.tolist(), exc))

    def _chain_stamps(self, reference, body, lo, hi):
        """
        Return the times in [lo, hi) to look the chain from reference to body up at.

        Its dynamic edges' stamps where all have data; else its latest common time.
        """
        with self._lock:
            up, down = self._path(reference, body)
            dynamic = [self._edges[f] for f in up + down if not self._edges[f].static]
            if not dynamic:
                t = self._latest(up, down, reference)
                return np.array([t] if lo <= t < hi or lo == -math.inf else [])
            first, last = self.time_range(reference, body)
            t = np.unique(np.concatenate([e.stamps[e.start:e.end] for e in dynamic]))
            return t[(t >= max(lo, first)) & (t < hi) & (t <= last)]
