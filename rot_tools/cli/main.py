"""
rot-tools: every representation of a rotation or rigid transform, on the command line.

Each command is a module of rot_tools.cli with ``add_parser(subparsers)`` and ``run(args)``;
this module lists them (COMMANDS), reads the command line and runs the command it names.
"""

from contextlib import contextmanager, suppress
import signal
import sys
import threading

from rot_tools.cli import (
    axis_angle, bag, compare, covariance, euler, frame, hand_eye, imu_check, matrix, options,
    output_file, quaternion, rodrigues, rotvec, screw)
from rot_tools.io import arguments

PROG = options.PROG

COMMANDS = (euler, matrix, axis_angle, rotvec, rodrigues, quaternion, frame, screw, bag,
            compare, covariance, imu_check, hand_eye)
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


def _terminated(signum, frame):
    """End the command on SIGTERM as an error ends it, so that its temporary files go."""
    raise SystemExit(EXIT_TERMINATED)


@contextmanager
def _sigterm_unwinds():
    """
    While in this block, SIGTERM raises SystemExit(EXIT_TERMINATED) in the main thread.

    Only where SIGTERM has its default action (a caller's own handler, or SIGTERM ignored,
    stays), and only in the main thread (where Python runs signal handlers). The default
    action is back when the block ends.
    """
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGTERM) != signal.SIG_DFL):
        yield
        return
    signal.signal(signal.SIGTERM, _terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _parse(argv):
    """Return the parsed command line, or None when --help or --version printed all."""
    try:
        return parse_args(sys.argv[1:] if argv is None else argv)
    except OSError as exc:  # --help or --version could not print: the standard output
        output_file.stdout_failed(exc)
    except SystemExit as exc:
        if exc.code not in (0, None):
            raise
        return None


def main(argv=None):
    """
    Run rot-tools on argv (default sys.argv[1:]); return the exit status.

    0 done; 1 the standard output could not be written (one line), or a fleet with a bag
    that failed; 2 bad arguments or input (one line ``rot-tools: error: ...``);
    EXIT_INTERRUPTED (130) after Ctrl-C and EXIT_TERMINATED (143) after SIGTERM, with one
    line ``rot-tools: interrupted`` / ``terminated``; output_file.EXIT_BROKEN_PIPE (141),
    quietly, when the reader of the standard output went away (``| head``). Never a
    traceback for these.
    """
    with _sigterm_unwinds():
        try:
            args = _parse(argv)
            status = 0 if args is None else args.run(args)
            output_file.flush_stdout()
            return status
        except SystemExit as exc:  # one-line errors (2), stdout's, SIGTERM's
            if exc.code == EXIT_TERMINATED:
                _say('terminated')
            return exc.code if isinstance(exc.code, int) else 2
        except KeyboardInterrupt:
            _say('interrupted')
            return EXIT_INTERRUPTED
        except BrokenPipeError:  # the reader of stdout or stderr went away: nothing to say
            output_file.release_stdout()
            return output_file.EXIT_BROKEN_PIPE


def _say(text):
    with suppress(OSError, ValueError, AttributeError):
        sys.stderr.write(f'{PROG}: {text}\n')


if __name__ == '__main__':
    sys.exit(main())
