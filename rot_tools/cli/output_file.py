"""
Output files written whole or not at all (``--csv FILE``, ``--plot FILE``), never over an input.

A file has no name until it is complete (:func:`complete_or_nothing`): on Linux it is made
unnamed (O_TMPFILE) in its directory and linked into place once whole, so whatever ends the
process meanwhile — an exception, SIGTERM, SIGKILL, the OOM killer — leaves nothing that
looks like the finished file, and NAME keeps what it held before. Elsewhere a temporary name
(``.NAME.XXXXXXXX.partial``, never the final suffix) is renamed once complete. A NAME that
exists and is not a regular file (``/dev/null``, a FIFO) is written directly: renaming over
it would replace the device or the pipe.

:func:`check_outputs` is the one guard of every command's output paths: it refuses an output
that is an input, lies in an input bag, or is another output, before anything is written.
:func:`to_stdout` writes to the standard output: a closed pipe ends the command quietly
(status 141, as SIGPIPE's), a full disk with one line (status 1), never a traceback.
"""

from contextlib import contextmanager, suppress
import os
from pathlib import Path
import secrets
import signal
import stat
import sys

from rot_tools.cli import options
from rot_tools.io import arguments, bag_read


_PARTIAL = set()
"""The temporary names this process writes under (where a file cannot be unnamed)."""


def _unnamed(directory):
    """Return a descriptor of a new file without a name in ``directory``, or None."""
    if not hasattr(os, 'O_TMPFILE') or not os.path.isdir('/proc/self/fd'):
        return None  # not Linux: no unnamed files, or no way to name one
    try:
        return os.open(directory, os.O_TMPFILE | os.O_WRONLY, 0o666)  # umask applies
    except OSError:  # a file system without them (NFS, overlayfs of older kernels)
        return None


def _temporary(name):
    """Return a temporary name for ``name``: never its suffix, within 255 bytes."""
    return f'.{name[:200]}.{secrets.token_hex(4)}.partial'


def _regular_or_new(path):
    try:
        return stat.S_ISREG(os.stat(path).st_mode)
    except FileNotFoundError:
        return True


