"""
rot-tools: every representation of a rotation or rigid transform, on the command line.

No ROS needed: argparse over rot_tools and rot_tools.io.report::

    rot-tools euler ZYX 30 20 10 --deg
    rot-tools matrix 0 -1 0  1 0 0  0 0 1
    rot-tools axis-angle 0 0 1 90 --deg
    rot-tools rotvec 0 0 1.5707963267949
    rot-tools quaternion 0 0 0.7071 0.7071
    rot-tools frame 0 1 0  -1 0 0  0 0 1
    rot-tools matrix 0 -1 0 1  1 0 0 0  0 0 1 0.5  0 0 0 1
    rot-tools screw --euler ZYX 90 0 0 --translation 1 0 0.5 --deg --point 1 2 3
    rot-tools bag run.bag --csv run.csv --plot rpy.png   (the 'bag' extra)
    rot-tools compare est.tum gt.csv --align se3
    rot-tools covariance quaternion 0 0 0 1 --cov 1e-4 0 0 0 1e-4 0 0 0 1e-4 --from rotvec --to rpy

Each command is a module of rot_tools.cli (``axis-angle``: axis_angle) with
``add_parser(subparsers)``, which adds its parser to argparse's subparsers action and returns
it, and ``run(args)``, which runs it and returns the exit status. This module lists them
(COMMANDS), reads the command line and runs the command it names.

The one-shot commands (euler ... screw) print ``transform_report`` (keys documented in
rot_tools.io.report) as YAML, or JSON with ``--json`` (rot_tools.cli.one_shot), of an input
checked at ``--tol`` and made exact (rot_tools.cli.typed_rotation).

Every option is accepted before the command, after its arguments and between them
(rot_tools.io.arguments.Parser.parse_command_line).

Bad input — a wrong count, a non-number, NaN/Inf, a matrix that is not a rotation or is a
reflection, a homogeneous matrix whose last row is not 0 0 0 1, a zero, non-orthogonal or
left-handed frame, a zero quaternion or one too far from unit length, an unknown sequence,
a zero axis with a non-zero angle — prints exactly one line ``rot-tools: error: ...`` on
stderr and exits with status 2. An angle typed without ``--deg`` that is larger than 2π
only gets a one-line ``rot-tools: hint: ...`` on stderr (after the report; status 0).
"""

from contextlib import contextmanager, suppress
import os
import signal
import sys
import threading

from rot_tools.cli import (
    axis_angle, bag, compare, covariance, euler, frame, imu_check, matrix, options,
    output_file, quaternion, rodrigues, rotvec, screw)
from rot_tools.io import arguments

PROG = options.PROG

COMMANDS = (euler, matrix, axis_angle, rotvec, rodrigues, quaternion, frame, screw, bag,
            compare, covariance, imu_check)
"""The modules of rot-tools' commands, in the order --help lists them."""

ONE_SHOT = (euler, matrix, axis_angle, rotvec, rodrigues, quaternion, frame, screw)
"""The one-shot commands, whose first examples the main help shows."""


def build_parser():
    """Build the rot-tools ArgumentParser: the common options, and a parser per command."""
    parser = arguments.Parser(
        prog=PROG,
        description='Print every representation of a rotation or rigid transform: matrix,\n'
        'axis-angle (both solutions), rotation vector, Euler angles, quaternion, and for a\n'
        'transform its homogeneous matrix and screw; with --point, where a point goes.\n'
        'YAML by default, JSON with --json. Angles in radians unless --deg.\n'
        'Options may come before COMMAND, after its arguments or between them.',
        epilog='examples:\n  ' + '\n  '.join(
            module.EXAMPLES.splitlines()[0] for module in ONE_SHOT)
        + '\n  rot-tools bag run.bag --csv run.csv'
        + '\n\n"rot-tools COMMAND --help" explains each command.')
    subparsers = parser.add_commands(lambda p: options.add_common(p, suppress=False),
                                     dest='command', metavar='COMMAND', required=True)
    for module in COMMANDS:
        module.add_parser(subparsers).set_defaults(run=module.run)
    return parser


def parse_args(argv):
    """Return the parsed command line; exit 2 with one error line when it is bad."""
    return build_parser().parse_command_line(arguments.negative_numbers_as_values(argv))


