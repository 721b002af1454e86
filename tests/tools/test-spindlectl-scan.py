#!/usr/bin/env python3
"""spindlectl show of scans (docs/volumes.md, "spindlectl show of a scan").

Through spindled on the simulated device (small profile): the Shepp-Logan
phantom of scripts/make-phantom (50x40x32 voxels of 0.8 x 1 x 1.25 mm, a
40 mm cube) as NIfTI-1, .nii.gz and a DICOM series, each shown and
captured. The lit voxels of the default window (ct-soft) lie in the
phantom's skull ellipsoid placed by the fit (its extents along display x,
y, z those of the ellipsoid: left-right 0.69, superior 0.90, anterior 0.92
of the radius); a window on the 40 HU features lights mostly ellipsoid
"e", which lies inferior and anterior: below the centre and towards +z;
the three files give the same capture, bit for bit. Raw files: an RGBA8
volume with a red block on the patient's right, a green one anterior and
a blue one superior (right -> display -x, anterior -> +z, superior -> +y),
and a big-endian int16 "CT" with an offset, air around a block at the
superior end (the default window lights the block only, above the
centre).

Without a daemon: refusals, each exit status 5 with a last line naming the
file: a truncated NIfTI, one whose header claims more slices than it holds
(plain and gzipped), a DICOM slice whose File Meta Information has a
damaged length (GDCM aborts inside the loader: "the scan loader crashed
(signal 6)"), a directory holding two series, a truncated slice, an empty
directory, a raw file shorter than its dims; the loader crashing, lying,
hanging or opening a file (test hooks); usage errors (exit 2).

Usage: test-spindlectl-scan.py SPINDLED SPINDLECTL SPINDLECTL_WITH_HOOKS MAKE_PHANTOM WORK_DIR"""
import math
import os
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time

spindled, ctl, ctl_hooks, make_phantom, work = sys.argv[1:6]
failures = []
FIT_MARGIN = 0.95
# The phantom: voxels along i, j, k and their spacing; i runs to the
# patient's left (display +x), j posterior (display -z), k superior (+y).
DIMS = (50, 40, 32)
SPACING = (0.8, 1.0, 1.25)
HALF = 20.0  # mm: half the cube's edge, and the phantom's unit R
SKULL = (0.69, 0.90, 0.92)  # semi-axes along display x (left), y (superior), z (anterior)
BRAIN = (0.6624, 0.88, 0.874)


def expect(cond, what):
    if not cond:
        failures.append(what)
        print('FAIL:', what)
    return cond


def run(prog, *args, env=None, timeout=60):
    e = dict(os.environ)
    e.pop('SPINDLE_SOCKET', None)
    e.update(env or {})
    p = subprocess.run([prog, *args], capture_output=True, text=True, timeout=timeout, env=e)
    return p.returncode, p.stdout, p.stderr


def wait_socket(path, proc):
    for _ in range(500):
        if proc.poll() is not None:
            raise SystemExit(f'FAIL: spindled exited with {proc.returncode}')
        try:
            with socket.socket(socket.AF_UNIX) as s:
                s.connect(path)
                return
        except OSError:
            time.sleep(0.01)
    raise SystemExit('FAIL: spindled did not listen')


def lit_points(data):
    """Volume-space points of the lit voxels of an .svol, per plane (R, G, B)."""
    w, h, images, n = struct.unpack('<IIII', data[8:24])
    half_height = struct.unpack('<f', data[28:32])[0]
    stride = (w + 7) // 8
    planes = ([], [], [])
    for k in range(images):
        theta = 2 * math.pi * k / n
        c, s_ = math.cos(theta), math.sin(theta)
        for plane in range(3):
            off = 64 + (k * 3 + plane) * h * stride
            block = data[off:off + h * stride]
            for i, byte in enumerate(block):
                if not byte:
                    continue
                v, col = divmod(i, stride)
                y = half_height - (v + 0.5) / h * 2 * half_height
                for bit in range(8):
                    if byte & (0x80 >> bit):
                        s = (col * 8 + bit + 0.5) / w * 2 - 1
                        planes[plane].append((s * c, y, s * s_))
    return planes, half_height


def centroid(points):
    n = len(points)
    return tuple(sum(p[a] for p in points) / n for a in range(3)) if n else (0, 0, 0)


def fit_scale(half, half_height):
    """mm to volume units, as spindlectl fits a box of half extents half (display x, y, z)."""
    return FIT_MARGIN * min(1 / math.hypot(half[0], half[2]), half_height / half[1])