@contextmanager
def complete_or_nothing(path, mode='w', **open_args):
    """
    Yield a file object on a file that no one sees until it is complete, then is ``path``.

    On Linux the file is made without a name (O_TMPFILE) in ``path``'s directory: whatever
    ends the process while it is written — an exception, SIGTERM, SIGKILL, the OOM killer —
    leaves nothing behind, as the kernel drops an unnamed file with its last descriptor. Once
    complete it is linked under a temporary name and renamed to ``path`` (atomic in one
    directory); ``path``, if it was there, holds its old content until then. Where files
    cannot be unnamed, it is written under a temporary name (``.NAME.XXXXXXXX.partial``)
    that an exception removes, and :func:`remove_partials` too before a worker ends itself.
    A ``path`` that is not a regular file (/dev/null, a FIFO) is written directly: renaming
    over it would replace the device or the pipe.
    """
    if not _regular_or_new(path):
        with open(path, mode, **open_args) as out:
            yield out
        return
    directory, name = os.path.split(os.path.abspath(path))
    fd = _unnamed(directory)
    if fd is not None:
        with open(fd, mode, **open_args) as out:
            yield out
            out.flush()
            where = os.open(directory, os.O_RDONLY | os.O_DIRECTORY)
            try:
                temporary = _temporary(name)
                os.link(f'/proc/self/fd/{fd}', temporary, dst_dir_fd=where)  # linkat, follows
                try:
                    os.replace(temporary, name, src_dir_fd=where, dst_dir_fd=where)
                except BaseException:
                    with suppress(OSError):
                        os.unlink(temporary, dir_fd=where)
                    raise
            finally:
                os.close(where)
        return
    partial = os.path.join(directory, _temporary(name))
    fd = os.open(partial, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    _PARTIAL.add(partial)
    try:
        with open(fd, mode, **open_args) as out:
            yield out
        os.replace(partial, path)
    except BaseException:
        with suppress(OSError):
            os.unlink(partial)
        raise
    finally:
        _PARTIAL.discard(partial)


def remove_partials():
    """Remove the temporary files this process is writing: it is about to end abruptly."""
    for partial in list(_PARTIAL):
        with suppress(OSError):
            os.unlink(partial)


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
        error("--plot needs matplotlib, the 'plot' extra: " + arguments.install_hint('plot'))
    except OSError as exc:
        error(f'--plot: cannot write {path}: {exc.strerror or exc}')


def _real(path):
    """Return the absolute path, every symlink and ``..`` resolved (as far as it exists)."""
    try:
        return Path(path).resolve()
    except (OSError, RuntimeError):  # a symlink loop: compared as typed, made absolute
        return Path(os.path.abspath(path))


def _stat(path):
    try:
        return os.stat(path)
    except (OSError, ValueError):
        return None


def _protected(path):
    """
    Return (what an input protects, is it a bag) for one input path.

    A rosbag2 directory (one holding metadata.yaml) protects itself and everything in it, and
    so does any file of one (its storage files, metadata.yaml); any other input protects
    itself, a bag when it is a directory or ends in .bag, .db3 or .mcap.
    """
    real = _real(path)
    if real.is_dir():
        return real, True
    if (real.parent / 'metadata.yaml').exists():
        return real.parent, True
    return real, real.suffix.lower() in bag_read.BAG_SUFFIXES


def check_outputs(outputs, inputs, error=None):
    """
    Refuse, before anything is written, an output path that would destroy an input or output.

    outputs: [(option, path)] of every file or directory the command writes (``--csv``,
    ``--plot``, ``--parquet`` ...); a path that is None (not asked for) or ``-`` (the
    standard output) passes, and so does an existing character device (/dev/null). inputs:
    every path the command reads (text files, bags; None is skipped). An output is refused
    when, with symlinks and relative paths resolved, it is an input (or a hard link to one),
    lies inside an input bag (a rosbag2 directory: the directory, its metadata.yaml, its
    storage files; a bag file), or is the same file as another output. ``error(text)``
    (default rot_tools.cli.options.error: one line, exit 2) says which and why.
    """
    error = options.error if error is None else error
    protected = [(str(path), *_protected(path)) for path in inputs if path is not None]
    seen = []
    for option, path in outputs:
        if path is None or str(path) == '-':
            continue
        target, found = _real(path), _stat(path)
        if found is not None and stat.S_ISCHR(found.st_mode):
            continue
        for given, area, bag in protected:
            source = _stat(given)
            if (target == area or target.is_relative_to(area)
                    or (found is not None and source is not None
                        and os.path.samestat(found, source))):
                what = f'the bag being read ({given})' if bag else f'an input ({given})'
                error(f'{option} {path} would overwrite {what}: refused')
        for other_option, other, other_target, other_found in seen:
            if target == other_target or (found is not None and other_found is not None
                                          and os.path.samestat(found, other_found)):
                error(f'{option} {path} and {other_option} {other} are the same file: refused')
        seen.append((option, path, target, found))


EXIT_STDOUT = 1
"""Exit status when the standard output cannot be written (a full disk, a closed stdout)."""

EXIT_BROKEN_PIPE = 128 + signal.SIGPIPE
"""Exit status when the reader of the standard output went away (``| head``): the shell's
status for a program ended by SIGPIPE, as rotation_client's."""


def release_stdout():
    """Point the standard output at /dev/null: what could not be written is dropped."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):  # None, or a stream of no file (a test's)
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)
    os.close(devnull)


def _say(text):
    with suppress(AttributeError, OSError, ValueError):  # a stderr closed too says nothing
        sys.stderr.write(f'{options.PROG}: error: {text}\n')


def stdout_failed(exc):
    """
    End the command for the standard output that ``exc`` (an OSError) could not write.

    The reader gone (BrokenPipeError: ``| head``, ``| true``) ends it quietly with
    EXIT_BROKEN_PIPE; anything else (``> /dev/full``) with one line ``rot-tools: error:
    cannot write to stdout: ...`` and EXIT_STDOUT. The standard output then points at
    /dev/null, so that Python's own flush at exit has nothing left to fail on.
    """
    release_stdout()
    if isinstance(exc, BrokenPipeError):
        raise SystemExit(EXIT_BROKEN_PIPE) from None
    _say(f'cannot write to stdout: {exc.strerror or exc}')
    raise SystemExit(EXIT_STDOUT) from None


class _Stdout:
    """sys.stdout as a writer sees it: what fails in writing to it ends the command."""

    __slots__ = ()

    def write(self, text):
        try:
            return sys.stdout.write(text)
        except OSError as exc:
            stdout_failed(exc)


def flush_stdout():
    """Flush the standard output; stdout_failed when it cannot be written."""
    if sys.stdout is None:
        return
    try:
        sys.stdout.flush()
    except OSError as exc:
        stdout_failed(exc)


def to_stdout(write):
    """
    Run ``write(out)``, where ``out.write(text)`` writes to the standard output, and flush it.

    Only the standard output's own failures are taken for it (stdout_failed): ``write``'s
    other errors (reading a bag, say) go on as they are. A standard output that was closed
    when rot-tools started is the same one line, status EXIT_STDOUT.
    """
    if sys.stdout is None:
        _say('cannot write to stdout: it is closed')
        raise SystemExit(EXIT_STDOUT)
    write(_Stdout())
    flush_stdout()
