"""
Output files: written whole or not at all, never over an input or, unasked, a recording.

:func:`complete_or_nothing` writes a file under a temporary name and renames it once complete;
:func:`check_outputs` is the one guard of every command's output paths; :func:`to_stdout`
writes the standard output (a closed pipe ends the command quietly, a full disk with one line).
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


def _regular_or_new(path):
    try:
        return stat.S_ISREG(os.stat(path).st_mode)
    except FileNotFoundError:
        return True


@contextmanager
def complete_or_nothing(path, mode='w', **open_args):
    """
    Yield a file object whose content becomes ``path`` when the block ends without an exception.

    It is written under a temporary name in ``path``'s directory, ``.NAME.XXXXXXXX.partial``
    (never NAME's suffix), and renamed to ``path`` (os.replace) once complete. An exception
    (an error, Ctrl-C, SIGTERM in rot-tools) removes the temporary file and leaves ``path`` as
    it was; only SIGKILL leaves the temporary file behind. A ``path`` that exists and is not a
    regular file (/dev/null, a FIFO) is written directly: renaming would replace it.
    """
    if not _regular_or_new(path):
        with open(path, mode, **open_args) as out:
            yield out
        return
    directory, name = os.path.split(os.path.abspath(path))
    partial = os.path.join(directory, f'.{name[:200]}.{secrets.token_hex(4)}.partial')
    try:
        with open(os.open(partial, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666), mode,
                  **open_args) as out:
            yield out
        os.replace(partial, path)
    except BaseException:
        with suppress(OSError):
            os.unlink(partial)
        raise


def write_table(write, path, error):
    """
    Call ``write(out)`` with the CSV file ``path`` open, or the standard output for '-'.

    The file is written whole or not at all (complete_or_nothing); ``error(text)`` prints
    one line and exits 2 when it cannot be written.
    """
    if path == '-':
        to_stdout(write)
        return
    try:
        with complete_or_nothing(path, 'w', encoding='utf-8', newline='') as out:
            write(out)
    except OSError as exc:
        error(f'--csv: cannot write {path}: {exc.strerror or exc}')


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


def _recording(path):
    """Whether ``path`` is a recording: a bag file, or a rosbag2 directory or a file in one."""
    real = _real(path)
    if real.is_dir():
        return (real / 'metadata.yaml').exists()
    return real.exists() and (real.suffix.lower() in bag_read.BAG_SUFFIXES
                              or (real.parent / 'metadata.yaml').exists())


def check_outputs(outputs, inputs, error=None, force=False):
    """
    Refuse, before anything is written, an output path that would destroy an input or output.

    outputs: [(option, path)] of every file or directory the command writes (``--csv``,
    ``--plot``, ``--parquet`` ...); a path that is None (not asked for) or ``-`` (the
    standard output) passes, and so does an existing character device (/dev/null). inputs:
    every path the command reads (None is skipped). An output is refused when, with symlinks
    and relative paths resolved, it is an input (or a hard link to one), lies inside an input
    bag, is the same file as another output, or, unless ``force`` (``--force``), is a
    recording (:func:`_recording`). ``error(text)`` (default rot_tools.cli.options.error: one
    line, exit 2) says which and why.
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
        if not force and _recording(path):
            error(f'{option} {path} is a recording (a bag): refused; --force writes over it')
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
