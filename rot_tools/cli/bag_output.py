"""
The table and the plot of a bag's topics: ``rot-tools bag --csv`` and ``--plot``.

The CSV has one row per accepted message (csv_header names the columns); its numbers are
made a chunk of rows at a time by rot_tools.io.csv_text, and text cells a spreadsheet would
run as a formula are escaped. The plot draws each topic's roll and pitch on one axis and its
yaw on another (a heading that turns many times would flatten the tilt to lines at 0), for
at most MAX_PLOTTED_TOPICS topics, and says which.
"""

import csv
import io
import os

import numpy as np
from rot_tools.cli import output_file
from rot_tools.io import csv_text


def in_unit(values, degrees):
    """Return angles in degrees when ``degrees``, else as they are (radians)."""
    return np.degrees(values) if degrees else np.asarray(values)

# ---------------------------------------------------------------------------------------
# CSV


def csv_header(seq):
    """Return the CSV's column names."""
    names = ['topic', 'stamp', 'frame_id', 'x', 'y', 'z', 'qx', 'qy', 'qz', 'qw',
             'roll', 'pitch', 'yaw']
    if seq:
        names += [f'{seq}_1', f'{seq}_2', f'{seq}_3']
    return names + ['rx', 'ry', 'rz', 'angle', 'wx', 'wy', 'wz', 'roll_std', 'pitch_std',
                    'yaw_std']


FORMULA_STARTS = ('=', '+', '-', '@', '\t', '\r')
"""First characters that make a spreadsheet run a cell as a formula (OWASP, CSV injection)."""


def csv_text_cell(text):
    """
    Write a text (never a number) as one CSV field, safe to open in a spreadsheet.

    A text starting with one of FORMULA_STARTS gets a single quote before it (OWASP's rule:
    ``=HYPERLINK("x")`` is written ``'=HYPERLINK(""x"")``, read as text); then the field is
    quoted only where CSV needs it.
    """
    if text.startswith(FORMULA_STARTS):
        text = "'" + text
    out = io.StringIO()
    csv.writer(out, lineterminator='\r\n').writerow([text])  # quotes a CR or LF inside
    return out.getvalue()[:-2]


ROWS_PER_CHUNK = 1024
"""Rows made into text at a time (their arrays stay in the CPU's cache)."""


def _number_text(value, precision):
    """One number by the rule of rot_tools.io.csv_text, with Python's (correctly rounded) %f."""
    if value != value:
        return ''
    digits = len('%d' % abs(value)) if abs(value) >= 1 else 0
    text = '%.*f' % (max(0, precision - digits), value)
    if '.' in text:
        text = text.rstrip('0').rstrip('.')
    return '0' if text in ('-0', '') else text


def binary_writer(out):
    """Return a function writing bytes to the text stream ``out`` (through its buffer if any)."""
    buffer = getattr(out, 'buffer', None)
    if buffer is None:
        return lambda data: out.write(data.decode('utf-8'))
    out.flush()
    return buffer.write


def row_values(t, degrees):
    """
    Return the numbers of a Topic's rows, (n, k) float64 in csv_header's order after frame_id.

    x, y, z, qx, qy, qz, qw, roll, pitch, yaw, the --seq angles, rx, ry, rz, angle, wx, wy,
    wz, roll_std, pitch_std, yaw_std; angles (and ω, σ) in degrees when ``degrees``; ω NaN
    where it has no value, σ where the message has no good covariance (or its type none).
    """
    columns = [t.position, t.quaternion, in_unit(t.rpy, degrees)]
    if t.seq_angles is not None:
        columns.append(in_unit(t.seq_angles, degrees))
    columns += [in_unit(t.rotvec, degrees), in_unit(t.angle, degrees)[:, None],
                in_unit(t.omega, degrees), in_unit(t.rpy_std, degrees)]
    return np.hstack(columns)


