"""
Write rot_tools/core/_generated.py and _generated_chunks.py: every kernel's one-item and chunk code.

Run ``python -m rot_tools.core._generate`` after changing a kernel, or after adding a conversion
(with its calls in ``ordinary_calls`` below); ``--check`` only says whether the files are up
to date (test_backend does the same and fails when one is not).

How: every call of ``ordinary_calls`` — each public one-item function with ordinary inputs,
every Euler sequence, with and without validation, and rotation_node's per-message path — is
run once with no generated code, so that ``apply`` runs each kernel on Python floats and
records it with its inputs' shapes and its outputs (``_backend.RECORD``). Each recorded
kernel is then traced (rot_tools.core._trace) into one function of each generated module, named
after the kernel: in _generated.py for one item (its CODE table), in _generated_chunks.py
for a chunk of a batch (rot_tools.core._trace_batch; its CHUNKS table), under the kernel's key.
"""

import argparse
from pathlib import Path
import py_compile
import re
import sys

import numpy as np
from rot_tools.core import _backend
from rot_tools.core.errors import RotationError

GENERATED = Path(__file__).resolve().parent / '_generated.py'
GENERATED_CHUNKS = GENERATED.with_name('_generated_chunks.py')
COMMAND = 'python -m rot_tools.core._generate'

_R = np.array([[0.36, 0.48, -0.8], [-0.8, 0.6, 0.0], [0.48, 0.64, 0.6]])  # a rotation
_B = np.array([0.3, -1.2, 2.5])


def ordinary_calls():
    """
    (label, public function name, call) of every one-item use of a kernel, ordinary inputs.

    The test that
    every public kernel runs generated code runs these (and its own inputs) and counts the
    calls that did not.
    """
    import rot_tools as rt
    from rot_tools.core import decomposition
    R, b = _R, _B
    R2 = rt.euler_to_matrix([0.3, -0.2, 2.9])  # θ > π/2: the other way through axis-angle
    calls = []

    def add(label, name, call):
        calls.append((label, name, call))

    for seq in rt.EULER_SEQUENCES:
        add(f'euler_to_matrix_{seq}', 'euler_to_matrix',
            lambda seq=seq: rt.euler_to_matrix([0.4, -0.3, 1.2], seq))
    for check in (True, False):
        tag = '' if check else '_unchecked'
        for seq in rt.EULER_SEQUENCES:
            add(f'matrix_to_euler_{seq}{tag}', 'matrix_to_euler',
                lambda seq=seq, check=check: rt.matrix_to_euler(R, seq, check=check))
        add(f'matrix_to_axis_angle{tag}', 'matrix_to_axis_angle',
            lambda check=check: (rt.matrix_to_axis_angle(R, check=check),
                                 rt.matrix_to_axis_angle(R2, check=check)))
        add(f'matrix_to_rotvec{tag}', 'matrix_to_rotvec',
            lambda check=check: rt.matrix_to_rotvec(R, check=check))
        add(f'matrix_to_quaternion{tag}', 'matrix_to_quaternion',
            lambda check=check: rt.matrix_to_quaternion(R, check=check))
        add(f'screw_from_transform{tag}', 'screw_from_transform',
            lambda check=check: rt.screw_from_transform(R, b, check=check))
        add(f'screw_log{tag}', 'screw_log', lambda check=check: rt.screw_log(R, b, check=check))
        add(f'transform_points{tag}', 'transform_points',
            lambda check=check: rt.transform_points(R, b, [1.0, 2.0, 3.0], check=check))
        add(f'compose_transforms{tag}', 'compose_transforms',
            lambda check=check: rt.compose_transforms(R, b, R2, -b, check=check))
        add(f'invert_transform{tag}', 'invert_transform',
            lambda check=check: rt.invert_transform(R, b, check=check))
        add(f'transform_to_homogeneous{tag}', 'transform_to_homogeneous',
            lambda check=check: rt.transform_to_homogeneous(R, b, check=check))
        add(f'homogeneous_to_transform{tag}', 'homogeneous_to_transform',
            lambda check=check: rt.homogeneous_to_transform(
                np.block([[R, b[:, None]], [np.zeros((1, 3)), np.ones((1, 1))]]), check=check))
        add(f'rotation_distance{tag}', 'rotation_distance',
            lambda check=check: rt.rotation_distance(R, R2, check=check))
        add(f'screw_interpolate{tag}', 'screw_interpolate',
            lambda check=check: rt.screw_interpolate(R, b, R2, -b, 0.25, check=check))
        for seq in rt.EULER_SEQUENCES:
            add(f'decompose_{seq}{tag}', 'decompose',
                lambda seq=seq, check=check: rt.decompose(R, b, seq, check=check))
    add('is_rotation', 'is_rotation', lambda: rt.is_rotation(R))
    add('validate_rotation', 'validate_rotation', lambda: rt.validate_rotation(R))
    add('rotvec_to_matrix', 'rotvec_to_matrix', lambda: rt.rotvec_to_matrix([0.3, -1.0, 0.5]))
    add('axis_angle_to_matrix', 'axis_angle_to_matrix',
        lambda: rt.axis_angle_to_matrix([0.0, 0.6, 0.8], 1.3))
    add('quaternion_to_matrix', 'quaternion_to_matrix',
        lambda: rt.quaternion_to_matrix([0.1, -0.5, 0.3, 0.8]))
    add('screw_exp', 'screw_exp', lambda: rt.screw_exp([0.3, -1.0, 0.5, 1.0, 2.0, -0.5]))
    add('transform_from_screw', 'transform_from_screw',
        lambda: rt.transform_from_screw([0.0, 0.6, 0.8], [1.0, 2.0, 0.0], 1.3, -0.4))
    add('frame_to_matrix', 'frame_to_matrix',
        lambda: rt.frame_to_matrix(R[:, 0], R[:, 1], R[:, 2]))
    for seq in rt.EULER_SEQUENCES:  # rotation_node's per-message path (and rot_tools.ros.messages:
        # quaternion_to_matrix and euler_to_matrix of tuples of floats, met above)
        add(f'decompose_values_{seq}', 'decompose_values',
            lambda seq=seq: (decomposition.decompose_values(R, b, seq),
                             decomposition.decompose_values(R2, b, seq)))
    return calls


