"""
What the one-shot commands share: their parser's shape, and the report they print.

Each one-shot command (a module each) reads one typed input into (R, b, sequence); run
prints the report as YAML, or JSON with ``--json``, and draws it with ``--plot FILE``.
"""

import sys

from rot_tools.cli import options, output_file, typed_rotation
from rot_tools.io.report import to_json, to_yaml, transform_report


def add_parser(subparsers, name, summary, usage, text, examples, add_arguments):
    """
    Add command ``name`` to argparse's subparsers action and return its parser.

    Its help is ``summary`` (one line, lower case), its usage line ``rot-tools USAGE``, its
    description the summary and ``text``, its epilog the ``examples`` (one a line).
    ``add_arguments(parser)`` adds the command's own words and options; the common options
    follow.
    """
    parser = subparsers.add_parser(
        name, help=summary, usage=f'{options.PROG} {usage}',
        description=f'{summary[0].upper()}{summary[1:]}.\n\n{text}',
        epilog='examples:\n  ' + examples.replace('\n', '\n  '))
    add_arguments(parser)
    options.add_common(parser, suppress=True)
    return parser


def write_plot(path, R, b, degrees):
    """Draw (R, b) into ``path`` with rot_tools.cli.plot, imported only now (matplotlib)."""
    def draw():
        from rot_tools.cli import plot
        plot.save(R, b, path, degrees)

    try:
        output_file.write_figure(draw, path, options.error)
    except ValueError as exc:  # RotationError: a picture too large for float64
        options.error(f'--plot: {exc}')


def run(args, rotation):
    """Print the report of the input ``rotation(args)`` reads; return the exit status (0)."""
    R, b, input_seq = typed_rotation.read(args, rotation, args.command)
    try:
        report = transform_report(R, b, seq=args.seq or input_seq or 'ZYX', degrees=args.deg,
                                  all_sequences=args.all_sequences, point=args.point)
    except ValueError as exc:  # RotationError is a ValueError
        options.error(f'{args.command}: {exc}')
    if args.plot:
        write_plot(args.plot, R, b, args.deg)
    text = to_json if args.json else to_yaml
    output_file.to_stdout(lambda out: out.write(text(report, precision=args.precision)))
    for hint in args.hints:
        sys.stderr.write(f'{options.PROG}: hint: {hint}\n')
    return 0
