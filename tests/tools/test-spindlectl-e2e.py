#!/usr/bin/env python3
"""The demo path end to end: spindled on the simulated device (small profile),
spindlectl show (the Stanford bunny), status, capture, preview; the model
stays shown until SIGTERM, and both programs exit cleanly. Then a model with
colours of its own (a PLY with red and blue vertices) shown without
--color: the capture lights red and blue, never green.
Usage: test-spindlectl-e2e.py SPINDLED SPINDLECTL DATA_DIR WORK_DIR"""
import json
import os
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time

spindled, ctl, data_dir, work = sys.argv[1:5]


def fail(what):
    print('FAIL:', what)
    sys.exit(1)


def wait_socket(path, proc):
    for _ in range(500):
        if proc.poll() is not None:
            fail(f'spindled exited with {proc.returncode}')
        try:
            with socket.socket(socket.AF_UNIX) as s:
                s.connect(path)
                return
        except OSError:
            time.sleep(0.01)
    fail('spindled did not listen')


def ctl_run(sock, *args):
    p = subprocess.run([ctl, '--socket', sock, *args], capture_output=True, text=True, timeout=60)
    if p.returncode != 0:
        fail(f'spindlectl {" ".join(args)}: exit {p.returncode}: {p.stderr}')
    return p.stdout


