"""
``rot-tools bag``: the orientations recorded in a bag, as a summary, a table and a plot.

:func:`add_parser` adds ``bag`` to rot-tools' commands and :func:`run` runs it: one bag here
(:func:`one_bag`), several through rot_tools.cli.fleet. What is read and computed per
topic: rot_tools.cli.bag_analysis; the outputs: rot_tools.cli.bag_output (CSV, plot) and
rot_tools.cli.bag_parquet.
"""

import argparse
import sys

from rot_tools.cli import bag_analysis, bag_parquet, fleet, options, output_file
from rot_tools.cli.bag_output import MAX_PLOTTED_TOPICS, plot_note, write_csv, write_plot
from rot_tools.core.euler import RPY_SEQUENCE
from rot_tools.io import arguments, bag_read
from rot_tools.io.boundary import QUATERNION_TOLERANCE
from rot_tools.io.message_covariance import READINGS
from rot_tools.io.report import DEFAULT_PRECISION


def one_bag(args, error):
    """
    rot-tools bag on the one bag ``args.path``; ``error(text)`` prints one line and exits 2.

    :func:`run` reads the command line's paths and checks the options first, and hands one
    bag given alone to this function. Whatever fails on this bag — the bag itself (a
    BagError), or rot-tools on it (any other exception: bag_analysis.failure names it) — is
    one line, never a traceback; an output file is then left as it was (written whole or
    not at all, rot_tools.cli.output_file), and so it is when a signal stops the command.
    """
    output_file.check_outputs([('--csv', args.csv), ('--plot', args.plot),
                               ('--parquet', args.parquet)], [args.path], error, args.force)
    try:
        with bag_parquet.run_of_one(args.parquet, args.path, error) as parquet:
            return _one_bag(args, error, parquet)
    except bag_read.BagError as exc:
        error(f'bag: {exc}')
    except Exception as exc:  # noqa: BLE001 - one bag's failure is one line, as in a fleet
        error(f'bag: {bag_analysis.failure(args.path, exc)}')


def _one_bag(args, error, parquet):
    from rot_tools.io.report import to_json, to_yaml

    storage, topics = bag_analysis.analyse(
        args.path, args.topic or (), args.start, args.end,
        QUATERNION_TOLERANCE if args.tol is None else args.tol, args.seq, args.wrap,
        tf=args.tf, reading=args.input_covariance)
    if args.plot:
        drawn = topics[:MAX_PLOTTED_TOPICS]
        output_file.write_figure(lambda: write_plot(args.plot, drawn, args.deg), args.plot,
                                 error)
        sys.stderr.write(plot_note(args.plot, drawn, topics[MAX_PLOTTED_TOPICS:]))
    if parquet is not None:
        table = bag_parquet.table(topics, str(args.path), args.deg, args.seq)
        try:
            bag_parquet.keep(parquet, bag_parquet.to_bytes(table))
        except OSError as exc:
            error(f'--parquet: cannot write {parquet}: {exc.strerror or exc}')
    if args.csv is not None:
        output_file.write_table(lambda out: write_csv(out, topics, args.deg, args.precision),
                                args.csv, error)
    if args.csv != '-':
        text = to_json if args.json else to_yaml
        document = text(bag_analysis.summary(args.path, storage, topics, args.deg),
                        precision=args.precision)
        output_file.to_stdout(lambda out: out.write(document))
    for line in bag_analysis.warnings(topics, args.deg):
        sys.stderr.write(f'warning: {line}\n')
    return 0


# ---------------------------------------------------------------------------------------
# The command


