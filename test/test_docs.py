"""
Every example output in README.md and doc/*.md is produced here or by a named test.

The rules (test/doc_blocks.py says how to follow them):
- console blocks of ``$ rot-tools ...`` commands are run, and their output compared;
- pycon blocks (``>>>``) are doctests;
- every other block that shows output is tagged ``<!-- output: NAME -->`` and a test file
  names NAME (it compares the block with the real output it produces);
- the README stays at most 300 lines, cites no course notes by their team names, and keeps
  ``make test`` as its test command (``.ci/run`` runs it).
"""

import doctest
import os
from pathlib import Path
import re
import shutil
import subprocess
import sys

from doc_blocks import all_blocks, blocks, console_steps, doc_files, matches, REPO, UPDATE
import pytest

BLOCKS = all_blocks()
RUNNABLE = re.compile(r'^(rot-tools\b|echo \$\?$)')


def _runnable(block):
    steps = console_steps(block.text)
    return bool(steps) and all(RUNNABLE.match(cmd) for cmd, _ in steps)


CONSOLE = [b for b in BLOCKS if b.lang == 'console' and b.tag is None and _runnable(b)]
DOCTESTS = [b for b in BLOCKS if b.lang in ('pycon', 'python') and '>>>' in b.text]


def _scratch(tmp_path):
    """Make a working directory that looks like the repository (doc/ writable, ../shared)."""
    work = tmp_path / REPO.name
    work.mkdir()
    for entry in REPO.iterdir():
        if entry.name not in ('doc', '.git'):
            (work / entry.name).symlink_to(entry)
    (work / 'doc').mkdir()
    for entry in (REPO / 'doc').iterdir():
        shutil.copy2(entry, work / 'doc' / entry.name)  # a copy: a --plot may overwrite it
    shared = REPO.parent / 'shared'
    if shared.exists():
        (tmp_path / 'shared').symlink_to(shared.resolve())
    return work


def _path_with_rot_tools(tmp_path):
    """PATH with the interpreter's scripts first, and a rot-tools shim if it has none."""
    bin_dir = Path(sys.executable).parent
    dirs = [str(bin_dir)]
    if not (bin_dir / 'rot-tools').exists():
        shim = tmp_path / 'bin'
        shim.mkdir()
        (shim / 'rot-tools').write_text(
            f'#!/bin/sh\nexec "{sys.executable}" -m rot_tools.cli.main "$@"\n')
        (shim / 'rot-tools').chmod(0o755)
        dirs.append(str(shim))
    return os.pathsep.join(dirs + [os.environ.get('PATH', '')])


def run_console(text, tmp_path):
    """Run the $ commands of a console block in one bash; return [(command, want, got)]."""
    steps = console_steps(text)
    script = ['exec 2>&1', '__status=0']
    for k, (cmd, _) in enumerate(steps):
        script += [f"printf '\\n@@step {k}@@\\n'", '(exit $__status)', cmd, '__status=$?']
    env = dict(os.environ, PATH=_path_with_rot_tools(tmp_path), COLUMNS='80',
               SOURCE_DATE_EPOCH='0')
    done = subprocess.run(['bash', '-c', '\n'.join(script)], cwd=_scratch(tmp_path), env=env,
                          capture_output=True, text=True, timeout=300)
    parts = re.split(r'\n@@step \d+@@\n', '\n' + done.stdout)[1:]
    assert len(parts) == len(steps), done.stdout
    return [(cmd, want, got) for (cmd, want), got in zip(steps, parts)]


@pytest.mark.parametrize('block', CONSOLE, ids=repr)
def test_console_block_shows_the_real_output(block, tmp_path):
    steps = run_console(block.text, tmp_path)
    if UPDATE and not all(matches(want, got) for _, want, got in steps):
        _rewrite(block, ''.join(f'$ {cmd}\n{got}' for cmd, _, got in steps))
        return
    for cmd, want, got in steps:
        assert matches(want, got), f'{block}: $ {cmd}\n--- docs\n{want}--- real\n{got}'


def _rewrite(block, text):
    """Replace the body of ``block`` in its file, found again by its text."""
    now = next(b for b in blocks(block.path) if b.text == block.text)
    lines = block.path.read_text(encoding='utf-8').splitlines(keepends=True)
    end = now.line
    while not lines[end].strip().startswith('```'):
        end += 1
    lines[now.line:end] = [text]
    block.path.write_text(''.join(lines), encoding='utf-8')


@pytest.mark.parametrize('path', doc_files(), ids=lambda p: str(p.relative_to(REPO)))
def test_python_examples_are_doctests(path):
    blocks = [b for b in DOCTESTS if b.path == path]
    if not blocks:
        pytest.skip('no >>> examples')
    parser = doctest.DocTestParser()
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.IGNORE_EXCEPTION_DETAIL
                                   | doctest.NORMALIZE_WHITESPACE)
    globs = {'__name__': 'docs'}
    cwd = os.getcwd()
    os.chdir(REPO)
    try:
        for block in blocks:
            test = parser.get_doctest(block.text, globs, f'{block}', str(path), block.line)
            runner.run(test, out=lambda text: None, clear_globs=False)
            globs = test.globs  # DocTest copies its globals: carry them to the next block
    finally:
        os.chdir(cwd)
    failures = runner.summarize(verbose=False)
    assert failures.failed == 0, _doctest_report(blocks, globs)


