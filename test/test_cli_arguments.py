"""The command-line pieces rot-tools and rotation_client share (rot_tools.io.arguments)."""

import argparse
from importlib.metadata import version

import pytest
from rot_tools.cli import main as cli
from rot_tools.io import arguments
from rot_tools.ros.client import arguments as client_arguments


def toy():
    """Return a parser 'toy' with a plain command 'one' and 'nested' with commands of its own."""
    parser = arguments.Parser(prog='toy', description='a toy')

    def deg(p):
        p.add_argument('--deg', action='store_true')
    commands = parser.add_commands(deg, dest='command', metavar='COMMAND', required=True)
    one = commands.add_parser('one', help='numbers', description='the command one')
    one.add_argument('numbers', type=arguments.number, nargs='*')
    one.add_argument('--deg', action='store_true', default=argparse.SUPPRESS)
    one.add_argument('--point', type=arguments.number, nargs=3)
    one.set_defaults(run='one')
    nested = commands.add_parser('nested', help='inputs')

    def cov(p):
        p.add_argument('--cov', nargs=2)
    inner = nested.add_commands(cov, dest='input', metavar='INPUT', required=True)
    nested.set_defaults(run='nested')
    leaf = inner.add_parser('leaf', description='the leaf')
    leaf.add_argument('name')
    leaf.add_argument('words', nargs='*')
    leaf.add_argument('--cov', nargs=2, default=argparse.SUPPRESS)
    return parser


def parse(argv, capsys):
    """Return (namespace or exit status, stdout, stderr) of toy on argv."""
    try:
        result = toy().parse_command_line(argv)
    except SystemExit as exc:
        result = exc.code
    out, err = capsys.readouterr()
    return result, out, err


@pytest.mark.parametrize('line', [
    'one 1 2 3 --deg --point 4 5 6',
    '--deg one 1 2 3 --point 4 5 6',
    'one 1 --deg 2 --point 4 5 6 3',
    'one --point 4 5 6 1 2 --deg 3',
])
def test_options_before_between_and_after_the_words(line, capsys):
    args, out, err = parse(line.split(), capsys)
    assert (out, err) == ('', '')
    assert vars(args) == {'deg': True, 'command': 'one', 'numbers': [1.0, 2.0, 3.0],
                          'point': [4.0, 5.0, 6.0], 'run': 'one'}


@pytest.mark.parametrize('line', [
    'nested --cov a b leaf x y z',
    '--deg nested leaf x --cov a b y z',
    '--deg nested leaf --cov a b x y z',
])
def test_a_command_with_commands_reads_options_anywhere_too(line, capsys):
    args, _, _ = parse(line.split(), capsys)
    assert vars(args) == {'deg': '--deg' in line, 'command': 'nested', 'cov': ['a', 'b'],
                          'input': 'leaf', 'name': 'x', 'words': ['y', 'z'], 'run': 'nested'}


def test_option_defaults_are_kept_and_filled(capsys):
    args, _, _ = parse(['one', '1'], capsys)
    assert vars(args) == {'deg': False, 'command': 'one', 'numbers': [1.0], 'point': None,
                          'run': 'one'}


@pytest.mark.parametrize('line, usage', [
    ('--help', 'usage: toy [-h] [--deg] COMMAND ...\n'),
    ('--help one 1', 'usage: toy [-h] [--deg] COMMAND ...\n'),
    ('one 1 --help', 'usage: toy one [-h] [--deg] [--point POINT POINT POINT] [numbers ...]\n'),
    ('nested --help', 'usage: toy nested [-h] [--cov COV COV] INPUT ...\n'),
    ('nested leaf x --help', 'usage: toy nested leaf [-h] [--cov COV COV] name [words ...]\n'),
])
def test_help_is_the_help_of_the_parser_it_follows(line, usage, capsys):
    status, out, err = parse(line.split(), capsys)
    assert (status, err) == (0, '')
    assert out.startswith(usage), out