TEXT = (
    'Reads rosbag2 (sqlite3, MCAP: a folder or a bare file) and ROS 1 bags without ROS (the\n'
    'rosbags library, the bag extra:\n'
    f"{arguments.install_hint('bag')}). Topics of type PoseStamped,\n"
    'PoseWithCovarianceStamped, Odometry, Imu, QuaternionStamped and TransformStamped are\n'
    "read (default: all of them). Each message passes the checks of rotation_node's\n"
    'inputs: a NaN/Inf, a zero or non-unit quaternion (|q| off 1 by more than --tol,\n'
    f'default {QUATERNION_TOLERANCE:g}), an Imu without orientation is refused and counted '
    'by reason.\n\n'
    'Prints a summary per topic (YAML, or JSON with --json): type, frame ids, messages\n'
    'accepted and refused, start, end, rate, roll/pitch/yaw ranges, total angle turned,\n'
    'mean orientation; for a topic with positions their ranges and the largest speed; for an\n'
    'Imu how far the angular velocity of its orientations is from its gyro (RMS), with a\n'
    'warning beyond a threshold. For Imu, PoseWithCovarianceStamped and Odometry, the median\n'
    'standard deviations of roll, pitch and yaw from their covariances, and how many were\n'
    "unknown or bad. roll, pitch, yaw are REP-103's (about the fixed X, Y, Z axes,\n"
    f'the extrinsic sequence {RPY_SEQUENCE}) and continuous along each topic (no jump at ±180°)\n'
    'unless --wrap. With --csv, one row per accepted message; with --plot, roll, pitch\n'
    'and yaw against time, one panel per topic.')
"""What ``rot-tools bag --help`` says of the command."""


def add_parser(subparsers):
    """Add ``rot-tools bag`` to argparse's subparsers action and return its parser."""
    p = subparsers.add_parser(
        'bag', help='the orientations recorded in a ROS bag: summary, CSV, plot',
        usage=f'{options.PROG} bag PATH... [--topic T]... [--tf REFERENCE BODY] [--seq SEQ] '
        '[--deg]\n'
        '       [--wrap] [--csv FILE|-] [--json] [--plot FILE] [--start S] [--end S]\n'
        '       [--input-covariance rotvec|rpy] [--jobs N] [--parquet DIR]\n'
        '       [--engine dask [--scheduler ADDRESS]]',
        description=f'The orientations recorded in a ROS bag.\n\n{TEXT}',
        epilog='examples:\n  rot-tools bag run.bag\n'
        '  rot-tools bag run.bag --topic /imu/data --csv imu.csv --deg\n'
        '  rot-tools bag rosbag2_dir --plot rpy.png --start 10 --end 20\n'
        '  rot-tools bag recordings/ --jobs 4 --parquet table/')
    p.add_argument('path', metavar='PATH', nargs='+',
                   help='a ROS 1 .bag file, a rosbag2 directory, or a file in one; any other '
                   'directory is searched for bags. Several bags: a summary per bag and '
                   'for the fleet, a bag that cannot be read listed as failed (exit '
                   'status 1), --csv one table with a bag column first')
    p.add_argument('--topic', action='append', metavar='T',
                   help='read this topic (repeat for more); default: every topic of a type '
                   'read')
    p.add_argument('--tf', nargs=2, metavar=('REFERENCE', 'BODY'),
                   help="the transform of BODY in REFERENCE from the bag's /tf and "
                   '/tf_static (tf2_msgs/TFMessage), through rot_tools.TransformTree, at every '
                   'stamp of the dynamic transforms between them (a topic named '
                   'tf:REFERENCE->BODY); other topics then only with --topic')
    p.add_argument('--wrap', action='store_true',
                   help='angles as computed, each in (−180°, 180°], instead of continuous')
    p.add_argument('--csv', metavar='FILE',
                   help='write one row per accepted message to FILE (- = standard output, '
                   'which then gets no summary): topic, stamp (s), frame_id, x, y, z, qx, qy, '
                   'qz, qw (w ≥ 0), roll, pitch, yaw, the --seq angles SEQ_1..3, rotation '
                   'vector rx, ry, rz, angle, body angular velocity wx, wy, wz from the '
                   'previous row of the topic (empty on its first row), standard deviations '
                   'roll_std, pitch_std, yaw_std from the covariance (empty where none is '
                   'known)')
    p.add_argument('--input-covariance', choices=READINGS, default='rotvec',
                   help="how a recorded covariance's rotation block is read, as "
                   "rotation_node's input_covariance: rotvec (default, ROS's "
                   "PoseWithCovariance: rotations about the parent's fixed X, Y, Z) or rpy "
                   '(already roll, pitch, yaw)')
    arguments.add_bag_window(p)
    p.add_argument('--jobs', type=arguments.whole_number, metavar='N',
                   help='read the bags in N processes (default: one per CPU; 1: here, one '
                   'after the other); the output is the same whatever N is')
    p.add_argument('--parquet', metavar='DIR',
                   help='write one Parquet file per bag in DIR: the --csv columns plus bag, '
                   'stamp as int64 nanoseconds (needs pyarrow, the bag extra)')
    options.add_force(p)
    p.add_argument('--engine', choices=('processes', 'dask'), default='processes',
                   help='processes: --jobs N processes here (default); dask: each bag a '
                   'task on a Dask cluster (the fleet extra), a local one of N workers '
                   'unless --scheduler')
    p.add_argument('--scheduler', metavar='ADDRESS',
                   help='with --engine dask: the address of a running Dask scheduler '
                   '(tcp://HOST:8786), whose workers must see the bags and DIR')
    common = p.add_argument_group('common options')
    suppress = argparse.SUPPRESS
    arguments.add_deg(common, 'every angle in degrees (angular velocities in deg/s)', suppress)
    common.add_argument('--seq', type=arguments.sequence, default=suppress, metavar='SEQ',
                        help='also the Euler angles of SEQ (CSV columns SEQ_1..3), '
                        'continuous like roll, pitch, yaw')
    arguments.add_json(common, 'print the summary as JSON instead of YAML', suppress)
    arguments.add_precision(common, 'round numbers to N significant digits and N decimal '
                            f'places (default {DEFAULT_PRECISION}), in the summary and the CSV '
                            '(whose stamps are exact)', suppress)
    common.add_argument('--tol', type=options.tolerance, default=suppress, metavar='TOL',
                        help='largest ||q| − 1| of a recorded quaternion (default '
                        f'{QUATERNION_TOLERANCE:g}, '
                        "rotation_node's quaternion_tolerance); within it q is normalised")
    options.add_plot(common, 'draw roll, pitch, yaw against time, one panel per topic',
                     suppress)
    arguments.add_version(common)
    return p


