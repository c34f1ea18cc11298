"""Packaging: package.xml, the installed metadata and a real `colcon build` of the package."""

import ast
import importlib.metadata
import os
from pathlib import Path
import re
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
    'rotation_client': 'rot_tools.ros.client.rotation_client:main',
    'rot-tools': 'rot_tools.cli.main:main',
}
ROSDEP_KEYS = {
    'numpy': 'python3-numpy', 'yaml': 'python3-yaml', 'matplotlib': 'python3-matplotlib',
    'scipy': 'python3-scipy', 'pytest': 'python3-pytest', 'hypothesis': 'python3-hypothesis',
    'setuptools': 'python3-setuptools', 'catkin_pkg': 'python3-catkin-pkg-modules'}
"""The rosdep key of each third-party module that is not a ROS package (a ROS package's key
is its name: rclpy, geometry_msgs, ament_flake8, ...)."""
PIP_ONLY = {'rosbags': 'bag', 'pyarrow': 'bag', 'dask': 'fleet', 'distributed': 'fleet',
            'duckdb': 'test', 'evo': 'test'}
"""Modules without a rosdep key, and the setup.py extra that installs them: not in
package.xml; rot_tools imports them where they are used, and a test module that needs one is
skipped without it (conftest.py)."""
AMENT_INDEX = Path(sys.prefix, 'share', 'ament_index', 'resource_index', 'packages')
"""The packages the ROS wheels registered in this environment (sys.prefix/share)."""
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


def undeclared_imports(paths, declared):
    """Return {rosdep key: [file names]} for the imports of ``paths`` not in ``declared``."""
    local = {path.stem for path in (REPO / 'test').glob('*.py')} | {PACKAGE}
    missing = {}
    for path in paths:
        for name in _imported_top_level_modules(path):
            if name in sys.stdlib_module_names or name in local or name in PIP_ONLY:
                continue
            if (AMENT_INDEX / name).is_file():
                key = name
            else:
                assert name in ROSDEP_KEYS, (
                    f'{path.name} imports {name!r}, which is neither a ROS package nor in '
                    'ROSDEP_KEYS nor PIP_ONLY: add its rosdep key to package.xml and here')
                key = ROSDEP_KEYS[name]
            if key not in declared:
                missing.setdefault(key, []).append(path.name)
    return missing


def _package_sources():
    sources = sorted((REPO / PACKAGE).rglob('*.py'))
    assert len(sources) > 10, 'no rot_tools/**/*.py found'
    return sources


@pytest.fixture(scope='module')
def ament_index():
    if not AMENT_INDEX.is_dir():
        pytest.skip(f'no ament index at {AMENT_INDEX}: ROS is not installed')
    return AMENT_INDEX


def test_package_xml_parses_with_catkin_pkg(manifest):
    assert manifest.package_format == 3
    assert manifest.name == PACKAGE
    assert manifest.licenses == ['Apache-2.0']
    assert manifest.get_build_type() == 'ament_python'


def test_package_xml_has_the_version_of_setup_py(manifest):
    assert manifest.version == importlib.metadata.version(PACKAGE)


def test_package_xml_describes_the_node_inputs_and_outputs(manifest):
    description = ' '.join(manifest.description.split())
    for part in ('odometry', 'IMU', 'PoseWithCovarianceStamped', 'QuaternionStamped',
                 'quaternion', 'markers', 'rotation_client'):
        assert part in description, part


def test_package_xml_exec_depends_on_every_package_rot_tools_imports(manifest, ament_index):
    declared = {dep.name for dep in manifest.exec_depends}
    assert undeclared_imports(_package_sources(), declared) == {}


def test_package_xml_test_depends_on_every_package_the_tests_import(manifest, ament_index):
    declared = {dep.name for dep in manifest.exec_depends + manifest.test_depends}
    tests = sorted((REPO / 'test').glob('*.py'))
    assert undeclared_imports(tests, declared) == {}


def test_the_dependency_check_names_an_import_left_undeclared(manifest, ament_index):
    declared = {dep.name for dep in manifest.exec_depends + manifest.test_depends}
    missing = undeclared_imports(sorted((REPO / 'test').glob('*.py')),
                                 declared - {'python3-scipy', 'geometry_msgs'})
    assert set(missing) == {'python3-scipy', 'geometry_msgs'}
    assert 'test_fitting.py' in missing['python3-scipy']


def test_rot_tools_imports_pip_only_modules_where_they_are_used():
    """A module of an extra is imported inside functions: the rest works without it."""
    found = [f'{path.name} imports {name}' for path in _package_sources()
             for name in _imported_top_level_modules(path, module_level_only=True)
             if name in PIP_ONLY]
    assert found == []


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


def _requirements_of(colcon_install):
    """Return {(name, extra): specifier} of the rot_tools colcon installed, from its metadata."""
    info = next(colcon_install.glob(f'lib/python3*/site-packages/{PACKAGE}-*-info'))
    found = {}
    for line in importlib.metadata.Distribution.at(info).requires:
        requirement, _, marker = line.partition(';')
        name = re.match(r'[\w.-]+', requirement).group()
        extra = re.search(r'extra == "(\w+)"', marker)
        found[name, extra and extra.group(1)] = requirement[len(name):].strip()
    return found


def test_extras_install_every_pip_only_module(colcon_install):
    requirements = _requirements_of(colcon_install)
    for module, extra in PIP_ONLY.items():
        assert (module, extra) in requirements, (module, extra, sorted(requirements))


def test_extras_take_a_range_of_versions_not_one(colcon_install):
    """setup.py's extras are ranges; the requirements files hold the exact pins."""
    pinned = {name: specifier for name, specifier in _requirements_of(colcon_install).items()
              if '==' in specifier}
    assert pinned == {}


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
    """Import the package, not a directory rot_tools without __init__.py beside it."""
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