@pytest.mark.parametrize('line, message', [
    ('', 'the following arguments are required: COMMAND'),
    ('two 1', "argument COMMAND: invalid choice: 'two'"),
    ('--bogus one 1', 'unrecognized arguments: --bogus'),
    ('one 1 --bogus 2', 'unrecognized arguments: --bogus'),
    ('one 1 x', "argument numbers: not a number: 'x'"),
    ('one 1 --point 1 2', 'argument --point: expected 3 arguments'),
    ('nested', 'the following arguments are required: INPUT'),
    ('nested leaf x --cov a', 'argument --cov: expected 2 arguments'),
    ('nested leaf', 'the following arguments are required: name'),
])
def test_errors_are_one_line_and_status_2(line, message, capsys):
    status, out, err = parse(line.split(), capsys)
    assert (status, out) == (2, '')
    assert err.startswith(f'toy: error: {message}') and err.count('\n') == 1, err


def test_version_is_the_installed_distributions(capsys):
    parser = arguments.Parser(prog='toy one')
    arguments.add_version(parser)
    with pytest.raises(SystemExit) as stop:
        parser.parse_command_line(['--version'])
    assert stop.value.code == 0
    assert capsys.readouterr() == (f'toy {version("rot_tools")}\n', '')


def test_version_without_the_distribution_is_one_error_line(monkeypatch, capsys):
    import importlib.metadata

    def missing(name):
        raise importlib.metadata.PackageNotFoundError(name)
    monkeypatch.setattr(importlib.metadata, 'version', missing)
    assert cli.main(['euler', 'ZYX', '1', '2', '3', '--version']) == 2
    assert capsys.readouterr() == (
        '', 'rot-tools: error: --version: rot_tools is not installed (no distribution '
        'metadata)\n')


# rot-tools' commands, and rotation_client


def test_every_command_is_a_module_with_add_parser_and_run():
    names = set()
    for module in cli.COMMANDS:
        parser = arguments.Parser(prog='rot-tools')
        subparsers = parser.add_commands(lambda p: None, dest='command')
        added = module.add_parser(subparsers)
        assert isinstance(added, argparse.ArgumentParser) and callable(module.run), module
        assert added.prog.startswith('rot-tools '), added.prog
        names.add(added.prog.split()[1])
    assert names >= {'euler', 'matrix', 'axis-angle', 'rotvec', 'quaternion', 'frame', 'screw',
                     'compare', 'covariance'}


@pytest.mark.parametrize('line, numbers', [
    ('euler ZYX --deg 30 20 10', [30.0, 20.0, 10.0]),
    ('euler ZYX 30 --deg 20 10', [30.0, 20.0, 10.0]),
    ('pose 1 0 --frame odom 0.5 0 0 1 0 --json', [1.0, 0.0, 0.5, 0.0, 0.0, 1.0, 0.0]),
    ('imu 0 0 --cov 1 0 0 0 1 0 0 0 1 0 1', [0.0, 0.0, 0.0, 1.0]),
])
def test_rotation_client_reads_options_between_its_numbers(line, numbers):
    args = client_arguments.parse_args(line.split())
    assert args.numbers == numbers
    if 'deg' in line:
        assert args.deg is True and args.sequence == 'ZYX'
    if 'odom' in line:
        assert (args.frame, args.json) == ('odom', True)


def test_both_programs_read_a_sequence_the_same_way(capsys):
    assert cli.main(['euler', 'RPY', '1', '2', '3']) == 2
    rot_tools_line = capsys.readouterr().err
    with pytest.raises(SystemExit) as stop:
        client_arguments.parse_args(['euler', 'RPY', '1', '2', '3'])
    assert stop.value.code == 2
    client_line = capsys.readouterr().err
    assert rot_tools_line.startswith("rot-tools: error: argument SEQ: unknown Euler sequence 'RPY")
    assert client_line == rot_tools_line.replace('rot-tools:', 'rotation_client:', 1)