def function_name(key):
    """Return a readable function name for a kernel key, e.g. euler_angles_kernel_ZYX_checked."""
    from rot_tools.core.euler import _PARSED
    name = key.split('[')[0].split(' ')[0].removeprefix('rot_tools.').replace('.', '_')
    for seq, spec in _PARSED.items():
        if f'spec={spec!r}' in key:
            name += f'_{seq}'
    checked = re.search(r' checked\((\d+)\)$', key)
    if checked:
        name += '_checked' + ('' if checked.group(1) == '1' else checked.group(1))
    if not name.isidentifier():
        raise ValueError(f'no function name for the kernel {key}')
    return name


def record():
    """
    Run ordinary_calls with no generated code; return what they ran.

    Run ordinary_calls with no generated code: [(name, key, kernel, tails, outputs)],
    sorted by function name.
    """
    saved = dict(_backend.GENERATED)
    _backend.GENERATED.clear()
    _backend._CODE_OF.clear()
    _backend.bind_conversions()  # (to no code: every one-item call then runs the kernel)
    _backend.RECORD = {}
    try:
        for label, _, call in ordinary_calls():
            try:
                call()
            except RotationError as exc:
                raise RuntimeError(f'the ordinary call {label} was refused: {exc}') from None
        found = sorted((function_name(key), key, *_backend.RECORD[key])
                       for key in _backend.RECORD)  # (by name: the order of calls is free)
    finally:
        _backend.RECORD = None
        _backend.GENERATED.update(saved)
        _backend._CODE_OF.clear()
        _backend.bind_conversions()
    return found


