#!/usr/bin/env python3
"""spindle-bench-brightness (bench/brightness.c) against spindled on the
simulated device, one daemon per brightness model (`--set brightness=MODE`,
CPU renderer): `--check exact` at the small profile (the axis glows: the
disk's 2-4 px band at least 3x its r0 band, and a wall through the axis
gets one voxel per px^2), `--check even` and `--check uniform` at small,
and `--check even` at perspecta (a few seconds). Where the EGL or OSMesa
renderer runs here (the daemon logs `renderer: egl` / `renderer: osmesa`),
its profile in the default model (even) matches the CPU's: every band and
tube with a meaningful count within 10%. Usage errors exit 2, no daemon 3.

    test-brightness.py SPINDLED BENCH WORKDIR

Every part runs and reports before the test fails; the profiles' numbers
are printed for the log.
"""
import json
import os
import pwd
import signal
import socket
import subprocess
import sys
import time

spindled, bench, work = sys.argv[1:4]
USER = pwd.getpwuid(os.getuid()).pw_name
GL_TOLERANCE = 0.10
MEANINGFUL = 200  # lit voxels (CPU) a band or tube needs to be compared

failures = []


def fail(what):
    print('FAIL:', what)
    failures.append(what)


class Daemon:
    def __init__(self, name, profile, renderer, mode):
        self.name = name
        self.sock = os.path.join(work, f'brightness-{name}.sock')
        self.log = os.path.join(work, f'brightness-{name}.log')
        if os.path.exists(self.sock):
            os.unlink(self.sock)
        with open(self.log, 'w') as log:
            self.proc = subprocess.Popen(
                [spindled, '--device', 'sim', '--profile', profile, '--renderer', renderer, '--socket', self.sock,
                 '--user', USER, '--config', '/dev/null', '--set', f'brightness={mode}'],
                stdout=log, stderr=subprocess.STDOUT)

    def wait(self):
        for _ in range(1000):
            if self.proc.poll() is not None:
                return f'spindled exited with {self.proc.returncode}'
            try:
                with socket.socket(socket.AF_UNIX) as s:
                    s.connect(self.sock)
                    return None
            except OSError:
                time.sleep(0.01)
        return 'spindled did not listen'

    def renderer(self):
        with open(self.log) as f:
            for line in f:
                if 'info: renderer: ' in line:
                    return line.split('renderer: ', 1)[1].strip()
        return None

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        try:
            rc = self.proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            rc = self.proc.wait()
        if rc != 0:
            fail(f'{self.name}: spindled exited with {rc}')
            self.print_log()

    def print_log(self):
        with open(self.log) as f:
            print(f'--- {self.name}: spindled log ---')
            print(f.read(), end='')
            print('---')


def bench_run(args, timeout=120):
    return subprocess.run([bench] + args, capture_output=True, text=True, timeout=timeout)


def summary(profile):
    """One line of the numbers that matter, for the log."""
    peaks = [f'{name} {shape["peak_to_r0"]:.2f}x' for name, shape in profile['shapes'].items()
             if shape.get('peak_to_r0') is not None]
    line = 'brightest from 2 px to r0 over r0: ' + ', '.join(peaks)
    disk = profile['shapes'].get('disk')
    b = [b for b in disk['bands'] if b['lo'] == 2] if disk else []
    if b:
        line += f'; disk 2-4 px {b[0]["relative"]:.2f}x its r0 band'
    spread = profile['spread']
    return line + (f'; spread {spread:.2f}' if spread is not None else '; spread n/a')


def measure(name, profile, mode, check, renderer='cpu'):
    """Runs the tool with --check against a daemon of that model; returns
    the profile (or None)."""
    t0 = time.monotonic()
    d = Daemon(name, profile, renderer, mode)
    out = None
    try:
        why = d.wait()
        if why:
            fail(f'{name}: {why}')
            d.print_log()
            return None
        args = ['--socket', d.sock, '--json'] + (['--check', check] if check else [])
        p = bench_run(args)
        try:
            out = json.loads(p.stdout)
        except ValueError:
            fail(f'{name}: no JSON (exit {p.returncode}): {p.stdout!r} {p.stderr!r}')
            return None
        ran = d.renderer()
        print(f'{name} ({profile}, renderer {ran}, brightness={mode}): {summary(out)}; '
              f'{time.monotonic() - t0:.1f} s')
        if check and p.returncode != 0:
            fail(f'{name}: --check {check} exited {p.returncode}: {p.stderr.strip()}')
        elif not check and p.returncode != 0:
            fail(f'{name}: exited {p.returncode}: {p.stderr.strip()}')
        out['renderer'] = ran
    finally:
        d.stop()
    return out


def exact_sanity(profile):
    """What the exact model gives by construction: a wall through the axis
    lies in one slice and gets one voxel per px^2 from 1 px out."""
    for b in profile['shapes']['wall']['bands']:
        if b['lo'] >= 1 and not 0.9 <= b['value'] <= 1.1:
            fail(f'exact: wall band {b["lo"]:g}-{b["hi"]:g} px has {b["value"]:.3f} voxels/px^2, expected 1')


def compare(gl, cpu, name):
    """Every band and tube with a meaningful count within GL_TOLERANCE."""
    compared = 0
    for shape, c in cpu['shapes'].items():
        g = gl['shapes'][shape]
        pairs = []
        if 'bands' in c:
            for cb, gb in zip(c['bands'], g['bands']):
                pairs.append((f'{shape} {cb["lo"]:g}-{cb["hi"]:g} px', cb, gb))
        for key in ('tubes', 'rings'):
            for ct, gt in zip(c.get(key, []), g.get(key, [])):
                pairs.append((f'{shape} {ct["radius_px"]:g} px', ct, gt))
        for what, cv, gv in pairs:
            if cv['lit'] < MEANINGFUL or not cv['area']:
                continue
            compared += 1
            ratio = gv['value'] / cv['value']
            if abs(ratio - 1) > GL_TOLERANCE:
                fail(f'{name}: {what}: {gv["value"]:.4f} voxels/px^2 against the CPU\'s {cv["value"]:.4f} '
                     f'({ratio:.3f}x)')
    print(f'{name}: {compared} bands and tubes compared with the CPU renderer')


def main():
    t0 = time.monotonic()
    for args, rc in ((['--check', 'nope'], 2), (['--shapes', 'disk,nope'], 2), (['extra'], 2),
                     (['--socket', os.path.join(work, 'brightness-none.sock')], 3)):
        p = bench_run(args, timeout=30)
        if p.returncode != rc:
            fail(f'{" ".join(args)}: exit {p.returncode}, expected {rc}: {p.stderr!r}')

    exact = measure('small-exact', 'small', 'exact', 'exact')
    if exact:
        exact_sanity(exact)
    even = measure('small-even', 'small', 'even', 'even')
    measure('small-uniform', 'small', 'uniform', 'uniform')
    measure('perspecta-even', 'perspecta', 'even', 'even')

    for renderer in ('egl', 'osmesa'):
        gl = measure(f'small-even-{renderer}', 'small', 'even', None, renderer)
        if gl is None:
            continue
        if gl['renderer'] != renderer:
            print(f'{renderer}: not available here (the daemon runs {gl["renderer"]}): not compared')
        elif even:
            compare(gl, even, f'{renderer} against cpu')

    print(f'{time.monotonic() - t0:.1f} s')
    if failures:
        print(f'{len(failures)} failure(s)')
        sys.exit(1)
    print('ok')


if __name__ == '__main__':
    main()