class Daemon:
    def __init__(self, tmp):
        self.sock = os.path.join(tmp, 'spindle.sock')
        self.log = open(os.path.join(work, 'scan-spindled.log'), 'w')
        self.proc = subprocess.Popen([spindled, '--device', 'sim', '--profile', 'small', '--socket', self.sock,
                                      '--config', '/dev/null'], stderr=self.log)
        wait_socket(self.sock, self.proc)

    def show_and_capture(self, name, *args):
        """spindlectl show ARGS until captured; (description line, .svol bytes) or None."""
        show = subprocess.Popen([ctl, '--socket', self.sock, 'show', *args], stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        try:
            desc = show.stdout.readline()
            line = show.stdout.readline()
            if not expect(line.startswith('shown '), f'{name}: show printed {desc!r} {line!r}'):
                show.kill()
                print(show.stderr.read())
                return None
            svol = os.path.join(work, f'scan-{name}.svol')
            rc, out, err = run(ctl, '--socket', self.sock, 'capture', svol)
            expect(rc == 0, f'{name}: capture: {err}')
            show.send_signal(signal.SIGTERM)
            expect(show.wait(timeout=10) == 0, f'{name}: show exited {show.returncode} on SIGTERM')
            with open(svol, 'rb') as f:
                return desc, f.read()
        finally:
            if show.poll() is None:
                show.kill()
                show.wait()

    def stop(self):
        self.proc.send_signal(signal.SIGTERM)
        rc = self.proc.wait(timeout=10)
        self.log.close()
        expect(rc == 0, f'spindled exited {rc}')


# ---- the phantom ----

def make_phantoms(tmp, dicom):
    args = [sys.executable, make_phantom, '--size', ','.join(map(str, DIMS)), '--spacing',
            ','.join(map(str, SPACING)), '--uid', 'a', '--nii', os.path.join(tmp, 'p.nii'), '--nii-gz',
            os.path.join(tmp, 'p.nii.gz')]
    if dicom:
        args += ['--dicom', os.path.join(tmp, 'dicom')]
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL, timeout=120)
    if dicom:
        subprocess.run([sys.executable, make_phantom, '--size', '50,40,2', '--uid', 'b', '--dicom',
                        os.path.join(tmp, 'dicom-b')], check=True, stdout=subprocess.DEVNULL, timeout=120)


def check_head(name, desc, data):
    """The default window: the lit voxels in the skull ellipsoid, filling it."""
    expect('window 40/400 (ct-soft), threshold -160, trilinear sampling' in desc, f'{name}: described as {desc!r}')
    (points, _, _), hh = lit_points(data)
    scale = fit_scale((HALF, HALF, HALF), hh) * HALF  # volume units per phantom unit
    inside = 0
    lo, hi = [1e9] * 3, [-1e9] * 3
    for p in points:
        q = sum((p[a] / (scale * SKULL[a])) ** 2 for a in range(3))
        inside += q <= 1.1 ** 2
        for a in range(3):
            lo[a], hi[a] = min(lo[a], p[a]), max(hi[a], p[a])
    extents = [(hi[a] - lo[a]) / (2 * scale) for a in range(3)]
    print(f'{name}: {len(points)} lit, {inside / max(len(points), 1):.4f} in the skull; half extents in R: '
          + ', '.join(f'{e:.3f}' for e in extents))
    expect(len(points) > 3000 and inside >= 0.99 * len(points), f'{name}: lit voxels outside the skull')
    for a in range(3):
        expect(abs(extents[a] - SKULL[a]) < 0.08, f'{name}: half extent along axis {a}: {extents[a]:.3f} R, '
               f'the skull {SKULL[a]}')


def check_features(name, data):
    """The 40 HU features inside the brain (the skull, 1000, is lit too;
    mostly ellipsoid e, at superior -0.25, anterior +0.35 of R): below the
    centre and towards +z."""
    (points, _, _), hh = lit_points(data)
    scale = fit_scale((HALF, HALF, HALF), hh) * HALF
    brain = [p for p in points if sum((p[a] / (scale * BRAIN[a])) ** 2 for a in range(3)) <= 0.9 ** 2]
    c = [v / scale for v in centroid(brain)]
    print(f'{name}: {len(points)} lit, {len(brain)} inside the brain, their centroid in R: '
          f'{c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f}')
    expect(len(brain) > 100, f'{name}: too few lit voxels')
    expect(abs(c[0]) < 0.08 and -0.35 < c[1] < -0.12 and 0.22 < c[2] < 0.45,
           f'{name}: centroid {c}, want about (0, -0.25, 0.35): superior up, anterior +z')


