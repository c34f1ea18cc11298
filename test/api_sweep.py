"""The public functions of rot_tools, from rot_tools.__all__, for the tests that sweep them."""

import inspect

import rot_tools

TIME_SERIES = {
    name: 'takes one sequence in time (stamps, N samples), not items or a batch of them'
    for name in ('align_rotations', 'angular_speeds', 'check_imu', 'delta_pairs',
                 'error_statistics', 'estimate_time_offset', 'hand_eye_rotation',
                 'interpolate_poses', 'nearest_stamps', 'rotation_errors')}
TIME_SERIES.update(
    hand_eye='takes the poses of two bodies over time (stamps, N samples each), not items',
    screw_congruence='takes the poses of two bodies at the same K instants, not items')
"""The public functions of a whole trajectory or stream: a sweep over items excuses them."""


def public_functions():
    """Return the names of rot_tools' public functions (its classes and constants left out)."""
    return {name for name in rot_tools.__all__ if inspect.isfunction(getattr(rot_tools, name))}


def parameters(name):
    """Return the parameter names of public function ``name``."""
    return set(inspect.signature(getattr(rot_tools, name)).parameters)


def assert_sweeps_every_public_function(swept, excused):
    """Fail naming each public function neither ``swept`` nor ``excused`` ({name: why})."""
    public = public_functions()
    unswept = sorted(public - set(swept) - set(excused))
    assert not unswept, f'public functions without inputs in this sweep: {unswept}'
    stale = sorted((set(swept) | set(excused)) - public)
    assert not stale, f'not public functions of rot_tools: {stale}'
