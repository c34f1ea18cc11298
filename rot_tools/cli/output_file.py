"""
Output files written whole or not at all (``--csv FILE``, ``--plot FILE``), never over an input.

A file is written under a temporary name in its own directory (``.NAME.XXXXXXXX.partial``:
never the final suffix, so nothing mistakes it for the finished file) and renamed to NAME
only once it is complete and closed; a write that fails (a full disk, a signal) removes
the temporary file and leaves whatever NAME held before. ``os.replace`` in one directory is
atomic on POSIX. A NAME that exists and is not a regular file (``/dev/null``, a FIFO) is
written directly: renaming over it would replace the device or the pipe.

:func:`refuse_overwriting` refuses an output that is the bag being read (or a file of its
rosbag2 directory); :func:`to_stdout` writes to the standard output, a closed pipe ending
quietly.
"""

from contextlib import contextmanager, suppress
import os
from pathlib import Path
import stat
import sys
import tempfile

from rot_tools.io import bag_read


def _regular_or_new(path):
    try:
        return stat.S_ISREG(os.stat(path).st_mode)
    except FileNotFoundError:
        return True


@contextmanager
def complete_or_nothing(path, mode='w', **open_args):
    """Yield a file object open on a temporary name; rename it to ``path`` when complete."""
    if not _regular_or_new(path):
        with open(path, mode, **open_args) as out:
            yield out
        return
    directory, name = os.path.split(os.path.abspath(path))
    fd, partial = tempfile.mkstemp(prefix=f'.{name}.', suffix='.partial', dir=directory)
    try:
        umask = os.umask(0)
        os.umask(umask)
        os.fchmod(fd, 0o666 & ~umask)  # as open() would create it, not mkstemp's 0600
        with open(fd, mode, **open_args) as out:
            yield out
        os.replace(partial, path)
    except BaseException:
        with suppress(OSError):
            os.unlink(partial)
        raise


def write_figure(draw, path, error):
    """
    Call ``draw()``, which writes the figure at ``path`` with matplotlib (the 'plot' extra).

    ``error(text)`` prints one line and exits 2 when matplotlib is missing or the file
    cannot be written.
    """
    try:
        draw()
    except ImportError as exc:
        if not (exc.name or '').startswith(('matplotlib', 'mpl_toolkits')):
            raise
        error("--plot needs matplotlib, the 'plot' extra: pip install 'rot_tools[plot]'")
    except OSError as exc:
        error(f'--plot: cannot write {path}: {exc.strerror or exc}')


def refuse_overwriting(bag, outputs, error):
    """
    Call ``error`` if an output file is the bag: the same file, or a file in its directory.

    outputs: [(option, path or None)]; ``-`` is the standard output. The bag is what
    rot_tools.io.bag_read.bag_paths opens (a rosbag2 directory for a file inside one).
    """
    try:
        inputs = [Path(p).resolve() for p in bag_read.bag_paths(bag)] + [Path(bag).resolve()]
    except bag_read.BagError:
        return  # the analysis says what is wrong with it
    for option, path in outputs:
        if path is None or path == '-':
            continue
        target = Path(path).resolve()
        for source in inputs:
            if (target == source or (source.is_dir() and target.is_relative_to(source))
                    or (target.exists() and os.path.samefile(target, source))):
                error(f'{option} {path} would overwrite the bag being read ({bag}): refused')


def release_stdout():
    """Point the standard output at /dev/null: what could not be written is dropped."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)


def to_stdout(write, error):
    """
    Run ``write(sys.stdout)`` and flush it.

    A closed pipe ends quietly (status 0, as ``| head`` expects); a full disk or a closed
    standard output is one error line (status 2).
    """
    if sys.stdout is None:
        error('cannot write to the standard output: it is closed')
    try:
        write(sys.stdout)
        sys.stdout.flush()
    except BrokenPipeError:  # `rot-tools bag ... --csv - | head`: the reader is done
        release_stdout()
    except OSError as exc:
        release_stdout()
        error(f'cannot write to the standard output: {exc.strerror or exc}')
