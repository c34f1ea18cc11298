"""
The table and the plot of a bag's topics: ``rot-tools bag --csv`` and ``--plot``.

The CSV has one row per accepted message (csv_header names the columns), numbers rounded to
``--precision``, stamps exact; the plot draws each topic's roll and pitch on one axis and its
yaw on another.
"""

import csv
import io
import os

import numpy as np
from rot_tools.cli import output_file
from rot_tools.core.euler import RPY_SEQUENCE

NS_PER_S = 1_000_000_000


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


def text_cell(text):
    """
    Return a text (never a number) as one CSV cell, safe to open in a spreadsheet.

    A text starting with one of FORMULA_STARTS gets a single quote before it (OWASP's rule:
    ``=HYPERLINK("x")`` is written ``'=HYPERLINK(""x"")``, read as text); then the csv module
    quotes the cell where CSV needs it (a comma, a quote, a line break: a CR too, which a
    writer whose lines end in LF alone would leave bare).
    """
    if text.startswith(FORMULA_STARTS):
        text = "'" + text
    cell = io.StringIO()
    csv.writer(cell, lineterminator='\r\n').writerow([text])
    return cell.getvalue()[:-2]


def stamp_text(ns):
    """Return the text of a stamp of ``ns`` (int) nanoseconds: '[-]s.nnnnnnnnn', exact."""
    sec, nsec = divmod(abs(ns), NS_PER_S)
    return f'{"-" if ns < 0 else ""}{sec}.{nsec:09d}'


def rounded(values, precision):
    """
    Return ``values`` rounded to ``precision`` significant digits and decimal places.

    The rule of every number rot-tools prints (rot_tools.io.report.round_number), as a batch
    of numbers: a value x with 10ᵉ ≤ |x| < 10ᵉ⁺¹ keeps k = precision − 1 − e decimals when
    |x| ≥ 1 and k = precision when |x| < 1, as rint(x·10ᵏ)/10ᵏ (k < 0: rint(x/10⁻ᵏ)·10⁻ᵏ,
    tens and more of the integer part rounded away; Python's formatting rounds where 10⁻ᵏ
    is no longer exact in float64). −0 becomes 0; NaN and ±inf stay.
    """
    x = np.asarray(values, dtype=np.float64)
    with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
        a = np.abs(x)
        e = np.floor(np.log10(a))
        e -= np.power(10.0, e) > a  # log10 rounded up past a power of ten
        e += np.power(10.0, e + 1) <= a  # ... or down below one
        k = np.where(a >= 1, precision - 1 - e, precision)
        k = np.where(np.isfinite(x), k, 0)
        up = np.power(10.0, np.maximum(k, 0))
        down = np.power(10.0, np.maximum(-k, 0))
        scaled = x * up / down
        # |x·10ᵏ| ≥ 2⁵²: the digit rounded to is below x's own last bit, x is its rounding
        out = np.where(np.isfinite(x) & (np.abs(scaled) < 2.0 ** 52),
                       np.rint(scaled) * down / up, x)
    big = np.flatnonzero(np.abs(x) >= 10.0 ** (precision + 22))  # 10⁻ᵏ beyond float64's
    out.flat[big] = [float(f'{v:.{precision}g}') for v in x.flat[big]]  # exact powers of ten
    return out + 0.0


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


ROWS_PER_CHUNK = 256
"""Rows made into Python values at a time, then written."""


def write_csv(out, topics, degrees, precision, bag=None, header=True):
    """
    Write the rows of every topic (topic by topic, in the bag's order) to ``out``.

    Numbers :func:`rounded` to ``precision``, each written by the csv module as its shortest
    round-trip text (Python's ``repr``), NaN as an empty cell (ω on a topic's first row and
    where Δt ≤ 0, σ where unknown); the stamp exactly (:func:`stamp_text`); text cells by
    :func:`text_cell`. ``bag``: a first column ``bag`` holding this text on every row (a table
    of many bags); ``header``: whether to write the line of column names.
    """
    seq = next((t.seq for t in topics if t.seq), None)
    writer = csv.writer(out, lineterminator='\n')
    if header:
        writer.writerow((['bag'] if bag is not None else []) + csv_header(seq))
    first = '' if bag is None else text_cell(bag) + ','
    for t in topics:
        if not len(t.R):
            continue
        head = first + text_cell(t.topic) + ','
        frames = np.array([text_cell(f) for f in t.columns.frame_ids], object)
        values = rounded(row_values(t, degrees), precision)
        for start in range(0, len(values), ROWS_PER_CHUNK):
            part = slice(start, start + ROWS_PER_CHUNK)
            numbers = values[part].astype(object)
            numbers[np.isnan(values[part])] = ''
            for ns, frame, row in zip(t.ns[part].tolist(), frames[t.frame[part]],
                                      numbers.tolist()):
                out.write(f'{head}{stamp_text(ns)},{frame},')  # text cells made above
                writer.writerow(row)


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

    Roll and pitch have an axis of their own: beside a yaw that turns many times, a small tilt
    would be a flat line at 0. Every topic given is drawn (the caller bounds them); the
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
    axes[-1].set_xlabel(f'time (s) from header stamp {stamp_text(ns0)}')
    fig.suptitle(f'roll, pitch, yaw (REP-103, extrinsic {RPY_SEQUENCE}), continuous', fontsize=11)
    with output_file.complete_or_nothing(path, 'wb') as out:
        fig.savefig(out, format=os.path.splitext(str(path))[1][1:].lower() or 'png')
