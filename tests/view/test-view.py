#!/usr/bin/env python3
"""spindle-view against spindled on the simulated device: the window (under
Xvfb, read back with --snapshot) shows the scene's voxels and changes when
the scene changes; --turntable writes a contact sheet from a capture file
and from the daemon; a non-admin user is refused.

    test-view.py SPINDLED SPINDLECTL SPINDLE-VIEW DATA_DIR OUT_DIR
"""
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zlib

SPINDLED, CTL, VIEW, DATA, OUT = sys.argv[1:6]
BRIGHT = 150   # above the outline's grey: only lit voxels are this bright


def png_rgb(path):
    """(width, height, rows of RGB bytes) of an 8-bit RGB PNG."""
    data = open(path, 'rb').read()
    assert data[:8] == b'\x89PNG\r\n\x1a\n', f'{path}: not a PNG'
    p, idat, w = 8, b'', None
    while p < len(data):
        n, kind = struct.unpack_from('>I4s', data, p)
        body = data[p + 8:p + 8 + n]
        if kind == b'IHDR':
            w, h, depth, ctype, _, _, interlace = struct.unpack('>IIBBBBB', body)
            assert depth == 8 and ctype == 2 and not interlace, f'{path}: not 8-bit RGB'
        elif kind == b'IDAT':
            idat += body
        p += 12 + n
    raw = zlib.decompress(idat)
    stride = 3 * w
    rows, prev = [], bytearray(stride)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - 3] if i >= 3 else 0
            b = prev[i]
            c = prev[i - 3] if i >= 3 else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                pr = a if pa <= pb and pa <= pc else b if pb <= pc else c
                line[i] = (line[i] + pr) & 255
        rows.append(bytes(line))
        prev = line
    return w, h, rows


def bright(rows):
    return sum(1 for r in rows for i in range(0, len(r), 3) if max(r[i], r[i + 1], r[i + 2]) > BRIGHT)


def run(args, timeout=60, **kw):
    r = subprocess.run(args, capture_output=True, text=True, timeout=timeout, **kw)
    return r


def main():
    xvfb = shutil.which('xvfb-run')
    tmp = tempfile.mkdtemp(prefix='spindle-view-')
    os.chmod(tmp, 0o755)
    sock = os.path.join(tmp, 'spindle.sock')
    log = open(os.path.join(OUT, 'view-spindled.log'), 'w')
    d = subprocess.Popen([SPINDLED, '-c', '/dev/null', '--device', 'sim', '--profile', 'small', '--renderer', 'cpu',
                          '-s', sock, '--set', 'render-threads=2'], stdout=log, stderr=log)
    shows = []
    failed = []

    def check(cond, what):
        print(('ok   ' if cond else 'FAIL ') + what, flush=True)
        if not cond:
            failed.append(what)

    def show(model):
        for p in shows:
            p.terminate()
            p.wait()
        shows.clear()
        p = subprocess.Popen([CTL, '--socket', sock, 'show', os.path.join(DATA, model)], stdout=subprocess.PIPE,
                             text=True)
        shows.append(p)
        line = p.stdout.readline()
        assert line.startswith('shown'), f'spindlectl show {model}: {line!r}'

    def snapshot(name):
        out = os.path.join(OUT, name)
        if os.path.exists(out):
            os.unlink(out)
        r = run([xvfb, '-a', VIEW, '--socket', sock, '--snapshot', out, '--exit-after', '1', '-g', '320x240'])
        check(r.returncode == 0, f'spindle-view --snapshot {name}: exit {r.returncode} {r.stderr.strip()}')
        return png_rgb(out) if r.returncode == 0 else (0, 0, [])

    try:
        end = time.monotonic() + 20
        while not os.path.exists(sock):
            assert d.poll() is None and time.monotonic() < end, 'spindled did not start'
            time.sleep(0.05)
        time.sleep(0.2)

        # The turntable from a capture file: no daemon, no window needed.
        show('cube.stl')
        svol = os.path.join(OUT, 'view-cube.svol')
        r = run([CTL, '--socket', sock, 'capture', svol])
        check(r.returncode == 0, f'capture: {r.stderr.strip()}')
        sheet = os.path.join(OUT, 'view-turntable.png')
        r = run([VIEW, '--turntable', sheet, '--input', svol, '--frames', '4', '--size', '96'],
                env=dict(os.environ, DISPLAY=''))
        check(r.returncode == 0, f'turntable from a capture: exit {r.returncode} {r.stderr.strip()}')
        if r.returncode == 0:
            w, h, rows = png_rgb(sheet)
            check((w, h) == (192, 192), f'contact sheet 2x2 frames of 96: {w}x{h}')
            check(bright(rows) > 50, f'the turntable shows voxels: {bright(rows)} bright pixels')
        r = run([VIEW, '--turntable', os.path.join(OUT, 'view-turntable-live.png'), '--socket', sock,
                 '--frames', '2', '--size', '64'])
        check(r.returncode == 0, f'turntable of the daemon\'s volume: exit {r.returncode} {r.stderr.strip()}')
        r = run([VIEW, '--turntable', os.path.join(OUT, 'x.png'), '--input', os.path.join(DATA, 'cube.stl')])
        check(r.returncode == 5, f'a file that is no .svol: exit {r.returncode} (5)')

        if not xvfb:
            print('SKIP the window: no xvfb-run')
            return 77 if not failed else 1
        # The window: the scene's voxels, and another picture for another scene.
        w, h, cube = snapshot('view-cube.png')
        check((w, h) == (320, 240), f'snapshot size {w}x{h}')
        check(bright(cube) > 100, f'the window shows the cube\'s voxels: {bright(cube)} bright pixels')
        show('bunny.ply')
        w, h, bunny = snapshot('view-bunny.png')
        check(bright(bunny) > 100, f'the window shows the bunny\'s voxels: {bright(bunny)} bright pixels')
        check(bunny != cube, 'the picture changes with the scene')
        for p in shows:
            p.terminate()
            p.wait()
        shows.clear()
        time.sleep(0.3)
        w, h, empty = snapshot('view-empty.png')
        check(bright(empty) < bright(bunny) / 10, f'nothing lit, nothing bright: {bright(empty)}')

        # Watching follows the capture policy.
        if os.getuid() == 0:
            def drop():
                os.setgroups([])
                os.setresgid(65534, 65534, 65534)
                os.setresuid(65534, 65534, 65534)
            os.chmod(sock, 0o777)
            r = run([VIEW, '--turntable', os.path.join(tmp, 'denied.png'), '--socket', sock], preexec_fn=drop)
            check(r.returncode == 4 and 'refused' in r.stderr, f'nobody is refused: exit {r.returncode} '
                  f'{r.stderr.strip()}')
    finally:
        for p in shows:
            p.terminate()
            p.wait()
        d.terminate()
        rc = d.wait(20)
        log.close()
        check(rc == 0, f'spindled exits 0 ({rc})')
        shutil.rmtree(tmp, ignore_errors=True)
    print(f'{len(failed)} failed' if failed else 'all passed')
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main())