def check_phantom(d, tmp, dicom):
    first = None
    for name in ['p.nii', 'p.nii.gz'] + (['dicom'] if dicom else []):
        got = d.show_and_capture(name.replace('.', '-'), os.path.join(tmp, name))
        if not got:
            continue
        desc, data = got
        check_head(name, desc, data)
        if first is None:
            first = data
        else:
            expect(data[64:] == first[64:], f'{name}: a capture other than p.nii\'s')
    got = d.show_and_capture('features', os.path.join(tmp, 'p.nii'), '--window', '40/20', '--threshold', '35',
                             '--sampling', 'nearest')
    if got:
        expect('window 40/20 (--window), threshold 35, nearest sampling' in got[0], f'described as {got[0]!r}')
        check_features('p.nii, window 40/20', got[1])


# ---- raw files ----

def write_rgba(path):
    """16 x 12 x 8 RGBA8 voxels (i right, j anterior, k superior: a raw
    file's spacing diagonal), after a 16-byte header to skip: a red block
    at the right end, green at the anterior end, blue at the superior end."""
    nx, ny, nz = 16, 12, 8
    vox = bytearray(nx * ny * nz * 4)
    def block(i0, i1, j0, j1, k0, k1, rgba):
        for k in range(k0, k1):
            for j in range(j0, j1):
                for i in range(i0, i1):
                    o = ((k * ny + j) * nx + i) * 4
                    vox[o:o + 4] = bytes(rgba)
    block(12, 16, 4, 8, 2, 6, (255, 0, 0, 255))
    block(6, 10, 9, 12, 2, 6, (0, 255, 0, 255))
    block(6, 10, 4, 8, 6, 8, (0, 0, 255, 255))
    with open(path, 'wb') as f:
        f.write(b'header: skip me!' + vox)


def check_rgba(d, tmp):
    path = os.path.join(tmp, 'blocks.rgba')
    write_rgba(path)
    got = d.show_and_capture('rgba', path, '--dims', '16x12x8', '--type', 'rgba8', '--spacing', '1', '--offset',
                             '16', '--sampling', 'nearest')
    if not got:
        return
    expect('raw 16x12x8 RGBA8' in got[0] and 'its own colours' in got[0], f'rgba: described as {got[0]!r}')
    (red, green, blue), hh = lit_points(got[1])
    scale = fit_scale((8, 4, 6), hh)  # display x = 16 i, y = 8 k, z = 12 j (mm, halved)
    r, g, b = ([v / scale for v in centroid(p)] for p in (red, green, blue))
    print(f'rgba: lit {len(red)} red, {len(green)} green, {len(blue)} blue; centroids in mm: '
          f'red {r[0]:.2f} {r[1]:.2f} {r[2]:.2f}, green {g[0]:.2f} {g[1]:.2f} {g[2]:.2f}, '
          f'blue {b[0]:.2f} {b[1]:.2f} {b[2]:.2f}')
    expect(min(len(red), len(green), len(blue)) > 50, 'rgba: a block not shown')
    expect(abs(r[0] + 6) < 1 and abs(r[1]) < 1 and abs(r[2]) < 1, f'rgba: red (right) at {r}, want x -6')
    expect(abs(g[2] - 4.5) < 1 and abs(g[0]) < 1 and abs(g[1]) < 1, f'rgba: green (anterior) at {g}, want z 4.5')
    expect(abs(b[1] - 3) < 1 and abs(b[0]) < 1 and abs(b[2]) < 1, f'rgba: blue (superior) at {b}, want y 3')


def check_big_endian(d, tmp):
    """8x8x8 int16 big-endian after 100 bytes: -1000 (air) but for 500 in
    the top two slices (superior)."""
    path = os.path.join(tmp, 'ct.be')
    with open(path, 'wb') as f:
        f.write(bytes(100))
        for k in range(8):
            f.write(struct.pack('>64h', *([500 if k >= 6 else -1000] * 64)))
    got = d.show_and_capture('big-endian', path, '--dims', '8x8x8', '--type', 'int16', '--spacing', '2,2,2',
                             '--offset', '100', '--big-endian')
    if not got:
        return
    expect('big-endian' in got[0] and 'window 40/400 (ct-soft)' in got[0], f'big-endian: described as {got[0]!r}')
    (points, _, _), hh = lit_points(got[1])
    scale = fit_scale((8, 8, 8), hh)
    c = [v / scale for v in centroid(points)]
    low = sum(1 for p in points if p[1] < 0)
    print(f'big-endian: {len(points)} lit, {low} below the centre; centroid in mm {c[0]:.2f} {c[1]:.2f} {c[2]:.2f}')
    expect(len(points) > 200 and low == 0 and abs(c[1] - 6) < 1, 'big-endian: the block at the top, nothing else')


