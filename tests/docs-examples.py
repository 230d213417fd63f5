#!/usr/bin/env python3
"""Runs every command of README.md, CONTRIBUTING.md and docs/*.md, as a user would, and fails on any that fails.

A command is a line of a code block (indented by four spaces or more, or fenced as sh/bash/shell)
that starts with a program the docs use (fractalbake, printf, listgeo, ...), with its continuation
lines. Each document's commands run in order, in a scratch folder of their own, through bash (so
pipes, loops and redirections work as written), with `fractalbake` on PATH and `docs/` linked in,
so that the example inputs resolve as they do from the repository's root. Sizes are reduced where
a command gives one: --size and --set size= to at most 1024 pixels a side (the aspect kept; not
where it names a --heightmap-engine, whose sizes are the engine's),
--points to 2e6, --insert to 20000. A few commands are not run, each for the reason listed below
(and Blender's where it is not installed).

Usage: docs-examples.py REPO_ROOT PATH/TO/fractalbake [DOC.md ...]
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

CMD = re.compile(r'^(fractalbake |\./scripts/|scripts/|bench/|\./build/|printf |listgeo |cmake |idiff |oiiotool |'
                 r'exrmaketiled |python3 |for |sbatch |bash |mkdir |blender )')
NOT_RUN = [
    (r'^\./scripts/test\.sh', 'the test suite itself, which runs this'),
    (r'^\./scripts/bake\.sh', 'builds into the repository (build/, out/); `fractalbake render` is run below'),
    (r'^bench/run\.sh', 'installs the peers and runs for minutes; bench/RESULTS.md holds its output'),
    (r'^cmake ', 'rebuilds the tree, which CTest has just built'),
    (r'scripts/fuzz\.sh', 'the CTest entry `fuzz` runs it'),
    (r'scripts/try-generator\.sh', 'the CTest entry `recipe` runs it'),
    (r'scripts/golden\.sh', 'the CTest entry `golden` runs it (and `update` rewrites the references)'),
    (r'scripts/bench-compare\.sh', 'builds another commit and benches for minutes; the CTest entry '
     '`cli-bench-compare` runs it on a tiny bench'),
    (r'scripts/gpu-check\.sh', 'a check for a GPU machine; the CTest entry `cli-gpu-check` runs it on lavapipe at a tiny scale'),
    (r'^sbatch ', 'needs a Slurm cluster'),
    (r'slurm-bake\.sh', 'needs a Slurm cluster; the CTest entry `cli-slurm` runs it on one it starts'),
]


def complete(text):
    """The text parses as whole shell commands (not the start of a loop)."""
    return subprocess.run(['bash', '-n', '-c', text], stderr=subprocess.DEVNULL).returncode == 0


def commands(path):
    out, cur, fence = [], None, None
    for i, line in enumerate(open(path, encoding='utf-8').read().split('\n')):
        if line.strip().startswith('```'):
            fence = None if fence is not None else line.strip()[3:].strip()
            cur = None
            continue
        if fence is not None:
            if fence not in ('', 'sh', 'bash', 'shell'):
                continue
            text = line.strip()
        else:
            m = re.match(r'^ {4,}(\S.*)$', line)
            if not m:
                cur = None
                continue
            text = m.group(1).strip()
        if cur is not None and cur['text'].endswith('\\'):
            cur['text'] = cur['text'][:-1].rstrip() + ' ' + text
            continue
        if cur is not None and not complete(cur['text']):  # a loop's body, up to its `done`
            cur['text'] += '\n' + text
            continue
        if CMD.match(text) and not text.startswith('fractalbake:'):
            cur = {'line': i + 1, 'text': text}
            out.append(cur)
        else:
            cur = None
    return out


def shrink_size(m, least=16):
    w, h = int(m.group(2)), int(m.group(3))
    k = max(w, h) / 1024.0
    if k > 1:
        w, h = max(least, round(w / k)), max(least, round(h / k))
    return '%s%dx%d' % (m.group(1), w, h)


def reduce(cmd):
    least = 64 if ' bench' in cmd else 16
    # an engine's heightmap takes only the sizes of its table (and a tiled one their sums): such a
    # bake keeps its size, as a user runs it (a terrain of 2017 x 2017 takes about a second)
    if '--heightmap-engine' not in cmd:
        cmd = re.sub(r'(--size[ =])(\d+)x(\d+)', lambda m: shrink_size(m, least), cmd)
        cmd = re.sub(r'(size=)(\d+)x(\d+)', lambda m: shrink_size(m, least), cmd)

    def cap(limit):
        def f(m):
            try:
                v = float(m.group(2))
            except ValueError:
                return m.group(0)
            return m.group(1) + ('%d' % min(v, limit))
        return f
    cmd = re.sub(r'(--points[ =])([0-9.e+]+)', cap(2e6), cmd)
    cmd = re.sub(r'(--insert[ =])([0-9.e+]+)', cap(20000), cmd)
    return cmd


def user_path():
    """PATH as a user's shell has it: without the folder of the Python that runs this test when a
    version manager (pyenv) put it first, which would hand Blender's embedded Python that
    interpreter's library in place of the system's (no numpy there)."""
    mine = os.path.dirname(os.path.realpath(sys.executable))
    return [d for d in os.environ.get('PATH', '').split(os.pathsep)
            if d and not (os.path.realpath(d) == mine and mine not in ('/usr/bin', '/bin'))]


def main():
    root, fb = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    docs = sys.argv[3:] or ['README.md', 'CONTRIBUTING.md'] + sorted(
        'docs/' + f for f in os.listdir(os.path.join(root, 'docs')) if f.endswith('.md'))
    ran = failed = skipped = 0
    vulkan = subprocess.run([fb, 'devices'], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL).stdout.startswith(b'#')
    for doc in docs:
        cmds = commands(os.path.join(root, doc))
        if not cmds:
            continue
        scratch = tempfile.mkdtemp(prefix='fb-docs-')
        try:
            os.symlink(os.path.join(root, 'docs'), os.path.join(scratch, 'docs'))
            bindir = os.path.join(scratch, '.bin')
            os.mkdir(bindir)
            os.symlink(fb, os.path.join(bindir, 'fractalbake'))
            env = dict(os.environ, PATH=os.pathsep.join([bindir] + user_path()),
                       XDG_RUNTIME_DIR=os.environ.get('XDG_RUNTIME_DIR', scratch))
            for c in cmds:
                why = next((r for p, r in NOT_RUN if re.search(p, c['text'])), None)
                if not why and '--backend vulkan' in c['text'] and not vulkan:
                    why = 'no Vulkan device here'
                if not why and c['text'].startswith('blender ') and not shutil.which('blender'):
                    why = 'Blender is not installed here'
                where = '%s:%d' % (doc, c['line'])
                if why:
                    print('not run  %s: %s  (%s)' % (where, c['text'], why))
                    skipped += 1
                    continue
                run = reduce(c['text'])
                p = subprocess.run(['bash', '-c', 'set -o pipefail; ' + run], cwd=scratch, env=env,
                                   stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                   timeout=600)
                ran += 1
                if p.returncode != 0:
                    failed += 1
                    tail = p.stdout.decode(errors='replace').strip().split('\n')[-3:]
                    print('FAIL     %s: exit %d: %s\n         %s' % (where, p.returncode, run, '\n         '.join(tail)))
                else:
                    print('ok       %s: %s' % (where, run))
        finally:
            shutil.rmtree(scratch, ignore_errors=True)
    # the docs are for users: the papers by name, never the team's notes
    for doc in docs:
        text = open(os.path.join(root, doc), encoding='utf-8').read()
        for bad in ('SPEC.md', '../shared'):
            if bad in text:
                print('FAIL     %s cites %s, which users do not have' % (doc, bad))
                failed += 1
    print('%d commands run, %d failed, %d not run (reasons above)' % (ran, failed, skipped))
    return 1 if failed or ran < 40 else 0


sys.exit(main())
