"""
rot_tools.hand_eye on a 10-minute pair of 100 Hz streams, and against OpenCV on stations.

1. **Streams.** Ten minutes (``--minutes``) of an arm waving a camera, both streams at 100 Hz,
   B's clock 0.12 s early (test/hand_eye_helpers.py's arm_streams: 0.05° and 0.5 mm of noise
   on the camera): hand_eye with ``offset='auto'``, the whole job — the time offset, the
   matching, the congruence check, the fit and the jackknife — timed over ``--repeat`` runs
   (median), with its errors against the truth.
2. **Stations.** The same arm at 25, 100 and 400 stations (arm_stations): hand_eye against
   cv2.calibrateHandEye with each of OpenCV's five methods on the same stations, interleaved,
   median; the ratio of the times, and each one's mean errors over the seeds. OpenCV forms
   every pair of stations, as hand_eye does up to 200 samples.

Nothing is asserted. Needs opencv-python-headless and scipy (the test requirements).

    .venv/bin/python bench/bench_hand_eye.py [--minutes 10] [--repeat 3] [--json FILE]
"""

import argparse
import math
from pathlib import Path
import sys

import benchlib
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / 'test'))  # the simulations

from hand_eye_helpers import (  # noqa: E402, I100 (after the path)
    arm_stations, arm_streams, inverted, rotation_error)
from rot_tools import hand_eye  # noqa: E402

METHODS = ('TSAI', 'PARK', 'HORAUD', 'ANDREFF', 'DANIILIDIS')


def _errors(R, b, recording):
    """Return the rotation error (degrees) and the translation error (mm) of X."""
    return (math.degrees(rotation_error(R, recording.X[0])),
            1000 * float(np.linalg.norm(np.ravel(b) - recording.X[1])))


def _ours(r, **options):
    return hand_eye(r.stamps_a, r.R_a, r.b_a, r.stamps_b, r.R_b, r.b_b, **options)


def streams(minutes, repeat):
    """Time hand_eye on the streams; return the figures."""
    r = arm_streams(1, seconds=60.0 * minutes, rate_a=100.0, rate_b=100.0)
    found = []
    times = benchlib.interleaved({'hand_eye': lambda: found.append(_ours(r, offset='auto'))},
                                 repeat)['hand_eye']
    last = found[-1]
    rotation, translation = _errors(last.X.R, last.X.b, r)
    figures = {'minutes': minutes, 'samples': last.samples, 'pairs': last.pairs,
               'seconds': benchlib.median(times), 'offset': last.offset,
               'rotation_error_deg': rotation, 'translation_error_mm': translation}
    print(f'\n{minutes:g} min of two 100 Hz streams: {len(r.stamps_a)} + {len(r.stamps_b)} poses, '
          f'{last.samples} matched, {last.pairs} pairs')
    print(f"hand_eye(offset='auto'): {figures['seconds']:.2f} s (median of {repeat}); "
          f'offset {last.offset:+.4f} s (true +0.12), X off by {rotation:.4f}° and '
          f'{translation:.3f} mm')
    return figures


def stations(count, seeds, repeat):
    """Time hand_eye and OpenCV's five methods on the same stations; return the figures."""
    import cv2
    recordings = [arm_stations(seed, stations=count) for seed in range(seeds)]
    cases = []
    for r in recordings:
        R_m, t_m = inverted(r.R_b, r.b_b)
        cases.append((r, list(r.R_a), list(r.b_a), list(R_m), list(t_m)))
    errors = {name: [] for name in ('hand_eye',) + METHODS}

    def ours():
        for r, *_ in cases:
            found = _ours(r)
            errors['hand_eye'].append(_errors(found.X.R, found.X.b, r))

    def theirs(name):
        method = getattr(cv2, f'CALIB_HAND_EYE_{name}')

        def run():
            for r, R_a, b_a, R_m, t_m in cases:
                R, t = cv2.calibrateHandEye(R_a, b_a, R_m, t_m, method=method)
                errors[name].append(_errors(R, t, r))
        return run

    candidates = {'hand_eye': ours, **{name: theirs(name) for name in METHODS}}
    times = {name: benchlib.median(t) / seeds
             for name, t in benchlib.interleaved(candidates, repeat).items()}
    rows = []
    for name in candidates:
        mean = np.mean(errors[name], axis=0)
        rows.append([name, f'{1000 * times[name]:.2f}', f'{times[name] / times["hand_eye"]:.2f}',
                     f'{mean[0]:.4f}', f'{mean[1]:.3f}'])
    benchlib.print_table(f'{count} stations, {seeds} seeds (time per calibration, median of '
                         f'{repeat}; mean errors of X)',
                         ['method', 'ms', 'time / hand_eye', 'rotation °', 'translation mm'],
                         rows)
    return {name: {'ms': 1000 * times[name], 'rotation_error_deg': float(row[3]),
                   'translation_error_mm': float(row[4])}
            for name, row in zip(candidates, rows)}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--minutes', type=float, default=10.0)
    parser.add_argument('--repeat', type=int, default=3)
    parser.add_argument('--seeds', type=int, default=10)
    parser.add_argument('--json', metavar='FILE')
    args = parser.parse_args(argv)
    print(benchlib.machine_line())
    figures = {'streams': streams(args.minutes, args.repeat)}
    for count in (25, 100, 400):
        figures[f'stations_{count}'] = stations(count, args.seeds, args.repeat)
    if args.json:
        benchlib.write_json(args.json, figures)


if __name__ == '__main__':
    main()
