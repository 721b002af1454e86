#!/usr/bin/env python3
"""spindlectl pattern: each built-in pattern shown through spindled on the
simulated device (small profile) and captured, and what it must light:
every pattern something, in the channels it uses; the axis only the centre
columns; the walls red, green, blue and white at their azimuths; an unknown
name is a usage error (exit 2) naming the patterns.

    test-patterns.py SPINDLED SPINDLECTL WORKDIR
"""
import os
import signal
import socket
import struct
import subprocess
import sys
import time

spindled, ctl, work = sys.argv[1:4]
W = H = 128
IMAGES = 64  # small: 128 images a revolution, mirrored


def fail(what):
    print('FAIL:', what)
    sys.exit(1)


def wait_socket(path, proc):
    for _ in range(1000):
        if proc.poll() is not None:
            fail(f'spindled exited with {proc.returncode}')
        try:
            with socket.socket(socket.AF_UNIX) as s:
                s.connect(path)
                return
        except OSError:
            time.sleep(0.01)
    fail('spindled did not listen')


def lit(data):
    """{(k, u, v, c)} of the lit voxels of a small-profile capture."""
    out = set()
    rb = W // 8
    stride = H * rb
    for k in range(IMAGES):
        for c in range(3):
            base = 64 + (k * 3 + c) * stride
            for i, byte in enumerate(data[base:base + stride]):
                for bit in range(8):
                    if byte & (0x80 >> bit):
                        out.add((k, (i % rb) * 8 + bit, i // rb, c))
    return out


def show(sock, name):
    p = subprocess.Popen([ctl, '--socket', sock, 'pattern', name], stdout=subprocess.PIPE, text=True)
    line = p.stdout.readline()
    if not line.startswith('shown '):
        fail(f'pattern {name}: printed {line!r}')
    path = os.path.join(work, f'pattern-{name}.svol')
    c = subprocess.run([ctl, '--socket', sock, 'capture', path], capture_output=True, text=True, timeout=60)
    if c.returncode != 0:
        fail(f'capture of {name}: {c.stderr}')
    p.send_signal(signal.SIGINT)
    if p.wait(timeout=10) != 0:
        fail(f'pattern {name} exited {p.returncode} on SIGINT')
    with open(path, 'rb') as f:
        data = f.read()
    if struct.unpack('<4sII', data[:4] + data[8:16])[1:] != (W, H):
        fail(f'{name}: not a small-profile capture')
    return lit(data)


def main():
    p = subprocess.run([ctl, 'pattern', 'nope'], capture_output=True, text=True, timeout=10)
    if p.returncode != 2 or 'one of: axis, rings' not in p.stderr:
        fail(f'unknown pattern: exit {p.returncode} {p.stderr!r}')
    sock = os.path.join(work, 'patterns.sock')
    d = subprocess.Popen([spindled, '--device', 'sim', '--profile', 'small', '--renderer', 'cpu', '--socket', sock,
                          '--config', '/dev/null'], stderr=subprocess.DEVNULL)
    try:
        wait_socket(sock, d)
        want_channels = {'axis': {0, 1, 2}, 'rings': {0, 1, 2}, 'grid-cube': {0, 1, 2}, 'colour-bars': {0, 1, 2},
                         'walls': {0, 1, 2}, 'slice-index': {0, 1, 2}}
        for name, channels in want_channels.items():
            voxels = show(sock, name)
            got = {c for (_, _, _, c) in voxels}
            print(f'{name}: {len(voxels)} lit voxels, channels {sorted(got)}')
            if not voxels or got != channels:
                fail(f'{name}: channels {sorted(got)}, expected {sorted(channels)}')
            if name == 'axis' and any(abs(u - W / 2 + 0.5) > 2 for (_, u, _, _) in voxels):
                fail('axis: a lit voxel away from the centre columns')
            if name == 'walls':
                # Image 0 stands at azimuth 0: the red wall (0 degrees) lies in
                # its s > 0 half, the blue one (180) in its s < 0 half.
                colour = {}
                for (k, u, v, c) in voxels:
                    if k == 0:
                        colour[(u, v)] = colour.get((u, v), 0) | (1 << c)
                red = [u for (u, v), bits in colour.items() if bits == 1]
                blue = [u for (u, v), bits in colour.items() if bits == 4]
                if not red or not blue or min(red) < W // 2 - 2 or max(blue) > W // 2 + 1:
                    fail(f'walls: image 0 lights red at columns {min(red, default=None)}.., blue at '
                         f'..{max(blue, default=None)}: expected red right of the axis, blue left')
    finally:
        d.send_signal(signal.SIGTERM)
        d.wait(timeout=10)
    print('ok')


if __name__ == '__main__':
    main()
