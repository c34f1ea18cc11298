"""README.md's commands, run as written in a fresh clone after ``make run``."""

from importlib import metadata
import os
from pathlib import Path
import re
import shlex
import shutil
import signal
import subprocess
import sys
import time

from conftest import DISCOVERY_TIMEOUT
from doc_blocks import blocks, console_steps, matches, REPO
import pytest

README = REPO / 'README.md'
ACTIVATE = 'source .venv/bin/activate'
"""How README.md puts the commands on PATH (its quick start says so in these words)."""

WALKED = re.compile(r'(rotation_client|rot-tools|rotation_node|make)\s|echo \$\?$')
"""The commands the walk runs: the package's three console scripts, make, and echo $?."""

ROS = 'needs ROS 2 Jazzy installed (/opt/ros/jazzy): the ROS workspace way, not the pip one'
ROS2CLI = 'needs ros2cli, which is not on PyPI'
NOT_WALKED = {
    'source /opt/ros/jazzy/setup.bash': ROS,
    'mkdir -p ~/ros2_ws/src && cp -r /path/to/rot_tools ~/ros2_ws/src/ && cd ~/ros2_ws':
        ROS + '; /path/to is for the reader to fill in',
    'rosdep install --from-paths src --ignore-src -y':
        ROS + '; test_package.py checks that package.xml declares every dependency',
    'colcon build --packages-select rot_tools':
        ROS + '; test_package.py runs a real colcon build of the package',
    'source install/setup.bash': ROS,
    'ros2 run rot_tools rotation_node --ros-args -p angle_unit:=deg':
        ROS2CLI + '; test_package.py checks that colcon installs it where ros2 run looks',
    'ros2 launch rot_tools rot_tools.launch.xml namespace:=/robot imu:=/robot/imu/data':
        ROS2CLI + '; test_launch.py runs the command the launch file makes',
    'ros2 topic echo /rot_tools/rpy': ROS2CLI,
    'ros2 topic pub --once /rot_tools/pose geometry_msgs/msg/PoseStamped \\\n'
    '    "{header: {frame_id: map}, pose: {position: {x: 1.0, z: 0.5}, '
    'orientation: {z: 1.0, w: 0.0}}}"': ROS2CLI,
    'ros2 service call /rot_tools/describe std_srvs/srv/Trigger': ROS2CLI,
    'ros2 run rot_tools rot-tools euler ZYX 30 20 10 --deg': ROS2CLI,
}
"""README.md's commands that the walk cannot run, by their exact text, with the reason."""

COMMAND_TIMEOUT = 60.0
"""Upper bound of one command that is meant to end (the slowest takes about a second)."""

TRACEBACK = 'Traceback (most recent call last)'


class Command:
    """A command of README.md: its text, the output shown after it (None: none can be)."""

    def __init__(self, line, text, shown):
        self.line, self.text, self.shown = line, text, shown

    def __repr__(self):
        return f'README.md:{self.line}: {self.text}'


def without_comment(text):
    """Return a command's text without a trailing `` # comment``."""
    return re.sub(r'\s+#\s.*$', '', text)


def sh_commands(text):
    """Return the commands of a ``sh`` block: one a line, or more joined by a final backslash."""
    commands, pending = [], ''
    for line in text.splitlines():
        if not pending and (not line.strip() or line.lstrip().startswith('#')):
            continue
        pending += line
        if line.endswith('\\'):
            pending += '\n'
        else:
            commands.append(without_comment(pending))
            pending = ''
    return commands


def readme_commands():
    """Return every command of README.md's shell blocks, in order."""
    found = []
    for block in blocks(README):
        if block.lang == 'console':
            found += [Command(block.line, without_comment(text), shown)
                      for text, shown in console_steps(block.text)]
        elif block.lang in ('sh', 'bash', 'shell'):
            found += [Command(block.line, text, None) for text in sh_commands(block.text)]
    return found


COMMANDS = readme_commands()


def terminal_env():
    """Return this process's environment as a user's terminal has it: no make around it."""
    return {name: value for name, value in os.environ.items()
            if name not in ('MAKEFLAGS', 'MFLAGS', 'MAKELEVEL', 'MAKEOVERRIDES')}


def git(*args, cwd=REPO):
    """Run git; return its standard output."""
    return subprocess.run(['git', *args], cwd=cwd, check=True, capture_output=True,
                          text=True, timeout=COMMAND_TIMEOUT).stdout