def write_csv(out, topics, degrees, precision, bag=None, header=True):
    """
    Write the rows of every topic (topic by topic, in the bag's order) to ``out``.

    Numbers rounded to ``precision`` significant digits and ``precision`` decimal places (the
    rule of every number rot-tools prints), trailing zeros dropped, −0 as 0; the stamp
    exactly (from integer nanoseconds); text cells by csv_text_cell; ω empty on a topic's
    first row and where Δt ≤ 0. The text is
    made by rot_tools.io.csv_text for a chunk of rows at once (Python's formatting, one
    number at a time, where its arithmetic would not be exact: precision > 12, |x| ≥ 1e15).
    ``bag``: a first column ``bag`` holding this text on every row (a table of many bags);
    ``header``: whether to write the line of column names.
    """
    seq = next((t.seq for t in topics if t.seq), None)
    if header:
        out.write(','.join((['bag'] if bag is not None else []) + csv_header(seq)) + '\n')
    first = b'' if bag is None else csv_text_cell(bag).encode() + b','
    write = binary_writer(out)
    for t in topics:
        if not len(t.R):
            continue
        values = row_values(t, degrees)
        topic = first + csv_text_cell(t.topic).encode()
        frames = [csv_text_cell(f).encode() for f in t.columns.frame_ids]
        fast = csv_text.numbers_fit(values, precision)
        for start in range(0, len(values), ROWS_PER_CHUNK):
            part = slice(start, start + ROWS_PER_CHUNK)
            if fast:
                write(csv_text.rows(topic, t.ns[part], frames, t.frame[part], values[part],
                                    precision))
                continue
            lines = [b'%s,%s,%s,%s\n' % (
                topic, csv_text.stamp_text(ns).encode(), frames[f],
                ','.join(_number_text(v, precision) for v in row).encode())
                for ns, f, row in zip(t.ns[part].tolist(), t.frame[part].tolist(),
                                      values[part].tolist())]
            write(b''.join(lines))


# ---------------------------------------------------------------------------------------
# Plot


MAX_PLOTTED_TOPICS = 8
"""Topics ``--plot`` draws at most (the first, in the summary's order); ``--topic`` chooses."""


def plot_note(path, drawn, left_out):
    """Return the line ``--plot`` writes on stderr: which topics are drawn, which left out."""
    names = ', '.join(t.topic for t in drawn) or 'no topic'
    note = f'rot-tools bag: --plot {path}: roll, pitch, yaw of {names}'
    if left_out:
        shown = ', '.join(t.topic for t in left_out[:20])
        more = f' and {len(left_out) - 20} more' if len(left_out) > 20 else ''
        note += (f'; left out, {len(left_out)} (at most {MAX_PLOTTED_TOPICS} topics are '
                 f'drawn; choose them with --topic): {shown}{more}')
    return note + '\n'


def write_plot(path, topics, degrees):
    """
    Roll and pitch, then yaw (continuous), against time: two axes per topic (matplotlib).

    Roll and pitch have an axis of their own: beside a yaw that turns through 2,000°, their
    ±10° would be flat lines at 0. Every topic given is drawn (the caller bounds them); the
    file is written whole or not at all (rot_tools.cli.output_file), in the format of its
    extension.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    panels = max(1, len(topics))
    fig = Figure(figsize=(9.0, 3.4 * panels + 0.6), layout='constrained')
    FigureCanvasAgg(fig)
    axes = fig.subplots(2 * panels, 1, sharex=True, squeeze=False)[:, 0]
    starts = [int(t.ns.min()) for t in topics if len(t.ns)]
    ns0 = min(starts) if starts else 0
    unit = 'deg' if degrees else 'rad'
    for k, t in enumerate(topics):
        tilt, heading = axes[2 * k], axes[2 * k + 1]
        tilt.set_title(f'{t.topic} ({t.msgtype})', fontsize=10, loc='left')
        for ax in (tilt, heading):
            ax.set_ylabel(f'angle ({unit})')
            ax.grid(True, alpha=0.3)
        if not len(t.R):
            tilt.text(0.5, 0.5, 'no accepted message', transform=tilt.transAxes, ha='center')
            continue
        angles, time = in_unit(t.rpy, degrees), 1e-9 * (t.ns - ns0)
        for i, (name, color) in enumerate(zip(('roll', 'pitch', 'yaw'),
                                              ('tab:red', 'tab:green', 'tab:blue'))):
            ax = heading if name == 'yaw' else tilt
            ax.plot(time, angles[:, i], color=color, lw=1.0, label=name,
                    gid=f'{t.topic}:{name}')
        for ax in (tilt, heading):
            ax.legend(loc='upper left', fontsize=8, ncols=2)
    axes[-1].set_xlabel(f'time (s) from header stamp {csv_text.stamp_text(ns0)}')
    fig.suptitle('roll, pitch, yaw (REP-103, extrinsic xyz), continuous', fontsize=11)
    with output_file.complete_or_nothing(path, 'wb') as out:
        fig.savefig(out, format=os.path.splitext(str(path))[1][1:].lower() or 'png')
