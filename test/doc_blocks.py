"""The example blocks of README.md and doc/*.md, to compare with real output."""

import doctest
from pathlib import Path
import re

REPO = Path(__file__).resolve().parent.parent
TAG = re.compile(r'<!--\s*output:\s*([\w.-]+)\s*-->')
FENCE = re.compile(r'^(\s*)(`{3,})\s*([\w+-]*)\s*$')


class Block:
    """A fenced block of a Markdown file: its language, text, tag and first line number."""

    def __init__(self, path, line, lang, text, tag):
        self.path, self.line, self.lang, self.text, self.tag = path, line, lang, text, tag

    def __repr__(self):
        return f'{self.path.relative_to(REPO)}:{self.line}'


def doc_files():
    """README.md and every doc/*.md, in a fixed order."""
    return [REPO / 'README.md'] + sorted((REPO / 'doc').glob('*.md'))


def blocks(path):
    """Every fenced block of the Markdown file ``path``, with the tag on the line before it."""
    lines = Path(path).read_text(encoding='utf-8').splitlines()
    found, i = [], 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        indent, fence, lang = m.groups()
        tag = None
        for before in reversed(lines[:i]):
            if before.strip():
                t = TAG.search(before)
                tag = t.group(1) if t else None
                break
        body, j = [], i + 1
        while j < len(lines) and lines[j].strip() != fence:
            body.append(lines[j][len(indent):] if lines[j].startswith(indent) else lines[j])
            j += 1
        found.append(Block(Path(path), i + 1, lang, '\n'.join(body) + '\n', tag))
        i = j + 1
    return found


def all_blocks():
    """Every fenced block of README.md and doc/*.md."""
    return [b for path in doc_files() for b in blocks(path)]


def doc_block(name):
    """Return the text of the block tagged ``<!-- output: name -->`` (KeyError if none)."""
    tagged = [b for b in all_blocks() if b.tag == name]
    if len(tagged) != 1:
        raise KeyError(f'{len(tagged)} blocks tagged {name!r} in README.md and doc/*.md')
    return tagged[0].text


def console_steps(text):
    """Split a console block into [(command, expected output)]: commands start with '$ '."""
    steps = []
    for line in text.splitlines():
        if line.startswith('$ '):
            steps.append([line[2:], []])
        elif steps:
            steps[-1][1].append(line)
        elif line.strip():
            raise ValueError(f'output before the first $ command: {line!r}')
    return [(cmd, '\n'.join(out) + '\n' if out else '') for cmd, out in steps]


def matches(want, got):
    """Tell whether got equals want, ``...`` in want matching any text (doctest ELLIPSIS)."""
    return doctest.OutputChecker().check_output(want, got, doctest.ELLIPSIS)


def assert_doc_output(name, got):
    """Assert that the block tagged ``name`` shows exactly ``got`` (``...`` matches any text)."""
    want = doc_block(name)
    if UPDATE and not matches(want, got):
        update_block(name, got)
        return
    assert matches(want, got), (
        f'the docs block {name!r} no longer matches the real output:\n--- docs\n{want}'
        f'--- real\n{got}')


UPDATE = bool(__import__('os').environ.get('ROT_TOOLS_UPDATE_DOCS'))
"""With ROT_TOOLS_UPDATE_DOCS=1, a block that differs from the real output is rewritten with
it (review the diff before committing) instead of failing the test."""


def update_block(name, text):
    """Replace the body of the block tagged ``name`` with ``text``."""
    for block in all_blocks():
        if block.tag == name:
            lines = block.path.read_text(encoding='utf-8').splitlines(keepends=True)
            fence = lines[block.line - 1].strip().split()[0].rstrip('abcdefghijklmnopqrstuvwxyz')
            end = block.line  # the closing fence follows the body
            while lines[end].strip() != fence:
                end += 1
            lines[block.line:end] = [text if text.endswith('\n') else text + '\n']
            block.path.write_text(''.join(lines), encoding='utf-8')
            return
    raise KeyError(name)
