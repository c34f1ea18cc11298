"""The node and client outputs shown in doc/node.md and doc/client.md, produced for real."""

import re
import shlex
import subprocess

from conftest import console_script, NodeProcess, REPO, script_env
from doc_blocks import assert_doc_output, console_steps, doc_block
import pytest

CLIENT = console_script('rotation_client', 'rot_tools.ros.client.rotation_client')
NODE = console_script('rotation_node', 'rot_tools.ros.node.rotation_node')


def normalised(text, namespace):
    """Output with the run's namespace removed and run-dependent values written '...'."""
    text = text.replace(namespace, '')
    text = text.replace(namespace[1:].replace('/', '.') + '.', '')  # in a logger's name
    text = re.sub(r'\[(\d{9,}\.\d+)\]', '[...]', text)  # a log line's time stamp
    text = re.sub(r'(\n\s*sec: )\d+(\n\s*nanosec: )\d+', r'\1...\2...', text)
    text = re.sub(r'ROS_DOMAIN_ID \d+', 'ROS_DOMAIN_ID ...', text)
    return text


def run_client_block(name, node_name):
    """Run the block's commands for real; return the text the block should show."""
    namespace = node_name[:-len('/rot_tools')]
    shown, status = [], 0
    for command, _ in console_steps(doc_block(name)):
        shown.append(f'$ {command}\n')
        if command == 'echo $?':
            shown.append(f'{status}\n')
            continue
        argv = shlex.split(command)
        head = None
        if len(argv) > 3 and argv[-3] == '|' and argv[-2] == 'head':  # ... | head -N
            head, argv = int(argv[-1].lstrip('-')), argv[:-3]
        quiet = argv[-2:] == ['>', '/dev/null']
        argv = argv[:-2] if quiet else argv
        assert argv[0] == 'rotation_client', command
        if '--node' not in argv:
            argv += ['--node', node_name]
        args = CLIENT + argv[1:]
        done = subprocess.run(args, capture_output=True, text=True, timeout=120,
                              env=script_env(args), stdin=subprocess.DEVNULL)
        status = done.returncode
        out = '' if quiet else done.stdout
        if head is not None:
            out = ''.join(out.splitlines(keepends=True)[:head])
        shown.append(normalised(out + done.stderr, namespace))
    return ''.join(shown)


@pytest.mark.parametrize('block', ['readme-client', 'node-describe'])
def test_client_block_on_a_fresh_node(tmp_path, block):
    process = NodeProcess(tmp_path)  # its first input is the block's, nothing refused before
    try:
        assert_doc_output(block, run_client_block(block, process.name))
    finally:
        process.kill()


def test_node_typo_warning(tmp_path):
    (command, _), = console_steps(doc_block('node-typo-warning'))
    process = NodeProcess(tmp_path, *shlex.split(command)[2:])
    try:
        err = process.wait_for_stderr('decomposing')
    finally:
        process.kill()
    namespace = process.name[:-len('/rot_tools')]
    assert_doc_output('node-typo-warning', f'$ {command}\n' + normalised(err, namespace))


def test_node_bad_parameter():
    (command, _), = console_steps(doc_block('node-bad-parameter'))
    args = NODE + shlex.split(command)[1:]
    done = subprocess.run(args, capture_output=True, text=True, timeout=120,
                          env=script_env(args), stdin=subprocess.DEVNULL)
    assert done.returncode == 2 and done.stdout == ''
    assert_doc_output('node-bad-parameter', f'$ {command}\n' + done.stderr)


def test_readme_bag():
    pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
    (command, _), = console_steps(doc_block('readme-bag'))
    args = console_script('rot-tools', 'rot_tools.cli.main') + shlex.split(command)[1:]
    done = subprocess.run(args, capture_output=True, text=True, timeout=120, cwd=REPO,
                          env=script_env(args), stdin=subprocess.DEVNULL)
    assert done.returncode == 0 and done.stderr == '', done.stderr
    assert_doc_output('readme-bag', f'$ {command}\n' + done.stdout)
