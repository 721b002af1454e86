#!/usr/bin/env python3
"""Model files that used to crash spindlectl, or that must be refused: each
gives a line on stderr naming the file and exit status 1, never a signal
(tests/data/bad-models/). The good test models still load (show goes on to
connect, to a socket nobody listens on), and a crash of the loader child,
forced by a test hook, is reported as such by the tests' build of
spindlectl.
Usage: test-bad-models.py SPINDLECTL SPINDLECTL_WITH_HOOKS DATA_DIR WORK_DIR"""
import os
import subprocess
import sys

ctl, ctl_hooks, data_dir, work = sys.argv[1:5]
bad_dir = os.path.join(data_dir, 'bad-models')
nosock = os.path.join(work, 'bad-models-no-daemon.sock')
failures = []


def expect(cond, what):
    if not cond:
        failures.append(what)
        print('FAIL:', what)


def show(path, prog=ctl, env=None):
    e = dict(os.environ)
    e.pop('SPINDLE_SOCKET', None)
    e.update(env or {})
    p = subprocess.run([prog, '--socket', nosock, 'show', path], capture_output=True, text=True,
                       timeout=100, env=e)
    return p.returncode, p.stderr


def bad_files():
    out = os.path.join(work, 'bad-models')
    subprocess.run([sys.executable, os.path.join(bad_dir, 'make-bad-models.py'), data_dir, out], check=True)
    paths = [os.path.join(out, n) for n in sorted(os.listdir(out))]
    # Committed inputs (fuzzing finds): everything but the script and README.
    paths += [os.path.join(bad_dir, n) for n in sorted(os.listdir(bad_dir))
              if not n.endswith(('.py', '.md')) and not n.startswith('.')]
    return paths


for path in bad_files():
    # A file that hangs assimp costs the loader's whole CPU limit (30 s):
    # the tests' build runs it with 2 s.
    if 'hang' in os.path.basename(path):
        rc, err = show(path, ctl_hooks, {'SPINDLE_MODEL_TEST_CPU_S': '2'})
        expect('the model loader used more than 2 s of CPU time' in err, f'{path}: stopped: {err!r}')
        # A load that takes over a second says that it goes on.
        expect(f'spindlectl: {path}: loading, 1 s so far' in err, f'{path}: progress after a second: {err!r}')
    else:
        rc, err = show(path)
    print(f'{os.path.basename(path)}: exit {rc}: {err.strip()}')
    expect(rc == 5, f'{path}: exit status 5 (a bad input file), got {rc}')
    # The last line names the file (a crashing assimp may have said something first).
    last = err.splitlines()[-1] if err else ''
    expect(last.startswith(f'spindlectl: {path}: '), f'{path}: a last line naming it: {err!r}')
    expect('cannot connect' not in err, f'{path}: refused before connecting: {err!r}')

for name in ('bunny.ply', 'cube.stl', 'lines.obj', 'points.ply', 'transformed.gltf'):
    rc, err = show(os.path.join(data_dir, name))
    expect(rc == 3 and 'cannot connect to spindled' in err, f'{name} loads: {err!r}')

bunny = os.path.join(data_dir, 'bunny.ply')
for hook, sig in (('segv', 11), ('abort', 6)):
    rc, err = show(bunny, ctl_hooks, {'SPINDLE_MODEL_TEST_HOOK': hook})
    want = f'spindlectl: {bunny}: the model loader crashed (signal {sig})\n'
    expect(rc == 5 and err == want, f'hook {hook}: exit {rc}, {err!r}, expected {want!r}')
rc, err = show(bunny, ctl, {'SPINDLE_MODEL_TEST_HOOK': 'segv'})
expect('cannot connect' in err, f'the installed spindlectl ignores the test hooks: {err!r}')

print('failures:', len(failures))
sys.exit(1 if failures else 0)