# ---- refusals ----

def expect_refused(path, needle, *args, prog=None, env=None, last=None):
    nosock = os.path.join(work, 'scan-no-daemon.sock')
    rc, out, err = run(prog or ctl, '--socket', nosock, 'show', path, *args, env=env)
    lines = err.splitlines()
    print(f'{os.path.basename(path)} {" ".join(args)}: exit {rc}: {lines[-1] if lines else ""}')
    expect(rc == 5, f'{path}: exit status 5, got {rc}: {err!r}')
    expect(lines and lines[-1].startswith(f'spindlectl: {path}'), f'{path}: a last line naming it: {err!r}')
    expect(needle in err, f'{path}: {needle!r} in {err!r}')
    if last:
        expect(lines and lines[-1] == last, f'{path}: last line {lines[-1] if lines else None!r}, want {last!r}')


def damage_meta(src, dst):
    """A copy of a DICOM file whose File Meta Information Version (0002,0001,
    OB) claims 256 MiB: GDCM asserts on it."""
    with open(src, 'rb') as f:
        data = bytearray(f.read())
    at = data.find(b'\x02\x00\x01\x00OB\x00\x00')
    if not expect(at > 0, f'{src}: no (0002,0001) OB element'):
        return
    data[at + 8:at + 12] = struct.pack('<I', 0x10000000)
    with open(dst, 'wb') as f:
        f.write(data)


