"""Command-line words shared by rot-tools and rotation_client."""

import argparse
import re

NEGATIVE_NUMBER = r'-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?|-(inf|infinity|nan)'
"""A negative number as typed: -30, -.5, -1e-3, -inf, -nan (case ignored)."""


def negative_numbers_as_values(argv):
    """
    Return argv with every negative number marked as a value for argparse.

    argparse reads '-30' and '-.5' as values but '-1e-3' or '-inf' as unknown options. A
    word that starts with a space is never an option, and float() ignores the space, so each
    negative number gets one in front (none after '--', where argparse takes words as they
    are). No option of ours looks like a number, so nothing is shadowed.
    """
    words, rest = [], False
    for word in argv:
        rest = rest or word == '--'
        number = not rest and re.fullmatch(NEGATIVE_NUMBER, word, re.IGNORECASE)
        words.append(' ' + word if number else word)
    return words


def whole_number(text):
    """Read an integer ≥ 1 (argparse type of ``--jobs``, ``--count``), else say why not."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f'must be a whole number >= 1, got {text.strip()!r}')
    return value
