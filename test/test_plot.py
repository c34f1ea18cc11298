"""rot_tools.cli.plot and ``rot-tools ... --plot FILE``: the figure's artists and the files."""

import math
from pathlib import Path
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET

import math_helpers as h
import numpy as np
import pytest
from rot_tools.cli import plot
from scipy.spatial.transform import Rotation

PNG_SIGNATURE = b'\x89PNG\r\n\x1a\n'
SVG = '{http://www.w3.org/2000/svg}'


def lines_by_gid(fig):
    (ax,) = fig.axes
    return {line.get_gid(): line for line in ax.get_lines() if line.get_gid()}


def points(line):
    return np.transpose(line.get_data_3d())


def test_screw_figure_holds_frames_axis_and_helix():
    c, theta, d = np.array([0.5, 0.5, 0.0]), math.pi / 2, 0.5
    u = np.array([0.0, 0.0, 1.0])
    R, b = h.screw_motion(u, c, theta, d)
    fig = plot.figure(R, b, degrees=True)
    lines = lines_by_gid(fig)
    assert set(lines) == {*plot.REFERENCE_GIDS, *plot.MOVED_GIDS, 'screw_axis', 'path'}
    for k in range(3):  # scale 1 here: |b| and |c| are small
        np.testing.assert_allclose(points(lines[plot.REFERENCE_GIDS[k]]),
                                   [np.zeros(3), np.eye(3)[k]], atol=1e-15)
        np.testing.assert_allclose(points(lines[plot.MOVED_GIDS[k]]), [b, b + R[:, k]],
                                   atol=1e-15)
    path = points(lines['path'])
    s = np.linspace(0.0, 1.0, len(path))
    expected = c + Rotation.from_rotvec(np.outer(s, theta * u)).apply(-c) + np.outer(s * d, u)
    np.testing.assert_allclose(path, expected, rtol=0, atol=1e-12)
    assert len(path) > 20  # smooth: 90° in steps of at most 3°
    axis = points(lines['screw_axis'])
    assert len(axis) == 2
    for p in axis:
        assert np.linalg.norm(np.cross(p - c, u)) < 1e-12
    (ax,) = fig.axes
    assert ax.get_title() == 'screw motion\nθ = 90 deg, d = 0.5, screw pitch = 0.3183 /rad'
    spans = [np.ptp(lim) for lim in (ax.get_xlim(), ax.get_ylim(), ax.get_zlim())]
    assert spans == pytest.approx([spans[0]] * 3, rel=1e-12)  # equal axes
    assert ax.get_box_aspect() is not None
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert 'screw axis along (0, 0, 1) through (0.5, 0.5, 0)' in legend
    assert 'path of the origin' in legend


def test_rotation_figure_draws_the_arc_of_the_x_tip():
    theta = 1.0
    R, _ = h.screw_motion((0, 0, 1), np.zeros(3), theta, 0.0)
    fig = plot.figure(R, None)
    lines = lines_by_gid(fig)
    arc = points(lines['path'])
    s = np.linspace(0.0, 1.0, len(arc))
    np.testing.assert_allclose(arc, np.transpose([np.cos(s * theta), np.sin(s * theta),
                                                  np.zeros_like(s)]), rtol=0, atol=1e-15)
    axis = points(lines['screw_axis'])
    np.testing.assert_allclose(axis[:, :2], 0.0, atol=1e-15)
    (ax,) = fig.axes
    assert ax.get_title() == 'rotation\nθ = 1 rad, d = 0, screw pitch = 0 /rad'
    assert 'path of the x-axis tip' in [t.get_text() for t in ax.get_legend().get_texts()]


def test_translation_figure_has_a_straight_path_and_no_axis():
    b = np.array([0.0, 3.0, 4.0])
    lines = lines_by_gid(plot.figure(np.eye(3), b))
    assert 'screw_axis' not in lines
    np.testing.assert_array_equal(points(lines['path']), [np.zeros(3), b])


def test_large_motion_scales_the_frames():
    b = np.array([20.0, 0.0, 0.0])
    lines = lines_by_gid(plot.figure(np.eye(3), b))
    np.testing.assert_allclose(points(lines['moved_x']), [b, b + (5, 0, 0)])