EXIT_INTERRUPTED = 128 + signal.SIGINT
"""Exit status after Ctrl-C (SIGINT): the shell's status for a program ended by it."""

EXIT_TERMINATED = 128 + signal.SIGTERM
"""Exit status after SIGTERM (``kill``, ``timeout``)."""


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where rot-tools is: it unwinds the command as Ctrl-C does."""


def _set_handlers(handlers):
    """
    Give each signal of ``handlers`` ({signum: handler}) its handler; return the previous ones.

    The one place rot-tools sets signal handlers: its handler of SIGINT and SIGTERM
    (:func:`_stop_raising`), and the dispositions it found, set back when main returns.
    """
    return {signum: signal.signal(signum, handler) for signum, handler in handlers.items()}


@contextmanager
def _stop_raising():
    """
    While in this block, SIGINT raises KeyboardInterrupt and SIGTERM Terminated.

    Both then unwind the command: every ``finally`` and ``with`` runs, so partial files are
    removed and worker pools shut down, and :func:`main` says one line. Only in the process
    that entered the block: a process forked from it (a fleet's worker) inherits the handler,
    which there gives the signal its default action back and raises it again, so the worker
    ends as if rot-tools had set no handler, without a traceback of its own. Where Python
    ignores an exception (a function run by os.fork, a ``__del__``: it only prints
    "Exception ignored"), the exception is raised again at the next Python call or return
    out of there (a profile function of one event), so it still reaches the command. A
    signal ignored when rot-tools started (SIGINT for a background job of a script,
    ``nohup``) stays ignored. Outside the main thread (where Python sets no handler) the
    block changes nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    owner = os.getpid()

    def stop(signum, frame):
        if os.getpid() != owner:
            _set_handlers({signum: signal.SIG_DFL})
            signal.raise_signal(signum)
            return
        raise Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()

    def swallowed(unraisable):
        stopped = unraisable.exc_value
        if os.getpid() != owner or not isinstance(stopped, KeyboardInterrupt):  # not stop's
            hook(unraisable)
            return

        def again(frame, event, arg):  # at the next call or return out of this hook
            if frame.f_code is not swallowed.__code__:
                sys.setprofile(None)
                raise stopped.with_traceback(None)
        sys.setprofile(again)

    previous = _set_handlers({signum: stop for signum in (signal.SIGINT, signal.SIGTERM)
                              if signal.getsignal(signum) != signal.SIG_IGN})
    hook, sys.unraisablehook = sys.unraisablehook, swallowed
    try:
        yield
    finally:
        sys.unraisablehook = hook
        sys.setprofile(None)
        _set_handlers({signum: handler for signum, handler in previous.items()
                       if handler is not None})


def _say(text):
    with suppress(OSError, ValueError, AttributeError):
        sys.stderr.write(f'{PROG}: {text}\n')


def main(argv=None):
    """
    Run rot-tools on argv (default sys.argv[1:]); return the exit status.

    0 done; 1 the standard output could not be written (one line), or a fleet with a bag
    that failed; 2 bad arguments or input (one line ``rot-tools: error: ...``);
    EXIT_INTERRUPTED (130) after Ctrl-C and EXIT_TERMINATED (143) after SIGTERM, with one line
    ``rot-tools: interrupted`` / ``rot-tools: terminated`` once the command has cleaned up;
    output_file.EXIT_BROKEN_PIPE (141), quietly, when the reader of the standard output went
    away (``| head``). Never a traceback for any of them.
    """
    with _stop_raising():
        try:
            args = parse_args(sys.argv[1:] if argv is None else argv)
            status = args.run(args)
            output_file.flush_stdout()
            return status
        except SystemExit as exc:  # argparse's --help (0), one-line errors (2), stdout's
            return exc.code if isinstance(exc.code, int) else 0 if exc.code is None else 2
        except Terminated:
            _say('terminated')
            return EXIT_TERMINATED
        except KeyboardInterrupt:
            _say('interrupted')
            return EXIT_INTERRUPTED
        except BrokenPipeError:  # the reader of stdout or stderr went away: nothing to say
            output_file.release_stdout()
            return output_file.EXIT_BROKEN_PIPE


if __name__ == '__main__':
    sys.exit(main())
