#!/usr/bin/env python3
"""The example clients (examples/) against spindled on the simulated device:
each runs to its end, exits 0 and shows what it says it shows.
Usage: test-examples.py SPINDLED ORBITS TORUS HELLO"""
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

spindled, orbits, torus, hello = sys.argv[1:5]
tmp = tempfile.mkdtemp(prefix='spindle-examples-')


def check(cond, what):
    if not cond:
        print('FAIL:', what)
        sys.exit(1)


# --help: the usage on stdout, exit 0; a bad option: usage on stderr, exit 2.
for prog in (orbits, torus, hello):
    name = os.path.basename(prog)
    p = subprocess.run([prog, '--help'], capture_output=True, text=True, timeout=10)
    check(p.returncode == 0 and p.stdout.startswith(f'usage: {name}'), f'{name} --help: {p.returncode} {p.stdout!r}')
    p = subprocess.run([prog, '--bogus'], capture_output=True, text=True, timeout=10)
    check(p.returncode == 2 and p.stderr.startswith(f'usage: {name}'), f'{name} --bogus: {p.returncode} {p.stderr!r}')


def start(config):
    conf = os.path.join(tmp, 'spindled.conf')
    with open(conf, 'w') as f:
        f.write('profile = small\nrenderer = cpu\n' + config)
    sock = os.path.join(tmp, 's.sock')
    d = subprocess.Popen([spindled, '-c', conf, '-s', sock], stderr=subprocess.DEVNULL)
    for _ in range(500):
        if os.path.exists(sock):
            return d, sock
        time.sleep(0.01)
    check(False, 'spindled never listened')


def stop(d):
    d.send_signal(signal.SIGTERM)
    check(d.wait(timeout=10) == 0, 'spindled exits 0')


def run(args, sock):
    p = subprocess.run(args + ['--socket', sock], capture_output=True, text=True, timeout=30)
    check(p.returncode == 0, f'{args}: exit {p.returncode}: {p.stderr}')
    return p.stdout, p.stderr


d, sock = start('')
# orbits animates once per shown volume: at 1800 rpm (small) about 30 a
# second once lit; lighting takes a fraction of a second.
out, _ = run([orbits, '--seconds', '2'], sock)
frames = int(re.search(r'(\d+) frames shown', out).group(1))
check(frames >= 10, f'orbits showed only {frames} frames: {out}')
check('display: locked' in out, f'orbits saw the lock: {out}')
out, _ = run([torus, '--rings', '24'], sock)
check(re.search(r'torus: 576 triangles shown by volume \d+', out), f'torus: {out}')
# Exclusive at the default policy: root may (the suite runs as root or as
# the daemon's user).
out, err = run([torus, '--rings', '12', '--exclusive'], sock)
check('shown by volume' in out and 'refused' not in err, f'torus --exclusive: {out} {err}')
stop(d)

# Policy none: the example falls back to a shared layer.
d, sock = start('exclusive = none\n')
out, err = run([torus, '--exclusive'], sock)
check('exclusive layer refused (not allowed)' in err and 'shown by volume' in out, f'{out} {err}')
stop(d)
shutil.rmtree(tmp)
print('examples: ok')
