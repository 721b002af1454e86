#!/usr/bin/env python3
"""spindlectl's command line without a daemon: help, version, usage errors,
missing files, a socket nobody listens on, and preview of a small .svol
written here. Usage: test-spindlectl-cli.py SPINDLECTL DATA_DIR WORK_DIR"""
import os
import struct
import subprocess
import sys
import zlib

ctl, data_dir, work = sys.argv[1:4]
failures = []


def run(*args, env=None):
    e = dict(os.environ)
    e.pop('SPINDLE_SOCKET', None)
    e.update(env or {})
    p = subprocess.run([ctl, *args], capture_output=True, text=True, timeout=30, env=e)
    return p.returncode, p.stdout, p.stderr


def expect(cond, what):
    if not cond:
        failures.append(what)
        print('FAIL:', what)


# Exit statuses (spindlectl(1)): 2 usage, 3 no daemon, 5 a bad input file.
USAGE, CONNECT, INPUT = 2, 3, 5


def expect_error(args, needle, status, env=None):
    rc, out, err = run(*args, env=env)
    expect(rc == status, f'{args}: exit {status}, got {rc}')
    expect(needle in err, f'{args}: stderr has {needle!r}: {err!r}')


def write_svol(path, w=32, h=32, n=8):
    """A mirrored volume of n/2 images with the centre row of each lit."""
    images = n // 2
    hdr = b'SVOL' + struct.pack('<HHIIIIBBHfQQ16x', 1, 64, w, h, images, n, 3, 1, 0, 1.0, 7, 0)
    rb = (w + 7) // 8
    plane = bytearray(h * rb)
    plane[(h // 2) * rb:(h // 2 + 1) * rb] = b'\xff' * rb
    with open(path, 'wb') as f:
        f.write(hdr + bytes(plane) * 3 * images)


def png_size(path):
    with open(path, 'rb') as f:
        data = f.read()
    expect(data[:8] == b'\x89PNG\r\n\x1a\n', 'png signature')
    length, kind = struct.unpack('>I4s', data[8:16])
    expect(kind == b'IHDR' and zlib.crc32(data[12:16 + length]) ==
           struct.unpack('>I', data[16 + length:20 + length])[0], 'png IHDR')
    return struct.unpack('>II', data[16:24])


rc, out, _ = run('--help')
expect(rc == 0 and 'usage: spindlectl' in out, '--help')
rc, out, _ = run('--version')
expect(rc == 0 and out.startswith('spindlectl '), '--version')

expect_error([], 'no command', USAGE)
expect_error(['frobnicate'], "unknown command 'frobnicate'", USAGE)
expect_error(['status', 'extra'], 'wrong number of arguments', USAGE)
expect_error(['--bogus', 'status'], '--help', USAGE)
expect_error(['show', 'x.stl', '--color', 'red'], 'bad colour', USAGE)
expect_error(['status', '--no-fit'], "go with 'show'", USAGE)
expect_error(['preview', 'a', 'b', '--size', '3'], 'bad size', USAGE)
expect_error(['show', os.path.join(work, 'missing.stl')], 'No such file', INPUT)
expect_error(['preview', os.path.join(work, 'missing.svol'), 'x.png'], 'No such file', INPUT)
expect_error(['preview', os.path.join(data_dir, 'cube.stl'), 'x.png'], 'not a valid .svol', INPUT)

nosock = os.path.join(work, 'no-daemon.sock')
expect_error(['--socket', nosock, 'status'], 'cannot connect to spindled at ' + nosock, CONNECT)
expect_error(['status'], 'cannot connect to spindled at ' + nosock, CONNECT, env={'SPINDLE_SOCKET': nosock})
expect_error(['--socket', nosock, 'show', os.path.join(data_dir, 'cube.stl')],
             'cannot connect to spindled', CONNECT)
expect_error(['--socket', nosock, 'capture', os.path.join(work, 'c.svol')],
             'cannot connect to spindled', CONNECT)
expect_error(['capture', 'c.svol', '--json'], "--json goes with 'status'", USAGE)

svol = os.path.join(work, 'cli-tiny.svol')
png = os.path.join(work, 'cli-tiny.png')
write_svol(svol)
rc, _, err = run('preview', svol, png, '--size', '100')
expect(rc == 0, f'preview: {err}')
if rc == 0:
    expect(png_size(png) == (100, 100), 'preview size')
rc, _, err = run('preview', svol, png)
expect(rc == 0 and png_size(png) == (640, 640), 'preview default size')

print('failures:', len(failures))
sys.exit(1 if failures else 0)