def run(args):
    """
    Run ``rot-tools bag`` on the parsed ``args``; return the exit status.

    0 when every bag was read; 1 when, among several bags, one could not be; one error line
    and status 2 (options.error) for what stops the command: an option that does not apply,
    a bag given alone that cannot be read, an output that cannot be written. Several bags,
    or a directory searched for bags: rot_tools.cli.fleet.run; one bag: :func:`one_bag`.
    """
    error = options.error
    for option, given in (('--point', args.point), ('--wxyz', args.wxyz),
                          ('--all-sequences', args.all_sequences)):
        if given:
            error(f'{option} does not apply to bag')
    missing = bag_read.rosbags_missing()
    if missing:
        error(f"bag needs the rosbags library ({missing} is missing), the 'bag' extra: "
              f"{arguments.install_hint('bag')}")
    if args.start is not None and args.end is not None and args.end < args.start:
        error(f'--end {args.end:g} is before --start {args.start:g}')
    if args.scheduler is not None and args.engine != 'dask':
        error('--scheduler ADDRESS is the address of a Dask scheduler: it needs --engine dask')
    try:
        bags, searched = fleet.find_bags(args.path)
    except bag_read.BagError as exc:
        error(f'bag: {exc}')
    if len(bags) > 1 or searched:
        return fleet.run(args, bags, error)
    args.path = bags[0]
    fleet.check_extras(args, error)
    return one_bag(args, error)
