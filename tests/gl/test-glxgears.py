#!/usr/bin/env python3
"""glxgears, unmodified, on the volumetric display: spindled on the simulated
device (small profile), Xvfb, and glxgears run through the spindle-gl
launcher. Two captures hold lit voxels where the fit mapping (docs/opengl.md;
its centre and scale from the layer's trace) puts the faces of glxgears'
three gears, and they differ (the gears turn); once glxgears is killed the
display is empty again. Skipped (77) only where Xvfb cannot run. In an
AddressSanitizer build the layer needs the ASan runtime loaded first in a
program not built with it: asan=LIBASAN preloads it (Mesa's own leaks are
not checked).
asan-static (a clang build: no shared runtime to preload) skips.
Usage: test-glxgears.py SPINDLED SPINDLECTL SPINDLE_GL plain|asan=LIBASAN|asan-static"""
import math
import os
import select
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time

spindled, ctl, launcher, build = sys.argv[1:5]
tmp = tempfile.mkdtemp(prefix='spindle-glxgears-')
procs = []


def fail(what):
    print('FAIL:', what)
    for name in ('glxgears.err', 'xvfb.log', 'spindled.log', 'trace'):
        path = os.path.join(tmp, name)
        if os.path.exists(path):
            with open(path, errors='replace') as f:
                print(f'--- {name} (end) ---\n' + f.read()[-1500:])
    sys.exit(1)


def skip(why):
    print('SKIP:', why)
    sys.exit(77)


def start_xvfb():
    xvfb = shutil.which('Xvfb')
    if not xvfb:
        skip('no Xvfb (scripts/install-deps installs xvfb)')
    r, w = os.pipe()
    log = open(os.path.join(tmp, 'xvfb.log'), 'w')
    p = subprocess.Popen([xvfb, '-displayfd', str(w), '-screen', '0', '320x240x24', '-nolisten', 'tcp', '-noreset'],
                         pass_fds=[w], stdout=log, stderr=log)
    procs.append(p)
    os.close(w)
    ready, _, _ = select.select([r], [], [], 15)
    num = os.read(r, 64).decode().strip() if ready else ''
    # r stays open while Xvfb runs: it writes the number again if it resets.
    if not num.isdigit():
        p.kill()
        with open(os.path.join(tmp, 'xvfb.log')) as f:
            skip('Xvfb cannot run here: ' + f.read()[-500:])
    return ':' + num


def start_daemon(sock):
    env = dict(os.environ)
    if os.geteuid() == 0:
        env.setdefault('SPINDLE_USER', 'root')
    log = open(os.path.join(tmp, 'spindled.log'), 'w')
    d = subprocess.Popen([spindled, '--device', 'sim', '--profile', 'small', '--renderer', 'cpu', '--socket', sock,
                          '--config', '/dev/null'], stderr=log, env=env)
    procs.append(d)
    for _ in range(500):
        if d.poll() is not None:
            fail(f'spindled exited {d.returncode}')
        try:
            with socket.socket(socket.AF_UNIX) as s:
                s.connect(sock)
                return d
        except OSError:
            time.sleep(0.01)
    fail('spindled did not listen')


def capture(sock, name):
    out = os.path.join(tmp, name)
    p = subprocess.run([ctl, '--socket', sock, 'capture', out], capture_output=True, text=True, timeout=20)
    if p.returncode != 0:
        fail(f'capture: {p.stderr}')
    with open(out, 'rb') as f:
        data = f.read()
    magic, _, _, w, h, n, total, _, flags = struct.unpack('<4sHHIIIIBB', data[:26])
    half, = struct.unpack('<f', data[28:32])
    if magic != b'SVOL':
        fail('capture is not an svol')
    return dict(W=w, H=h, n=n, N=total, mirrored=flags & 1, h=half, planes=data[64:])


def lit_count(vol):
    return sum(bin(b).count('1') for b in vol['planes'])


def pixel(vol, k, u, v, c):
    rb = (vol['W'] + 7) // 8
    off = ((k * 3 + c) * vol['H'] + v) * rb + u // 8
    return vol['planes'][off] >> (7 - u % 8) & 1


def lit_near(vol, p, r=2):
    """A voxel within r pixels (and one image) of volume point p is lit
    (docs/formats.md: image k at angle 2 pi k / N, column u, row v)."""
    x, y, z = p
    n, N = vol['n'], vol['N']
    phi = math.atan2(z, x) % (math.pi if vol['mirrored'] else 2 * math.pi)
    k0 = round(phi / (2 * math.pi / N))
    for dk in (-1, 0, 1):
        k = (k0 + dk) % n
        th = 2 * math.pi * k / N
        s = x * math.cos(th) + z * math.sin(th)
        u0 = math.floor((s + 1) / 2 * vol['W'])
        v0 = math.floor((vol['h'] - y) / (2 * vol['h']) * vol['H'])
        for u in range(u0 - r, u0 + r + 1):
            for v in range(v0 - r, v0 + r + 1):
                if 0 <= u < vol['W'] and 0 <= v < vol['H'] and any(pixel(vol, k, u, v, c) for c in range(3)):
                    return True
    return False