@pytest.mark.parametrize('angle', [math.radians(2.0), 1e-9])
def test_a_far_axis_does_not_shrink_the_motion(angle):
    # A small turn about z with b = (1, 0, 0): the axis is the vertical line through
    # (0.5, 0.5·cot(θ/2)), 28.6 away for 2°, 5e8 for 1e-9 rad; the motion is 1 across.
    R = Rotation.from_rotvec([0.0, 0.0, angle]).as_matrix()
    far = 0.5 / math.tan(angle / 2)
    fig = plot.figure(R, (1.0, 0.0, 0.0))
    lines = lines_by_gid(fig)
    assert 'screw_axis' not in lines
    np.testing.assert_allclose(points(lines['moved_x']), [(1, 0, 0), (1 + R[0, 0], R[1, 0], 0)],
                               atol=1e-15)  # frames 1 long
    (ax,) = fig.axes
    limits = np.array([ax.get_xlim(), ax.get_ylim(), ax.get_zlim()])
    # x spans the most, from 0 to the moved x tip 1 + cos θ; a margin of 10 % on each side.
    assert np.ptp(limits, axis=1) == pytest.approx([1.1 * (1 + math.cos(angle))] * 3,
                                                   rel=1e-12)
    # The dotted pointer: from the view's centre to its face, toward the axis's nearest point.
    start, end = points(lines['toward_axis'])
    np.testing.assert_allclose(start, limits.mean(axis=1), atol=1e-12)
    toward = np.array([0.5, far, start[2]]) - start
    np.testing.assert_allclose(np.cross(end - start, toward), 0.0, atol=1e-9 * far)
    assert (end - start) @ toward > 0
    assert np.abs(end - start).max() == pytest.approx(np.ptp(limits[0]) / 2)
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert (f'screw axis along (0, 0, 1) through (0.5, {far:.3g}, 0),\n{far:.3g} from the '
            'origin: off the view, dotted toward it') in legend


def svg_text(path):
    root = ET.parse(path).getroot()
    return [''.join(element.itertext()) for element in root.iter(f'{SVG}text')]


@pytest.mark.parametrize('args, title', [
    (['axis-angle', '0', '0', '1', '90', '--deg'], 'θ = 90 deg, d = 0, screw pitch = 0 /rad'),
    (['axis-angle', '0', '0', '1', '1.5'], 'θ = 1.5 rad, d = 0, screw pitch = 0 /rad'),
    (['screw', '--axis-angle', '0', '0', '1', '2', '--translation', '1', '0', '0', '--deg'],
     'θ = 2 deg, d = 0, screw pitch = 0 /rad')], ids=['deg', 'rad', 'screw_deg'])
def test_plot_option_draws_theta_in_the_unit_asked(tmp_path, args, title):
    from rot_tools.cli.main import main
    out = tmp_path / 'picture.svg'
    assert main(args + ['--plot', str(out)]) == 0
    assert title in svg_text(out)
    assert (' deg' in title) == any(' deg,' in text for text in svg_text(out))


def test_plot_option_says_where_a_far_axis_is(tmp_path):
    from rot_tools.cli.main import main
    out = tmp_path / 'picture.svg'
    assert main(CASES['small_angle_screw'] + ['--plot', str(out)]) == 0
    check_svg(out, COMMON_GIDS + ('toward_axis',))
    assert '28.6 from the origin: off the view, dotted toward it' in svg_text(out)


def check_png(path):
    data = Path(path).read_bytes()
    assert data[:8] == PNG_SIGNATURE
    length, kind, width, height = struct.unpack('>I4sII', data[8:24])
    assert (length, kind) == (13, b'IHDR') and width > 300 and height > 300
    assert data[-8:-4] == b'IEND'


def check_svg(path, gids):
    root = ET.parse(path).getroot()
    assert root.tag == f'{SVG}svg'
    ids = {element.get('id') for element in root.iter()}
    assert set(gids) <= ids


CASES = {
    'rotation': ['axis-angle', '0', '0', '1', '90', '--deg'],
    'screw': ['screw', '--axis-angle', '0', '0', '1', '90', '--translation', '1', '0', '0.5',
              '--deg'],
    'translation': ['screw', '--translation', '1', '2', '2'],
    'small_angle_screw': ['screw', '--axis-angle', '0', '0', '1', '2', '--translation', '1',
                          '0', '0', '--deg'],
    'half_turn': ['axis-angle', '1', '1', '1', '180', '--deg'],
}
COMMON_GIDS = ('path', *plot.MOVED_GIDS, *plot.REFERENCE_GIDS)


