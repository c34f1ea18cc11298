"""
Shared helpers of the bench/ scripts: interleaved timing, medians, result tables.

Every figure the scripts report is a ratio of rot_tools to a reference measured side by side
in one run: the repetitions of the candidates are interleaved (the order rotates from one
repetition to the next), and each candidate's median is taken, so load from other processes
on the machine hits both sides alike. Nothing here asserts a time: these are scripts, not
tests.
"""

import json
import os
import platform
import statistics
import sys
import threading
import time


def interleaved(candidates, repeats):
    """
    Time each zero-argument callable ``repeats`` times, interleaved; {name: [seconds]}.

    Repetition r calls the candidates in the order rotated by r, so no candidate is always
    first (warm caches) or last.
    """
    names = list(candidates)
    times = {name: [] for name in names}
    for r in range(repeats):
        shift = r % len(names)
        for name in names[shift:] + names[:shift]:
            start = time.perf_counter()
            candidates[name]()
            times[name].append(time.perf_counter() - start)
    return times


def median(values):
    """Median of a non-empty sequence."""
    return statistics.median(values)


def verdict(ratio, goal):
    """'yes' / 'NO' for ratio ≤ goal, '-' when there is no goal."""
    if goal is None:
        return '-'
    return 'yes' if ratio <= goal else 'NO'


def fmt_goal(goal):
    return '-' if goal is None else f'<= {goal:g}'


def print_table(title, header, rows, file=None):
    """Print rows (lists of str) under header as an aligned plain-text table."""
    file = file or sys.stdout
    widths = [max(len(str(row[i])) for row in [header] + rows) for i in range(len(header))]
    line = '  '.join('-' * w for w in widths)
    print(f'\n{title}', file=file)
    print('  '.join(str(h).ljust(w) for h, w in zip(header, widths)), file=file)
    print(line, file=file)
    for row in rows:
        print('  '.join(str(c).rjust(w) if i else str(c).ljust(w)
                        for i, (c, w) in enumerate(zip(row, widths))), file=file)
    file.flush()


def machine_line():
    """One line describing the interpreter, NumPy and the machine."""
    import numpy as np
    load = os.getloadavg()[0] if hasattr(os, 'getloadavg') else float('nan')
    return (f'Python {platform.python_version()}, NumPy {np.__version__}, '
            f'{os.cpu_count()} CPU(s), load average {load:.2f} at start')


def write_json(path, payload):
    """Write the results for run_all.py (or anyone) when --json PATH was given."""
    if path:
        with open(path, 'w', encoding='utf-8') as f:
            json.dump(payload, f, indent=1)


def spin_in_thread(rclpy, executor, timeout=0.05):
    """Spin an rclpy executor in a daemon thread until rclpy shuts down; return the thread."""
    def spin():
        try:
            while rclpy.ok():
                executor.spin_once(timeout_sec=timeout)
        except Exception:  # noqa: BLE001 - shut down while spinning: the end
            pass
    thread = threading.Thread(target=spin, daemon=True)
    thread.start()
    return thread


def rss_mb(pid):
    """Resident set size of a process in MB, from /proc (Linux)."""
    with open(f'/proc/{pid}/status', encoding='ascii') as f:
        for line in f:
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) / 1024.0
    raise RuntimeError(f'no VmRSS for pid {pid}')
