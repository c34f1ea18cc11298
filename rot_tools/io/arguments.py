"""
Command-line pieces shared by rot-tools and rotation_client: argparse, no ROS.

Parser (one-line errors, exit status 2, options anywhere among a command's words),
``--version``, value types, the options both programs take and the words of an input.
"""

import argparse
import math
import re
import sys

from rot_tools.core.euler import EULER_SEQUENCES
from rot_tools.io.report import DEFAULT_PRECISION, sequence_hint

EXIT_USAGE = 2
"""Exit status of a program given bad arguments."""

SEQUENCE_HELP = (
    'one of the 12 axis orders XYZ XZY YXZ YZX ZXY ZYX XYX XZX YXY YZY ZXZ ZYZ; '
    'upper case = intrinsic (body axes), lower case = extrinsic (fixed axes)')

COVARIANCE_ENTRIES = tuple(f'C{i}{j}' for i in '123' for j in '123')
"""The names of a 3×3 covariance's entries, row by row."""

NEGATIVE_NUMBER = r'-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?|-(inf|infinity|nan)'
"""A negative number as typed: -30, -.5, -1e-3, -inf, -nan (case ignored)."""


def fail(program, message):
    """Print ``program: error: message`` as one line on stderr and exit with status 2."""
    sys.stderr.write(f'{program}: error: {" ".join(str(message).split())}\n')
    sys.exit(EXIT_USAGE)


def program_name(parser):
    """Return the program's name: the first word of prog ('rot-tools euler' is a command's)."""
    return parser.prog.split()[0]


class Parser(argparse.ArgumentParser):
    """
    An ArgumentParser whose errors are one line, and whose commands take options anywhere.

    argparse reads the words of a command added by add_subparsers with parse_known_args,
    which gives each positional argument the words up to the next option only: the angles of
    ``euler ZYX --deg 30 20 10`` would be left over. parse_intermixed_args reads options
    anywhere among a parser's positionals, but refuses a parser with commands. So a parser
    with commands (:meth:`add_commands`) reads a command line in two steps
    (:meth:`parse_command_line`): its options before the command, the command's name and the
    command's words as they are (``nargs=argparse.REMAINDER``); then those words, by the
    command's own parser, the same way (parse_intermixed_args when it has no commands, or
    parse_args when the words hold ``--``, after which every word is a value as typed).
    """

    def __init__(self, *args, **kwargs):
        kwargs.setdefault('formatter_class', argparse.RawDescriptionHelpFormatter)
        super().__init__(*args, **kwargs)
        self.commands = None
        """argparse's action of this parser's commands (add_subparsers), if it has some."""
        self.add_options = None
        """The function that adds the options that may come before a command."""
        self.defaults = {}
        """What set_defaults set: the namespace gets it even when argv is read in two steps."""

    def set_defaults(self, **kwargs):
        """Set defaults of the namespace, as argparse does (``run=`` a command's function)."""
        super().set_defaults(**kwargs)
        self.defaults.update(kwargs)

    def error(self, message):
        """Print ``PROGRAM: error: message`` on one line and exit 2."""
        fail(program_name(self), message)

    def print_help(self, file=None):
        """Print the help to ``file`` (default stdout); a failed write raises, unlike argparse."""
        (file or sys.stdout).write(self.format_help())

    def add_commands(self, add_options, **kwargs):
        """
        Add the options that come before a command, then return the commands' action.

        ``add_options(parser)`` adds those options: to this parser, and to the parser that
        reads a command line up to its command (:meth:`parse_command_line`). ``kwargs`` go
        to add_subparsers (dest, metavar, required...); each command's parser is a Parser.
        """
        add_options(self)
        self.add_options = add_options
        self.commands = self.add_subparsers(**kwargs)
        return self.commands

    def parse_command_line(self, argv, namespace=None):
        """
        Return the namespace of argv: options before a command, and among its words.

        One bad word exits with one error line (status 2); ``--help`` prints the help of the
        parser it follows and exits 0.
        """
        if self.commands is None:
            if '--' in argv:  # the words after it are values as typed, which argparse's
                return self.parse_args(argv, namespace)  # intermixed reading mishandles
            return self.parse_intermixed_args(argv, namespace)
        leading = Parser(prog=self.prog, add_help=False)
        self.add_options(leading)
        leading.set_defaults(**self.defaults)
        leading.add_argument(self.commands.dest, nargs='?')
        leading.add_argument('words', nargs=argparse.REMAINDER)
        found, unknown = leading.parse_known_args(argv, namespace)
        # argparse keeps each command's parser by name in its action's choices, the names
        # it lists in --help and checks a command against.
        command = self.commands.choices.get(getattr(found, self.commands.dest))
        if command is None or unknown:
            # No command, an unknown one, or an option this level does not know before it
            # (--help among them): argparse reads the line whole and prints the help, or
            # its one error line.
            return self.parse_args(argv, namespace)
        words = found.words
        del found.words
        if len(words) < len(argv) and argv[len(argv) - len(words) - 1] == '--':
            words = ['--', *words]  # argparse drops a '--' right after the command's name
        return command.parse_command_line(words, found)


