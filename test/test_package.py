"""Packaging: package.xml, the installed metadata and a real `colcon build` of the package."""

import ast
import importlib.metadata
import os
from pathlib import Path
import shutil
import subprocess
import sys

from catkin_pkg.package import parse_package
from conftest import RUN
import pytest

REPO = Path(__file__).resolve().parents[1]
PACKAGE = 'rot_tools'
CONSOLE_SCRIPTS = {
    'rotation_node': 'rot_tools.ros.node.rotation_node:main',
    'rotation_client': 'rot_tools.ros.rotation_client:main',
    'rot-tools': 'rot_tools.cli.main:main',
}
# exec_depends the node needs whatever the code happens to import today.
REQUIRED_EXEC_DEPENDS = {
    'rclpy', 'geometry_msgs', 'std_msgs', 'std_srvs', 'nav_msgs', 'sensor_msgs',
    'visualization_msgs', 'rcl_interfaces', 'builtin_interfaces', 'python3-numpy', 'tf2_msgs',
}
# rosdep keys of the non-ROS third-party modules rot_tools may import.
ROSDEP_KEYS = {'numpy': 'python3-numpy', 'yaml': 'python3-yaml',
               'matplotlib': 'python3-matplotlib'}
# Modules of an optional extra of setup.py that have no rosdep key: {module: extra}. They
# are not exec_depends; rot_tools imports them only inside functions, so that everything
# else works without them.
OPTIONAL_EXTRAS = {'rosbags': 'bag', 'pyarrow': 'bag', 'dask': 'fleet', 'distributed': 'fleet'}
# Packages the ROS wheels registered in this environment's ament index (sys.prefix/share).
AMENT_INDEX = Path(sys.prefix, 'share', 'ament_index', 'resource_index', 'packages')
COLCON_TIMEOUT = 300  # seconds; the build itself takes about 1 s
SOURCE_IGNORE = shutil.ignore_patterns(
    '.*', 'build', 'install', 'log', '__pycache__', '*.egg-info')


@pytest.fixture(scope='module')
def manifest():
    warnings = []
    package = parse_package(str(REPO / 'package.xml'), warnings=warnings)
    assert warnings == []
    return package