def rot_tools_cli(args, code=''):
    """Run rot-tools in a fresh interpreter (after ``code``); return the CompletedProcess."""
    program = (f'{code}\nimport sys\nfrom rot_tools.cli.main import main\n'
               'sys.exit(main(sys.argv[1:]))')
    return subprocess.run([sys.executable, '-c', program, *args], capture_output=True,
                          text=True, timeout=120)


@pytest.mark.parametrize('case', CASES)
@pytest.mark.parametrize('ext', ['png', 'svg'])
def test_plot_option_writes_the_file(tmp_path, case, ext):
    from rot_tools.cli.main import main
    out = tmp_path / f'{case}.{ext}'
    assert main(CASES[case] + ['--plot', str(out)]) == 0
    if ext == 'png':
        check_png(out)
    else:
        check_svg(out, COMMON_GIDS + {'translation': (), 'small_angle_screw': ('toward_axis',)}
                  .get(case, ('screw_axis',)))


def test_plot_option_before_the_command_and_upper_case_extension(tmp_path, capsys):
    from rot_tools.cli.main import main
    out = tmp_path / 'picture.PNG'
    assert main(['--plot', str(out)] + CASES['screw']) == 0
    check_png(out)
    assert 'screw:' in capsys.readouterr().out  # the report is printed as usual


def test_plot_option_is_listed_in_help(capsys):
    from rot_tools.cli.main import main
    assert main(['--help']) == 0
    assert '--plot FILE' in capsys.readouterr().out
    assert main(['euler', '--help']) == 0
    assert '--plot FILE' in capsys.readouterr().out


@pytest.mark.parametrize('name', ['picture.jpg', 'picture', 'picture.png.txt'])
def test_other_extensions_are_refused(tmp_path, capsys, name):
    from rot_tools.cli.main import main
    assert main(CASES['rotation'] + ['--plot', str(tmp_path / name)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ''
    assert len(captured.err.splitlines()) == 1
    assert 'rot-tools: error: argument --plot: ' in captured.err and '.png or .svg' in captured.err
    assert not any(tmp_path.iterdir())


def test_unwritable_file_is_one_line(tmp_path, capsys):
    from rot_tools.cli.main import main
    out = tmp_path / 'no' / 'such' / 'dir.png'
    assert main(CASES['rotation'] + ['--plot', str(out)]) == 2
    captured = capsys.readouterr()
    assert captured.out == '' and len(captured.err.splitlines()) == 1
    assert captured.err.startswith('rot-tools: error: --plot: cannot write')


def test_a_picture_too_large_for_float64_is_one_line(tmp_path, capsys):
    from rot_tools.cli.main import main
    out = tmp_path / 'huge.png'
    assert main(['screw', '--translation', '1.7e308', '0', '0', '--plot', str(out)]) == 2
    captured = capsys.readouterr()
    assert captured.out == '' and len(captured.err.splitlines()) == 1
    assert captured.err.startswith('rot-tools: error: --plot: the picture of this motion '
                                   'overflows float64')
    assert not out.exists()


def test_missing_matplotlib_is_one_line_and_exit_2(tmp_path):
    out = tmp_path / 'picture.png'
    done = rot_tools_cli(CASES['screw'] + ['--plot', str(out)],
                         "import sys\nsys.modules['matplotlib'] = None  # import fails")
    assert done.returncode == 2
    assert done.stdout == ''
    assert done.stderr.count('\n') == 1 and 'Traceback' not in done.stderr
    assert "pip install -e '.[plot]' in the rot_tools checkout" in done.stderr
    assert not out.exists()


def test_without_plot_matplotlib_is_not_imported():
    done = rot_tools_cli(CASES['screw'] + ['--json'],
                         "import sys\nsys.modules['matplotlib'] = None  # import fails")
    assert done.returncode == 0, done.stderr
    done = rot_tools_cli(CASES['screw'], 'import atexit, sys\natexit.register(lambda: print('
                         "'matplotlib' in sys.modules, file=sys.stderr))")
    assert done.stderr == 'False\n'


def test_a_failed_write_leaves_nothing(tmp_path, savefig_fills_the_disk):
    """Half a picture and a full disk: no file left, neither the target nor a temporary."""
    with pytest.raises(OSError, match='No space left'):
        plot.save(np.eye(3), np.ones(3), tmp_path / 'motion.png')
    assert list(tmp_path.iterdir()) == []