def check_refusals(tmp, dicom):
    with open(os.path.join(tmp, 'p.nii'), 'rb') as f:
        nii = f.read()
    path = os.path.join(tmp, 'truncated.nii')
    with open(path, 'wb') as f:
        f.write(nii[:len(nii) // 2])
    expect_refused(path, 'its header says')
    lying = bytearray(nii)
    lying[46:48] = struct.pack('<h', 64)  # dim[3]: 64 slices, the file holds 32
    path = os.path.join(tmp, 'lying.nii')
    with open(path, 'wb') as f:
        f.write(lying)
    expect_refused(path, 'its header says')
    import gzip
    path = os.path.join(tmp, 'lying.nii.gz')
    with gzip.open(path, 'wb') as f:
        f.write(lying)
    expect_refused(path, '(truncated, or the header lies)')

    path = os.path.join(tmp, 'short.raw')
    with open(path, 'wb') as f:
        f.write(bytes(1000))
    expect_refused(path, 'holds 1000 bytes', '--dims', '10x10x10', '--type', 'uint16', '--spacing', '1,1,1')
    empty = os.path.join(tmp, 'empty')
    os.mkdir(empty)
    with open(os.path.join(empty, '.hidden'), 'w') as f:
        f.write('not a slice')
    expect_refused(empty, 'no DICOM images')

    if dicom:
        src = os.path.join(tmp, 'dicom')
        names = sorted(os.listdir(src))
        crash = os.path.join(tmp, 'crash')
        shutil.copytree(src, crash)
        damage_meta(os.path.join(src, names[5]), os.path.join(crash, names[5]))
        expect_refused(crash, 'crashed', last=f'spindlectl: {crash}: the scan loader crashed (signal 6)')
        mixed = os.path.join(tmp, 'mixed')
        shutil.copytree(src, mixed)
        shutil.copy(os.path.join(tmp, 'dicom-b', 'IM0000'), os.path.join(mixed, 'ZZ-other-series'))
        expect_refused(mixed, 'holds more than one series')
        cut = os.path.join(tmp, 'cut-slice')
        shutil.copytree(src, cut)
        with open(os.path.join(cut, names[3]), 'r+b') as f:
            f.truncate(2000)
        expect_refused(cut, 'truncated')

    # The loader misbehaving (the tests' build of spindlectl).
    nii_path = os.path.join(tmp, 'p.nii')
    for hook, needle in (('segv', 'the scan loader crashed (signal 11)'),
                         ('abort', 'the scan loader crashed (signal 6)'),
                         ('garbage', 'the scan loader sent a malformed result (bad magic 0xabababab)'),
                         ('scan-huge', 'malformed result (header: 4096x4096x4096 voxels: over 2^31 in all)'),
                         ('scan-singular', 'malformed result (header: the voxel to patient transform'),
                         ('scan-size', 'malformed result (7 bytes of samples for 2x2x2 uint8)'),
                         ('scan-short', 'malformed result (cut short)'),
                         ('scan-extra', 'malformed result (more bytes than it announced)'),
                         ('open', 'test hook open: Operation not permitted'),
                         ('socket', 'test hook socket: Operation not permitted'),
                         ('exec', 'test hook exec: Operation not permitted')):
        expect_refused(nii_path, needle, prog=ctl_hooks, env={'SPINDLE_MODEL_TEST_HOOK': hook})
    expect_refused(nii_path, 'the scan loader took longer than 1 s', prog=ctl_hooks,
                   env={'SPINDLE_MODEL_TEST_HOOK': 'hang', 'SPINDLE_MODEL_TEST_TIMEOUT_MS': '1000'})
    if dicom:  # every file of a directory readable, nothing else
        expect_refused(os.path.join(tmp, 'dicom'), 'test hook open: Operation not permitted', prog=ctl_hooks,
                       env={'SPINDLE_MODEL_TEST_HOOK': 'open'})


def check_usage(tmp):
    nii = os.path.join(tmp, 'p.nii')
    nosock = os.path.join(work, 'scan-no-daemon.sock')
    for args, needle in ((['show', nii, '--window', '40'], 'bad window'),
                         (['show', nii, '--window', '40/0'], 'bad window'),
                         (['show', nii, '--preset', 'ct-brain'], "unknown preset 'ct-brain'"),
                         (['show', nii, '--sampling', 'cubic'], 'bad sampling'),
                         (['show', nii, '--threshold', 'x'], 'bad threshold'),
                         (['show', nii, '--no-fit'], '--no-fit goes with models'),
                         (['show', nii, '--preset', 'mri', '--window', '1/2'], 'give one'),
                         (['show', nii, '--dims', '2x2'], 'bad dims'),
                         (['show', nii, '--dims', '2x2x2'], 'needs --dims, --type and --spacing'),
                         (['show', nii, '--dims', '2x2x2', '--type', 'int8', '--spacing', '1'], 'bad type'),
                         (['show', nii, '--dims', '2x2x2', '--type', 'uint8', '--spacing', '1,0,1'], 'bad spacing'),
                         (['show', 'model.stl', '--window', '1/2'], 'go with a scan'),
                         (['status', '--preset', 'mri'], "go with 'show'")):
        rc, out, err = run(ctl, '--socket', nosock, *args)
        expect(rc == 2 and needle in err, f'{args}: exit {rc} (want 2), {err!r} (want {needle!r})')
    # A negative value after an option is its value, not an operand.
    rc, out, err = run(ctl, '--socket', nosock, 'show', nii, '--threshold', '-500', '--preset', 'ct-lung')
    expect(rc == 3 and 'window -600/1500 (ct-lung), threshold -500' in out, f'--threshold -500: {rc} {out!r}')
    rc, out, err = run(ctl, '--socket', nosock, 'show', nii, '--preset', 'ct-lung')
    expect(rc == 3 and 'threshold -950' in out, f'ct-lung keeps air dark: {out!r}')
    rc, out, err = run(ctl, '--socket', nosock, 'show', nii, '--preset', 'mri')
    expect(rc == 3 and 'window ' in out and '(mri' in out, f'mri preset: {out!r}')


def check_quota(tmp):
    """A scan over the daemon's max-buffer-bytes: its quota error, exit 4."""
    sock = os.path.join(tmp, 'small-quota.sock')
    proc = subprocess.Popen([spindled, '--device', 'sim', '--profile', 'small', '--socket', sock, '--config',
                             '/dev/null', '--set', 'max-buffer-bytes=200000'], stderr=subprocess.DEVNULL)
    try:
        wait_socket(sock, proc)
        rc, out, err = run(ctl, '--socket', sock, 'show', os.path.join(tmp, 'p.nii'))
        print(f'over max-buffer-bytes: exit {rc}: {err.strip()}')
        expect(rc == 4 and "the daemon refused the scan's 128000 bytes of samples" in err,
               f'over max-buffer-bytes: exit {rc} (want 4): {err!r}')
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=10)


def main():
    dicom = shutil.which('dump2dcm') is not None
    if not dicom:
        print("SKIP (the DICOM parts): dcmtk's dump2dcm is not installed (scripts/install-deps)")
    tmp = tempfile.mkdtemp(prefix='scan-show-', dir=work)
    try:
        make_phantoms(tmp, dicom)
        check_usage(tmp)
        check_refusals(tmp, dicom)
        d = Daemon(tmp)
        try:
            check_phantom(d, tmp, dicom)
            check_rgba(d, tmp)
            check_big_endian(d, tmp)
        finally:
            d.stop()
        check_quota(tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print('failures:', len(failures))
    sys.exit(1 if failures else 0)


main()