def _imported_top_level_modules(path, module_level_only=False):
    """Absolute imports of one module, as top-level names (optionally: outside functions)."""
    names = set()

    def visit(node, in_function):
        if isinstance(node, ast.Import) and not (module_level_only and in_function):
            names.update(alias.name.split('.')[0] for alias in node.names)
        elif (isinstance(node, ast.ImportFrom) and node.level == 0
              and not (module_level_only and in_function)):
            names.add(node.module.split('.')[0])
        in_function = in_function or isinstance(
            node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
        for child in ast.iter_child_nodes(node):
            visit(child, in_function)

    visit(ast.parse(path.read_text(), filename=str(path)), False)
    return names


def test_package_xml_parses_with_catkin_pkg(manifest):
    assert manifest.package_format == 3
    assert manifest.name == PACKAGE
    assert manifest.version == importlib.metadata.version(PACKAGE)
    assert manifest.licenses == ['Apache-2.0']
    assert manifest.get_build_type() == 'ament_python'
    description = ' '.join(manifest.description.split())
    for part in ('odometry', 'IMU', 'PoseWithCovarianceStamped', 'QuaternionStamped',
                 'quaternion', 'markers', 'rotation_client'):
        assert part in description, part
    assert REQUIRED_EXEC_DEPENDS <= {dep.name for dep in manifest.exec_depends}
    assert {'python3-pytest', 'python3-hypothesis'} <= {dep.name for dep in manifest.test_depends}


def test_package_xml_declares_every_package_the_code_imports(manifest):
    sources = sorted((REPO / PACKAGE).rglob('*.py'))  # every sub-package
    assert len(sources) > 10, 'no rot_tools/**/*.py found'
    declared = {dep.name for dep in manifest.exec_depends}
    assert AMENT_INDEX.is_dir(), f'no ament index at {AMENT_INDEX}: are the ROS wheels installed?'
    missing = {}
    for path in sources:
        for name in _imported_top_level_modules(path):
            if name in sys.stdlib_module_names or name == PACKAGE:
                continue
            if name in OPTIONAL_EXTRAS:
                assert name not in _imported_top_level_modules(path, module_level_only=True), (
                    f'{path.name} imports {name!r} (optional extra '
                    f'{OPTIONAL_EXTRAS[name]!r}) at module level: import it where it is used')
                continue
            if (AMENT_INDEX / name).is_file():
                key = name
            else:
                assert name in ROSDEP_KEYS, (
                    f'{path.name} imports {name!r}, which is neither a ROS package nor in '
                    'ROSDEP_KEYS: add its rosdep key to package.xml and ROSDEP_KEYS')
                key = ROSDEP_KEYS[name]
            if key not in declared:
                missing.setdefault(key, []).append(path.name)
    assert missing == {}, f'imported but not an <exec_depend> in package.xml: {missing}'


def test_optional_extras_name_their_modules():
    requires = importlib.metadata.distribution(PACKAGE).requires
    for module, extra in OPTIONAL_EXTRAS.items():
        assert any(req.startswith((f'{module}==', f'{module}['))
                   and f'extra == "{extra}"' in req
                   for req in requires), (module, extra, requires)


def test_installed_distribution_matches_setup():
    dist = importlib.metadata.distribution(PACKAGE)
    scripts = {ep.name: ep.value for ep in dist.entry_points if ep.group == 'console_scripts'}
    assert scripts == CONSOLE_SCRIPTS
    assert {'numpy', 'setuptools'} <= {req.split()[0] for req in dist.requires}


@pytest.fixture(scope='session')
def colcon_install(tmp_path_factory):
    """`colcon build` the package in a fresh workspace; return its install prefix."""
    workspace = tmp_path_factory.mktemp('colcon_ws')
    shutil.copytree(REPO, workspace / 'src' / PACKAGE, ignore=SOURCE_IGNORE)
    colcon = Path(sys.executable).with_name('colcon')
    if not colcon.is_file():
        colcon = shutil.which('colcon')
    assert colcon, 'colcon not found: pip install -r requirements-test.txt'
    env = dict(os.environ, AMENT_PREFIX_PATH=sys.prefix,
               COLCON_HOME=str(workspace / 'colcon_home'))
    try:
        result = subprocess.run(
            [str(colcon), 'build', '--base-paths', 'src'], cwd=workspace, env=env,
            stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=COLCON_TIMEOUT)
    except subprocess.TimeoutExpired:
        pytest.fail(f'colcon build took more than {COLCON_TIMEOUT} s')
    assert result.returncode == 0, f'colcon build failed:\n{result.stdout}\n{result.stderr}'
    return workspace / 'install' / PACKAGE


def _run_in_workspace(prefix, *command):
    """Run a command the way a ROS user does: after sourcing the workspace's setup.sh."""
    script = '. "$1" && shift && exec "$@"'
    setup = prefix.parent / 'setup.sh'
    return subprocess.run(
        ['sh', '-c', script, 'sh', str(setup), *map(str, command)], cwd=prefix.parent,
        stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=60)


def test_colcon_installs_executables_where_ros2_run_finds_them(colcon_install):
    for name in CONSOLE_SCRIPTS:
        executable = colcon_install / 'lib' / PACKAGE / name
        assert executable.is_file(), f'{executable} missing'
        assert os.access(executable, os.X_OK), f'{executable} is not executable'


def test_colcon_installs_manifest_and_ament_index_marker(colcon_install):
    share = colcon_install / 'share'
    assert (share / PACKAGE / 'package.xml').read_text() == (REPO / 'package.xml').read_text()
    assert (share / 'ament_index' / 'resource_index' / 'packages' / PACKAGE).is_file()


def test_colcon_installs_the_parameter_file(colcon_install):
    installed = colcon_install / 'share' / PACKAGE / 'config' / 'rot_tools.yaml'
    assert installed.read_text() == (REPO / 'config' / 'rot_tools.yaml').read_text()


def test_installed_package_is_imported_from_the_install_space(colcon_install):
    result = _run_in_workspace(
        colcon_install, sys.executable, '-c', 'import rot_tools; print(rot_tools.__file__)')
    assert result.returncode == 0, result.stderr
    assert Path(result.stdout.strip()).is_relative_to(colcon_install)


def test_colcon_builds_only_rot_tools_not_the_vendored_tf2_msgs(colcon_install):
    built = sorted(p.name for p in colcon_install.parent.iterdir() if p.is_dir())
    assert built == [PACKAGE]


def test_colcon_never_builds_the_vendored_tf2_msgs(tmp_path):
    """vendor/tf2_msgs is for the pip path only: colcon skips it even when pointed at it."""
    assert (REPO / 'vendor' / 'tf2_msgs' / 'package.xml').is_file()
    colcon = Path(sys.executable).with_name('colcon')
    result = subprocess.run(
        [str(colcon if colcon.is_file() else 'colcon'), 'build', '--base-paths',
         str(REPO / 'vendor')], cwd=tmp_path, env=dict(os.environ, COLCON_HOME=str(tmp_path)),
        stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=COLCON_TIMEOUT)
    assert result.returncode == 0, result.stderr
    assert 'tf2_msgs' not in result.stdout + result.stderr
    assert not (tmp_path / 'install' / 'tf2_msgs').exists()


def _requirements(name):
    """Return the requirement lines of a requirements file as {name: line}, without -r."""
    lines = (line.split('#')[0].strip() for line in (REPO / name).read_text().splitlines())
    return {line.split('==')[0].lower(): line for line in lines
            if line and not line.startswith('-')}


def test_stock_requirements_differ_from_the_pinned_ones_only_in_numpy():
    pinned, stock = _requirements('requirements.txt'), _requirements('requirements-stock.txt')
    assert (pinned.pop('numpy'), stock.pop('numpy')) == ('numpy==2.4.6', 'numpy==1.26.4')
    assert stock == pinned


@pytest.mark.parametrize('name, version', [
    ('pytest', '7.4.4'), ('scipy', '1.11.4'), ('numpy', '1.26.4')])
def test_stock_requirements_are_ubuntu_24_04s_versions(name, version):
    stock = _requirements('requirements-stock.txt') | _requirements('requirements-stock-test.txt')
    assert stock[name] == f'{name}=={version}'


def test_every_requirement_is_pinned_exactly():
    for path in sorted(REPO.glob('requirements*.txt')):
        for line in _requirements(path.name).values():
            assert line.count('==') == 1 and not set('<>~!;') & set(line), (path.name, line)


@pytest.mark.parametrize('where', ['beside_a_clone', 'parent', 'root'])
def test_import_rot_tools_from_any_directory(tmp_path, where):
    """
    Import the package, not a directory rot_tools without __init__.py beside it.

    Such a directory (a clone, seen from its parent) is imported as an empty namespace
    package when the installed package is found only after the current directory's
    namespace portion, as with setuptools' default editable import hook.
    """
    if where == 'beside_a_clone':
        cwd = tmp_path
        (cwd / PACKAGE / PACKAGE).mkdir(parents=True)
        (cwd / PACKAGE / 'README.md').write_text('a clone\n')
    else:
        cwd = REPO.parent if where == 'parent' else Path('/')
    code = 'import rot_tools; print(rot_tools.__file__); rot_tools.euler_to_matrix'
    result = subprocess.run([sys.executable, '-c', code], cwd=cwd, stdin=subprocess.DEVNULL,
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert Path(result.stdout.strip()) == REPO / PACKAGE / '__init__.py'


def test_activating_the_venv_puts_the_commands_on_path():
    """`source .venv/bin/activate`, as the README says, is all the commands need."""
    bin_dir = Path(sys.executable).parent
    if not (bin_dir / 'activate').is_file():
        pytest.skip('not running in a venv')
    path = os.pathsep.join(p for p in os.environ['PATH'].split(os.pathsep)
                           if Path(p) != bin_dir)
    script = ('. "$1/activate" && '
              'for c in rot-tools rotation_node rotation_client; do command -v $c; done')
    result = subprocess.run(['sh', '-c', script, 'sh', str(bin_dir)],
                            env=dict(os.environ, PATH=path), stdin=subprocess.DEVNULL,
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == [
        str(bin_dir / name) for name in ('rot-tools', 'rotation_node', 'rotation_client')]


def test_installed_client_runs(colcon_install):
    """`ros2 run rot_tools rotation_client` runs lib/rot_tools/rotation_client: with rclpy."""
    client = colcon_install / 'lib' / PACKAGE / 'rotation_client'
    result = _run_in_workspace(colcon_install, client, '--help')
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith('usage: rotation_client')
    # It starts rclpy and looks for the node (none in this run's domain by that name).
    result = _run_in_workspace(colcon_install, client, 'describe', '--timeout', '0.5',
                               '--node', f'/{RUN}/colcon/rot_tools')
    assert result.returncode == 1, result.stderr
    assert result.stderr.startswith(
        f'rotation_client: cannot reach node /{RUN}/colcon/rot_tools: not found'), result.stderr


def test_installed_cli_runs(colcon_install):
    result = _run_in_workspace(colcon_install, colcon_install / 'lib' / PACKAGE / 'rot-tools',
                               '--help')
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith('usage: rot-tools')


def test_colcon_installs_the_opt_in_fast_dds_profile(colcon_install):
    """The Fast DDS profile doc/node.md offers ships in share/rot_tools/config, as it is."""
    installed = colcon_install / 'share' / PACKAGE / 'config' / 'fastdds_profile.xml'
    assert installed.read_text() == (REPO / 'config' / 'fastdds_profile.xml').read_text()
    assert not list(colcon_install.glob('lib/python3*/site-packages/rot_tools/**/*.xml'))