def mat_mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def rot(deg, axis):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    m = [[float(r == q) for q in range(4)] for r in range(4)]
    m[i][i], m[i][j], m[j][i], m[j][j] = c, -s, s, c
    return m


def trans(x, y, z):
    return [[1, 0, 0, x], [0, 1, 0, y], [0, 0, 1, z], [0, 0, 0, 1]]


def apply(m, p):
    return [sum(m[i][k] * (p + [1])[k] for k in range(4)) for i in range(3)]


# glxgears (mesa-utils 8.5): the view (glTranslatef(0, 0, -40), then
# glRotatef 20 about x, 30 about y), and each gear's place, the z of its
# front face and a radius inside that face's annulus (any turn of the gear
# keeps those points on it).
VIEW = mat_mul(mat_mul(trans(0, 0, -40), rot(20, 0)), rot(30, 1))
GEARS = [((-3.0, -2.0), 0.5, 2.3), ((3.1, -2.0), 1.0, 1.1), ((-3.1, 4.2), 0.25, 1.47)]


def face_points():
    for (gx, gy), zf, r in GEARS:
        m = mat_mul(VIEW, trans(gx, gy, 0))
        for a in range(0, 360, 30):
            yield apply(m, [r * math.cos(math.radians(a)), r * math.sin(math.radians(a)), zf])


def read_fit(trace):
    fit = None
    with open(trace) as f:
        for line in f:
            if line.startswith('fit centre '):
                w = line.split()
                fit = ([float(v) for v in w[2:5]], float(w[-1]))
    if not fit:
        fail('no fit in the trace')
    return fit


def wait_shown(trace, n, timeout=15):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if os.path.exists(trace):
            with open(trace) as f:
                if sum(l.startswith('shown ') for l in f) >= n:
                    return
        time.sleep(0.05)
    fail(f'fewer than {n} frames shown in {timeout} s')


def check_gears(vol, fit):
    (cx, cy, cz), s = fit
    pts = [[s * (p[0] - cx), s * (p[1] - cy), s * (p[2] - cz)] for p in face_points()]
    for p in pts:
        if p[0] ** 2 + p[2] ** 2 > 1 or abs(p[1]) > vol['h']:
            fail(f'the fit puts {p} outside the display')
    hits = sum(lit_near(vol, p) for p in pts)
    if hits < 0.9 * len(pts):
        fail(f'only {hits} of {len(pts)} points of the gears\' faces lit')
    return hits, len(pts)


def main():
    if build == 'asan-static':
        skip('AddressSanitizer runtime linked statically: the layer cannot be preloaded into glxgears')
    gears = shutil.which('glxgears')
    if not gears:
        fail('no glxgears (scripts/install-deps installs mesa-utils)')
    display = start_xvfb()
    sock = os.path.join(tmp, 'spindle.sock')
    daemon = start_daemon(sock)
    trace = os.path.join(tmp, 'trace')
    env = dict(os.environ, DISPLAY=display, vblank_mode='0')
    if build.startswith('asan='):
        env['LD_PRELOAD'] = build[5:]
        env['ASAN_OPTIONS'] = 'detect_leaks=0:abort_on_error=1'
    errlog = open(os.path.join(tmp, 'glxgears.err'), 'w')
    g = subprocess.Popen(['sh', launcher, '--socket', sock, '--trace', trace, gears], env=env,
                         stdout=subprocess.DEVNULL, stderr=errlog)
    procs.append(g)
    wait_shown(trace, 3)
    a = capture(sock, 'a.svol')
    time.sleep(0.25)
    b = capture(sock, 'b.svol')
    if g.poll() is not None:
        fail(f'glxgears exited {g.returncode}')
    fit = read_fit(trace)
    for vol in (a, b):
        if lit_count(vol) < 1000:
            fail(f'only {lit_count(vol)} voxels lit')
        hits, total = check_gears(vol, fit)
    if a['planes'] == b['planes']:
        fail('two captures 0.25 s apart are the same: the gears do not turn')
    g.send_signal(signal.SIGTERM)
    g.wait(timeout=10)
    end = time.monotonic() + 3
    while lit_count(capture(sock, 'c.svol')) and time.monotonic() < end:
        time.sleep(0.1)
    if lit_count(capture(sock, 'c.svol')):
        fail('glxgears is gone but its gears still show')
    with open(os.path.join(tmp, 'glxgears.err')) as f:
        err = f.read()
    if 'not shown' in err or 'lost' in err:
        fail(f'glxgears\' stderr: {err}')
    daemon.send_signal(signal.SIGTERM)
    if daemon.wait(timeout=10) != 0:
        fail(f'spindled exited {daemon.returncode}')
    print(f'gears lit at {hits} of {total} face points; fit centre {fit[0]} scale {fit[1]:.4f}')
    print('1 passed, 0 failed')


try:
    main()
finally:
    for p in procs:
        if p.poll() is None:
            p.kill()
            p.wait()
    shutil.rmtree(tmp, ignore_errors=True)