def version_line(program):
    """
    Return 'PROGRAM VERSION': the installed rot_tools distribution's version (setup.py's).

    importlib.metadata.PackageNotFoundError when rot_tools is not installed.
    """
    from importlib.metadata import version  # only when asked
    return f'{program} {version("rot_tools")}'


class Version(argparse.Action):
    """--version: print :func:`version_line` of the program and exit 0."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS,
                 help='print the version and exit'):  # noqa: A002
        super().__init__(option_strings, dest, nargs=0, default=default, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        from importlib.metadata import PackageNotFoundError
        try:
            text = version_line(program_name(parser))
        except PackageNotFoundError:
            parser.error('--version: rot_tools is not installed (no distribution metadata)')
        print(text)
        parser.exit(0)


def install_hint(extra):
    """Return the command that adds an optional extra to a checkout's install (not on PyPI)."""
    return f"pip install -e '.[{extra}]' in the rot_tools checkout"


def add_version(parser):
    """Add --version to parser."""
    parser.add_argument('--version', action=Version)


# ---------------------------------------------------------------------------------------
# Value types (argparse turns their ArgumentTypeError into 'argument X: message')


def any_number(text):
    """Read a float, NaN and Inf included (a node decides what it refuses)."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'not a number: {text.strip()!r}') from None


def number(text):
    """Read a finite float."""
    value = any_number(text)
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f'not a finite number: {text.strip()!r}')
    return value


def sequence(text):
    """Read one of the 24 Euler sequences; an unknown one's error points at the meant one."""
    if text not in EULER_SEQUENCES:
        raise argparse.ArgumentTypeError(
            f'unknown Euler sequence {text.strip()!r}: use {SEQUENCE_HELP}{sequence_hint(text)}')
    return text


def precision(text):
    """Read a number of significant digits, 1 to 17."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if not 1 <= value <= 17:
        raise argparse.ArgumentTypeError(f'expected an integer 1..17, got {text.strip()!r}')
    return value


def whole_number(text):
    """Read an integer ≥ 1 (argparse type of ``--jobs``, ``--count``), else say why not."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f'must be a whole number >= 1, got {text.strip()!r}')
    return value


def negative_numbers_as_values(argv):
    """
    Return argv with every negative number marked as a value for argparse.

    argparse reads '-30' and '-.5' as values but '-1e-3' or '-inf' as unknown options. A
    word that starts with a space is never an option, and float() ignores the space, so each
    negative number gets one in front (none after '--', where argparse takes words as they
    are). No option of ours looks like a number, so nothing is shadowed.
    """
    words, rest = [], False
    for word in argv:
        rest = rest or word == '--'
        is_number = not rest and re.fullmatch(NEGATIVE_NUMBER, word, re.IGNORECASE)
        words.append(' ' + word if is_number else word)
    return words


# ---------------------------------------------------------------------------------------
# Options and words. ``default=argparse.SUPPRESS`` on a command's parser keeps a value given
# before the command.


def seconds_from_start(text):
    """Parse a number of seconds from a bag's start (>= 0)."""
    value = number(text)
    if value < 0:
        raise argparse.ArgumentTypeError(
            f"must be >= 0 seconds from the bag's start, got {text.strip()!r}")
    return value


def add_bag_window(parser):
    """Add --start S and --end S: the messages recorded between S seconds from a bag's start."""
    parser.add_argument('--start', type=seconds_from_start, metavar='S',
                        help="only messages recorded S seconds or more after the bag's start")
    parser.add_argument('--end', type=seconds_from_start, metavar='S',
                        help="only messages recorded at most S seconds after the bag's start")


def add_deg(parser, text, default=False):
    """Add --deg: angles in degrees (``text`` says which)."""
    parser.add_argument('--deg', action='store_true', default=default, help=text)


def add_json(parser, text='print JSON instead of YAML', default=False):
    """Add --json: JSON instead of YAML."""
    parser.add_argument('--json', action='store_true', default=default, help=text)


def add_precision(parser, text, default=DEFAULT_PRECISION):
    """Add --precision N: significant digits of the numbers printed."""
    parser.add_argument('--precision', type=precision, default=default, metavar='N', help=text)


def add_wxyz(parser, text, default=False):
    """Add --wxyz: quaternions typed w first instead of the ROS order (x, y, z, w)."""
    parser.add_argument('--wxyz', action='store_true', default=default, help=text)


def add_cov(parser, text, type=number, nargs=9, metavar=COVARIANCE_ENTRIES,  # noqa: A002
            default=None):
    """Add --cov C11 .. C33: a rotation's 3×3 covariance, row by row, rad²."""
    parser.add_argument('--cov', type=type, nargs=nargs, metavar=metavar, default=default,
                        help=text)


def add_sequence(parser):
    """Add the word SEQ: an Euler sequence, one of the 24."""
    parser.add_argument('sequence', type=sequence, metavar='SEQ', help=SEQUENCE_HELP)


def add_numbers(parser, dest, metavar, text, type=number):  # noqa: A002
    """Add the numbers of an input, as many as typed: the command counts them."""
    parser.add_argument(dest, type=type, nargs='*', metavar=metavar, help=text)