class FreshClone:
    """A git clone of this checkout, ``shared`` beside it, and README's make commands dry-run."""

    def __init__(self, top):
        self.path = top / 'rot_tools'
        git('clone', '-q', str(REPO), str(self.path))
        # What a commit of the checkout would hold: its uncommitted changes to tracked files.
        for name in filter(None, git('diff', '--name-only', '-z', 'HEAD').split('\0')):
            if (REPO / name).is_file():
                (self.path / name).parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(REPO / name, self.path / name)
            else:
                (self.path / name).unlink(missing_ok=True)
        shared = REPO.parent / 'shared'
        if shared.is_dir():
            (top / 'shared').symlink_to(shared.resolve())
        self.dry_runs = {}
        for command in COMMANDS:
            if command.text.startswith('make '):
                done = subprocess.run(['make', '-n', *command.text.split()[1:]],
                                      cwd=self.path, env=terminal_env(), capture_output=True,
                                      text=True, timeout=COMMAND_TIMEOUT)
                self.dry_runs[command.text] = (done.returncode, done.stdout + done.stderr)


@pytest.fixture(scope='module')
def clone(tmp_path_factory):
    """Clone this checkout once for the module's tests (and dry-run README's make commands)."""
    if not (REPO / '.git').exists() or not shutil.which('git') or not shutil.which('make'):
        pytest.skip('the walk clones this checkout: it needs a git checkout, git and make')
    return FreshClone(tmp_path_factory.mktemp('walk'))


def test_every_readme_command_is_walked_or_listed():
    shown = {command.text for command in COMMANDS}
    neither = [c for c in COMMANDS if c.text not in NOT_WALKED and not WALKED.match(c.text)]
    assert not neither, (
        f'README.md commands that the walk neither runs nor lists: {neither}; make the walk '
        'run them, or name them in NOT_WALKED with the reason')
    stale = [text for text in NOT_WALKED if text not in shown]
    assert not stale, f'NOT_WALKED names commands that README.md no longer shows: {stale}'
    assert any(c.text == 'make run' for c in COMMANDS), 'README.md no longer says make run'


def test_sh_blocks_are_read_as_bash_reads_them():
    text = ('# a comment\nmake run    # set up\n\nros2 topic pub /a t \\\n    "{x: 1}"\n'
            'echo "#1"\n')
    assert sh_commands(text) == ['make run', 'ros2 topic pub /a t \\\n    "{x: 1}"',
                                 'echo "#1"']


def extra_requirements(*extras):
    """Return the names of the requirements of rot_tools' ``extras`` (its metadata)."""
    names = set()
    for requirement in metadata.requires('rot_tools') or ():
        name, _, marker = requirement.partition(';')
        if any(re.search(rf'extra == "{extra}"', marker) for extra in extras):
            names.add(re.match(r'[A-Za-z0-9._-]+', name).group().lower())
    return names


def test_make_run_installs_the_extras_then_starts_the_node(clone):
    # README's bag example needs the bag and plot extras, and says make run installs them.
    status, out = clone.dry_runs['make run']
    assert status == 0, out
    lines = out.splitlines()
    assert lines[-1].split() == ['.venv/bin/rotation_node'], out
    venv = [k for k, line in enumerate(lines) if line.endswith(' -m venv .venv')]
    extras = extra_requirements('bag', 'plot')
    assert {'rosbags', 'matplotlib'} <= extras
    installs = [k for k, line in enumerate(lines)
                if ' -m pip ' in line and ' install ' in line
                and extras <= {word.lower() for word in line.split()}]
    assert venv and installs and venv[0] < installs[0] < len(lines) - 1, (
        f'make run does not install {sorted(extras)} before it starts the node:\n{out}')


def test_make_run_s_pip_installs_resolve(clone):
    # Each pip install but the editable one runs with --dry-run --no-index: pip reads its files.
    if Path(sys.prefix).resolve() != (REPO / '.venv').resolve():
        pytest.skip('make run sets up .venv: its pins are checked by the suite that runs there')
    status, out = clone.dry_runs['make run']
    commands = [shlex.split(line) for line in out.splitlines()
                if re.match(r'\.venv/bin/python -m pip .* install ', line) and ' -e ' not in line]
    assert len(commands) >= 2, out  # the requirements and the extras
    for words in commands:
        at = words.index('install') + 1
        args = [sys.executable, *words[1:at], '--dry-run', '--no-index', *words[at:]]
        done = subprocess.run(args, cwd=clone.path, env=terminal_env(), capture_output=True,
                              text=True, timeout=COMMAND_TIMEOUT)
        assert done.returncode == 0, f'{shlex.join(words)}:\n{done.stdout}{done.stderr}'