def _doctest_report(blocks, globs):
    """Re-run the blocks, collecting the failure text for the assertion message."""
    out = []
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.IGNORE_EXCEPTION_DETAIL
                                   | doctest.NORMALIZE_WHITESPACE)
    parser = doctest.DocTestParser()
    globs = {'__name__': 'docs'}
    for block in blocks:
        test = parser.get_doctest(block.text, globs, f'{block}', str(block.path), block.line)
        runner.run(test, out=out.append, clear_globs=False)
        globs = test.globs
    return ''.join(out)


def _test_sources():
    here = Path(__file__).resolve().parent
    return '\n'.join(p.read_text(encoding='utf-8') for p in sorted(here.glob('*.py'))
                     if p.name != Path(__file__).name)


def test_every_tagged_block_is_compared_by_a_test():
    sources = _test_sources()
    tags = [b for b in BLOCKS if b.tag]
    unused = [f'{b} ({b.tag})' for b in tags if f"'{b.tag}'" not in sources]
    assert not unused, f'tagged blocks that no test compares: {unused}'
    names = [b.tag for b in tags]
    assert len(names) == len(set(names)), f'a tag used twice: {sorted(names)}'


def test_no_block_is_only_an_ellipsis():
    # '...' matches any text: a block of nothing else would match every output
    for block in BLOCKS:
        shown = [x for x in block.text.splitlines() if x.strip() and not x.startswith('$ ')]
        if block.tag or block.lang == 'console':
            assert any(x.strip() != '...' for x in shown), f'{block}: shows only ...'


def test_every_console_block_is_run_or_tagged():
    untested = [b for b in BLOCKS if b.lang == 'console' and b.tag is None and not _runnable(b)]
    assert not untested, (f'console blocks showing output that no test produces: {untested}; '
                          'tag them <!-- output: NAME --> and compare them in a test')


def test_output_blocks_are_marked():
    # yaml / text / json blocks show output: they need a tag (or they are input files,
    # marked <!-- input -->)
    for block in BLOCKS:
        if block.lang in ('yaml', 'json', 'text', 'pycon'):
            if block.lang == 'pycon':
                assert '>>>' in block.text, f'{block}: a pycon block without >>>'
                continue
            lines = block.path.read_text(encoding='utf-8').splitlines()[:block.line - 1]
            before = next((x for x in reversed(lines) if x.strip()), '')
            assert block.tag or '<!-- input -->' in before, (
                f'{block}: a {block.lang} block must be tagged <!-- output: NAME --> or '
                '<!-- input -->')


def test_readme_is_short_and_keeps_its_test_command():
    readme = (REPO / 'README.md').read_text(encoding='utf-8')
    assert len(readme.splitlines()) <= 300
    assert 'make test' in readme
    assert 'make test' in (REPO / '.ci' / 'run').read_text(encoding='utf-8')


USER_FACING = re.compile(r'seed 00[0-9]|seed\'s|the seeds|SPEC ?§|\bissue [0-9]+', re.I)


def test_no_internal_names_in_the_docs():
    # Users know the course notes by author and title (doc/references.md), not by the
    # team's names for them.
    found = []
    for path in doc_files():
        for n, line in enumerate(path.read_text(encoding='utf-8').splitlines(), 1):
            if USER_FACING.search(line):
                found.append(f'{path.relative_to(REPO)}:{n}: {line.strip()}')
    assert not found, '\n'.join(found)


def test_links_between_the_docs_resolve():
    broken = []
    for path in doc_files():
        text = path.read_text(encoding='utf-8')
        for target in re.findall(r'\]\(([^)#\s]+)(?:#[^)]*)?\)', text):
            if re.match(r'[a-z]+://', target):
                continue
            if not (path.parent / target).exists():
                broken.append(f'{path.relative_to(REPO)} → {target}')
    assert not broken, broken


@pytest.mark.skipif(shutil.which('bash') is None, reason='needs bash')
def test_the_console_runner_sees_a_wrong_output(tmp_path):
    # the comparison is not vacuous: a changed number or a missing line is caught
    (cmd, want, got), = run_console('$ rot-tools rotvec 0 0 0 | head -2\nmatrix:\n'
                                    '- [1.0, 0.0, 0.0]\n', tmp_path)
    assert matches(want, got)
    assert not matches(want.replace('1.0', '2.0', 1), got)
    assert not matches(want + 'more\n', got)


@pytest.mark.filterwarnings('ignore::DeprecationWarning')  # catkin_pkg's docutils call
def test_changelog_is_in_the_ros_format():
    from catkin_pkg.changelog import get_changelog_from_path
    from catkin_pkg.package import parse_package
    text = (REPO / 'CHANGELOG.rst').read_text(encoding='utf-8')
    assert text.startswith('^' * 31 + '\nChangelog for package rot_tools\n')
    assert '\nForthcoming\n-----------\n' in text
    changelog = get_changelog_from_path(str(REPO / 'CHANGELOG.rst'), 'rot_tools')
    versions = [str(v) for v, _, _ in changelog.foreach_version()]
    assert parse_package(str(REPO / 'package.xml')).version in versions
