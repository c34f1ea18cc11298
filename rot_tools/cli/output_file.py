"""
Output files written whole or not at all (``--csv FILE``, ``--plot FILE``).

A file is written under a temporary name in its own directory (``.NAME.XXXXXXXX.partial``:
never the final suffix, so nothing mistakes it for the finished file) and renamed to NAME
only once it is complete and closed; a write that fails (a full disk, a signal) removes
the temporary file and leaves whatever NAME held before. ``os.replace`` in one directory is
atomic on POSIX. A NAME that exists and is not a regular file (``/dev/null``, a FIFO) is
written directly: renaming over it would replace the device or the pipe.
"""

from contextlib import contextmanager, suppress
import os
import stat
import tempfile


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