def lit_planes(data, w=128, h=128, images=64):
    planes = [0, 0, 0]
    stride = h * (w // 8)
    for k in range(images):
        for c in range(3):
            off = 64 + (k * 3 + c) * stride
            planes[c] += sum(bin(b).count('1') for b in data[off:off + stride])
    return planes


def colored_cube(path):
    """A cube, its -x vertices red, its +x vertices blue."""
    verts = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    with open(path, 'w') as f:
        f.write('ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n'
                'property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n'
                'element face 6\nproperty list uchar int vertex_indices\nend_header\n')
        for x, y, z in verts:
            f.write(f'{x} {y} {z} ' + ('255 0 0' if x < 0 else '0 0 255') + '\n')
        for q in quads:
            f.write('4 ' + ' '.join(map(str, q)) + '\n')


def show_colored(sock):
    ply = os.path.join(work, 'e2e-colored.ply')
    colored_cube(ply)
    show = subprocess.Popen([ctl, '--socket', sock, 'show', ply], stdout=subprocess.PIPE, text=True)
    try:
        line = show.stdout.readline()
        if not line.startswith('shown '):
            fail(f'show of a coloured model printed {line!r}')
        svol = os.path.join(work, 'e2e-colored.svol')
        ctl_run(sock, 'capture', svol)
        with open(svol, 'rb') as f:
            planes = lit_planes(f.read())
        print('coloured model: lit voxels per plane (R, G, B)', planes)
        if not (planes[0] > 500 and planes[2] > 500 and planes[1] == 0):
            fail(f'coloured model: lit voxels per plane {planes}, want red and blue only')
        show.send_signal(signal.SIGTERM)
        if show.wait(timeout=10) != 0:
            fail(f'show exited {show.returncode} on SIGTERM')
    finally:
        if show.poll() is None:
            show.kill()


def calibrate(sock, tmp):
    """calibrate sets a key live, --save writes it into the config file
    (keeping every other line), a daemon started on that file has it, and
    a value out of range for the display is refused (exit 4)."""
    conf = os.path.join(tmp, 'spindled.conf')
    with open(conf, 'w') as f:
        f.write('# kept\nprofile = small\naxis-offset-u = 9  # old value\n')
    out = ctl_run(sock, 'calibrate', 'axis-offset-u', '-3', '--save', '--config', conf)
    if 'axis-offset-u -3 px' not in out or f'saved axis-offset-u = -3 in {conf}' not in out:
        fail(f'calibrate printed {out!r}')
    with open(conf) as f:
        text = f.read()
    if text != '# kept\nprofile = small\naxis-offset-u = -3 # old value\n':
        fail(f'saved config {text!r}')
    ctl_run(sock, 'calibrate', 'phase-offset', '2.5')
    js = json.loads(ctl_run(sock, 'status', '--json'))
    if js['calibration'] != {'phase_offset': 2.5, 'axis_offset_u': -3, 'axis_offset_v': 0, 'vertical_scale': 1,
            'vertical_offset': 0}:
        fail(f'status --json calibration {js["calibration"]!r}')
    p = subprocess.run([ctl, '--socket', sock, 'calibrate', 'axis-offset-v', '33'], capture_output=True,
                       text=True, timeout=60)
    if p.returncode != 4 or 'out of range' not in p.stderr:
        fail(f'axis-offset-v 33 at 128x128: exit {p.returncode}: {p.stderr!r}')
    sock2 = os.path.join(tmp, 'saved.sock')
    d2 = subprocess.Popen([spindled, '--device', 'sim', '--socket', sock2, '--config', conf],
                          stderr=subprocess.DEVNULL)
    try:
        wait_socket(sock2, d2)
        out = ctl_run(sock2, 'calibrate')
        if 'axis-offset-u -3 px' not in out or 'phase-offset 0 deg' not in out:
            fail(f'daemon on the saved config: {out!r}')
    finally:
        d2.send_signal(signal.SIGTERM)
        d2.wait(timeout=10)


def main():
    tmp = tempfile.mkdtemp(prefix='spindle-e2e-')
    sock = os.path.join(tmp, 'spindle.sock')
    log = open(os.path.join(work, 'e2e-spindled.log'), 'w')
    daemon = subprocess.Popen([spindled, '--device', 'sim', '--profile', 'small', '--socket', sock,
                               '--config', '/dev/null'], stderr=log)
    show = None
    try:
        wait_socket(sock, daemon)
        show = subprocess.Popen([ctl, '--socket', sock, 'show', os.path.join(data_dir, 'bunny.ply'),
                                 '--color', 'ffcc00'], stdout=subprocess.PIPE, text=True)
        line = show.stdout.readline()
        if not line.startswith('shown ') or int(line.split()[1]) < 1:
            fail(f'show printed {line!r}')

        status = dict(l.split(': ', 1) for l in ctl_run(sock, 'status').splitlines() if ': ' in l)
        for key, want in (('width', '128'), ('images per revolution', '128'), ('mirrored', 'yes'),
                          ('clients', '2'), ('projector present', 'yes')):
            if status.get(key) != want:
                fail(f'status {key}: {status.get(key)!r}, expected {want!r}')
        if int(status['volumes shown']) < 1:
            fail('no volume shown')
        js = json.loads(ctl_run(sock, 'status', '--json'))  # one JSON object, the same figures
        if (js['device']['width'], js['device']['mirrored'], js['display']['clients'], js['protocol']) != \
                (128, True, 2, 6) or js['display']['volumes_shown'] < 1 or 'composition' not in js or \
                js.get('watchers', {}).get('max_watchers') != 4 or \
                js.get('calibration') != {'phase_offset': 0, 'axis_offset_u': 0, 'axis_offset_v': 0,
                                          'vertical_scale': 1, 'vertical_offset': 0}:
            fail(f'status --json: {js!r}')

        svol = os.path.join(work, 'e2e-bunny.svol')
        ctl_run(sock, 'capture', svol)
        with open(svol, 'rb') as f:
            data = f.read()
        magic, version, hsize, w, h, images, n = struct.unpack('<4sHHIIII', data[:24])
        if (magic, w, h, images, n) != (b'SVOL', 128, 128, 64, 128):
            fail(f'capture header {(magic, w, h, images, n)}')
        if len(data) != 64 + images * 3 * h * (w // 8):
            fail('capture size')
        # Yellow (ffcc00): red and green planes lit, blue dark.
        planes = lit_planes(data, w, h, images)
        if not (planes[0] > 1000 and planes[1] > 500 and planes[2] == 0):
            fail(f'lit voxels per plane {planes}')

        png = os.path.join(work, 'e2e-bunny.png')
        subprocess.run([ctl, 'preview', svol, png], check=True, timeout=60)
        with open(png, 'rb') as f:
            if f.read(8) != b'\x89PNG\r\n\x1a\n':
                fail('preview is not a PNG')

        show.send_signal(signal.SIGTERM)
        if show.wait(timeout=10) != 0:
            fail(f'show exited {show.returncode} on SIGTERM')
        show = None
        show_colored(sock)
        calibrate(sock, tmp)
    finally:
        if show:
            show.kill()
        daemon.send_signal(signal.SIGTERM)
        rc = daemon.wait(timeout=10)
        log.close()
    if rc != 0:
        fail(f'spindled exited {rc}')
    if os.path.exists(sock):
        fail('socket left behind')
    print('1 passed, 0 failed')


main()