HEADER = f'''\
# flake8: noqa
"""
Generated by ``{COMMAND}`` from the kernels of rot_tools: do not edit.

One function per kernel the library and rotation_node use on one item: the kernel written
out straight-line by rot_tools.core._trace (the same float operations as the kernel on Python
floats, so the same bits). rot_tools.core._backend finds them in CODE by the kernel's key.
test/test_backend.py fails when this file is not what the kernels give: after changing or
adding a kernel, run the command above.
"""

'''
CHUNK_HEADER = f'''\
# flake8: noqa
"""
Generated by ``{COMMAND}`` from the kernels of rot_tools: do not edit.

One function per kernel of rot_tools/core/_generated.py, for a chunk of a batch: the kernel
written out by rot_tools.core._trace_batch as NumPy calls into the caller's buffers (the same
ufuncs in the same order as the kernel on NumPy arrays, so the same bits).
rot_tools.core._backend finds them in CHUNKS by the kernel's key, with the numbers of float and
bool buffers each needs. test/test_backend.py fails when this file is stale.
"""

import numpy as _np

'''


def sources():
    """Return {path: text} of both generated modules, from the kernels as they are now."""
    from rot_tools.core import _trace, _trace_batch  # (only here: rot_tools never imports them)
    packers, functions, table, ufuncs, chunks, chunk_table = set(), [], [], set(), [], []
    found = record()
    names = [name for name, *_ in found]
    if len(set(names)) != len(names):
        raise ValueError(f'two kernels would have one function name: {sorted(names)}')
    for name, key, kernel, tails, outputs in found:
        functions.append(f'# {key}\n' + _trace.function_source(
            name, kernel, _backend.FLOATS, tails, outputs, packers))
        spec = ', '.join(f'({tail!r}, {_trace.DTYPE_NAMES[dtype]})' for tail, dtype in outputs)
        table.append(f'    {key!r}: ([{spec}], {name}),')
        try:
            text, floats, bools, used = _trace_batch.chunk_source(
                name, kernel, _backend.ARRAYS, tails, outputs)
        except _trace.TraceError:
            continue  # (its batches run on the kernel itself)
        chunks.append(f'# {key}\n' + text)
        ufuncs |= used
        chunk_table.append(f'    {key!r}: ([{spec}], {name}, {floats}, {bools}),')
    lines = [HEADER + _trace.PRELUDE.rstrip('\n'), *_trace.op_lines(_backend.FLOATS),
             *_trace.packer_lines(packers), '', '']
    chunk_lines = [CHUNK_HEADER + _trace_batch.PRELUDE.rstrip('\n'),
                   *_trace_batch.ufunc_lines(ufuncs), '', '']
    return {
        GENERATED: '\n'.join(lines) + '\n\n'.join(functions) + '\n\nCODE = {\n'
        + '\n'.join(table) + '\n}\n',
        GENERATED_CHUNKS: '\n'.join(chunk_lines) + '\n\n'.join(chunks) + '\n\nCHUNKS = {\n'
        + '\n'.join(chunk_table) + '\n}\n'}


def main(argv=None):
    parser = argparse.ArgumentParser(prog=COMMAND, description=__doc__.split('\n')[0])
    parser.add_argument('--check', action='store_true',
                        help='only say whether the files are up to date (exit 1 if not)')
    args = parser.parse_args(argv)
    stale = 0
    for path, text in sources().items():
        current = path.read_text(encoding='utf-8') if path.exists() else ''
        if args.check:
            print(f'{path}: {"up to date" if text == current else "STALE: run " + COMMAND}')
            stale += text != current
            continue
        if text != current:
            path.write_text(text, encoding='utf-8')
        # Its bytecode for this interpreter now (even where PYTHONDONTWRITEBYTECODE is set):
        # compiling the module's source takes ~0.1 s, loading the bytecode a few ms.
        py_compile.compile(str(path), doraise=True)
        print(f'{path}: {text.count(chr(10))} lines, {text.count("def ")} functions'
              + ('' if text != current else ' (unchanged)'))
    return 1 if stale else 0


if __name__ == '__main__':
    sys.exit(main())