class Background:
    """A command left running, as in a terminal of its own or after ``&``: output in a file."""

    def __init__(self, command, argv, cwd, env, out_path):
        self.command, self.out_path = command, out_path
        with open(out_path, 'w') as out:
            self.process = subprocess.Popen(argv, cwd=cwd, env=env, stdin=subprocess.DEVNULL,
                                            stdout=out, stderr=subprocess.STDOUT,
                                            start_new_session=True)

    def output(self):
        return self.out_path.read_text()

    def wait_for(self, done, what):
        """Wait until ``done(output)``; fail if the command ends or DISCOVERY_TIMEOUT passes."""
        deadline = time.monotonic() + DISCOVERY_TIMEOUT
        while not done(self.output()):
            if time.monotonic() > deadline or self.process.poll() is not None:
                pytest.fail(f'{self.command}: no {what} (status {self.process.poll()}):\n'
                            + self.output())
            time.sleep(0.05)

    def interrupt(self):
        """Send SIGINT to the command's process group (Ctrl-C); return its exit status."""
        os.killpg(self.process.pid, signal.SIGINT)
        try:
            return self.process.wait(timeout=10.0)
        except subprocess.TimeoutExpired:
            self.kill()
            pytest.fail(f'{self.command}: still running 10 s after SIGINT')

    def kill(self):
        if self.process.poll() is None:
            os.killpg(self.process.pid, signal.SIGKILL)
            self.process.wait()


def typed(command, cwd, env, status):
    """Run ``command`` in bash, ``$?`` being ``status``; return (exit status, stdout+stderr)."""
    process = subprocess.Popen(['bash', '-c', f'(exit {status})\n{command}'], cwd=cwd, env=env,
                               stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True, start_new_session=True)
    try:
        out, _ = process.communicate(timeout=COMMAND_TIMEOUT)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        out, _ = process.communicate()
        pytest.fail(f'{command}: still running after {COMMAND_TIMEOUT:g} s:\n{out}')
    return process.returncode, out


def activated(clone, venv):
    """Link the clone's .venv to ``venv``; return the environment after README's activate."""
    (clone.path / '.venv').symlink_to(venv)
    done = subprocess.run(['bash', '-c', f'{ACTIVATE} && env -0'], cwd=clone.path,
                          env=terminal_env(), capture_output=True, text=True, check=True,
                          timeout=COMMAND_TIMEOUT)
    env = dict(item.split('=', 1) for item in done.stdout.split('\0') if '=' in item)
    assert Path(env['PATH'].split(os.pathsep)[0]).resolve() == (venv / 'bin').resolve()
    return env


def test_the_readme_commands_work_as_written(clone, tmp_path):
    venv = Path(sys.prefix)
    if sys.prefix == sys.base_prefix or not all(
            (venv / 'bin' / name).exists()
            for name in ('activate', 'rotation_node', 'rotation_client', 'rot-tools')):
        pytest.skip('the walk runs in the venv make run or make test sets up')
    assert f'`{ACTIVATE}`' in README.read_text(encoding='utf-8')
    env = activated(clone, venv)
    jobs, status = [], 0
    try:
        for k, command in enumerate(COMMANDS):
            if command.text in NOT_WALKED or not WALKED.match(command.text):
                continue  # listed, or a failure of test_every_readme_command_is_walked_or_listed
            if command.text.startswith('make '):
                status, out = clone.dry_runs[command.text]
                assert status == 0, f'{command}: make -n fails:\n{out}'
                if command.text == 'make run':  # its last line, in a terminal of its own
                    node = out.splitlines()[-1].split()
                    assert node[0] == '.venv/bin/rotation_node', out
                    jobs.append(Background(command, node, clone.path, terminal_env(),
                                           tmp_path / 'make_run'))
                    jobs[-1].wait_for(lambda out: 'decomposing' in out, 'start-up line')
                continue
            if command.text.endswith('&'):
                jobs.append(Background(command, ['bash', '-c', command.text[:-1]], clone.path,
                                       env, tmp_path / f'job{k}'))
                if command.shown:
                    jobs[-1].wait_for(lambda out: matches(command.shown, out), 'output shown')
                continue
            status, out = typed(command.text, clone.path, env, status)
            assert TRACEBACK not in out, f'{command}:\n{out}'
            if command.shown is not None:
                assert matches(command.shown, out), (
                    f'{command}\n--- README.md\n{command.shown}--- real\n{out}')
            later = COMMANDS[k + 1].text if k + 1 < len(COMMANDS) else None
            assert status == 0 or later == 'echo $?', f'{command}: exit status {status}\n{out}'
        for job in reversed(jobs):
            ended = job.interrupt()
            node = job.command.text == 'make run'
            assert ended == (0 if node else 130), f'{job.command}: status {ended}'
            assert TRACEBACK not in job.output(), f'{job.command}:\n{job.output()}'
    finally:
        for job in jobs:
            job.kill()
