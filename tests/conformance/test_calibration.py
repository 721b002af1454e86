#!/usr/bin/env python3
"""Calibration (protocol 6, display.calibrate): get_status sends the
calibration in use before status; calibrate answers with it; a value out of
range is refused out_of_range and one from a client other than root or the
daemon's user refused denied, nothing changing and the connection going on;
an unknown key is invalid_value. The axis offset moves every image of the
volume shown by whole pixels, bit for bit; back at 0 the volume is the one
before."""
import math

from harness import ERR, NOBODY, P, MODE, case, check, connect_as, run, shared, svol_header, svol_planes, lit, w

KEY = {n: v for n, (v, _) in P.enums['display.calibration_key'].items()}
REFUSAL = {n: v for n, (v, _) in P.enums['display.refusal'].items()}
IDENTITY = dict(phase_offset=0.0, axis_offset_u=0, axis_offset_v=0, vertical_scale=1.0, vertical_offset=0.0)


def calibration(c):
    c.req(1, 'display.get_status')
    ev = c.wait('display.calibration')
    c.wait('display.status')
    return {k: ev[k] for k in IDENTITY}


def calibrate(c, key, value):
    """Sends calibrate; returns (the refused event or None, the calibration
    answered)."""
    c.req(1, 'display.calibrate', KEY[key], value)
    ev = c.wait(lambda e: e.name in ('display.refused', 'display.calibration'), what='calibrate answer')
    refused = None
    if ev.name == 'display.refused':
        refused = ev
        ev = c.wait('display.calibration')
    return refused, {k: ev[k] for k in IDENTITY}


def scene(c):
    """Lines and points over much of the volume, white."""
    pts = [(-0.8, -0.7, 0.1), (0.7, 0.8, -0.2), (0.2, -0.9, 0.6), (-0.3, 0.9, -0.6), (0.0, 0.5, 0.0),
           (0.9, 0.0, 0.0)]
    buf = c.create('create_buffer_inline', w.vertices(pts))
    lst = c.create('create_list')
    layer = c.create('create_layer')
    c.req(lst, 'list.set_color', 0xffffffff)
    c.req(lst, 'list.draw', MODE['lines'], buf, 0, 4, 0)
    c.req(lst, 'list.draw', MODE['points'], buf, 4, 2, 0)
    c.req(layer, 'layer.set_list', lst)
    c.frame_commit()


def shifted(planes, hdr, du, dv):
    """The dense planes of every image moved by du columns and dv rows."""
    W, H, n = hdr['W'], hdr['H'], hdr['images']
    rb = (W + 7) // 8
    out = bytearray(len(planes))
    for p in range(n * 3):
        base = p * H * rb
        for y in range(H):
            sy = y - dv
            if not 0 <= sy < H:
                continue
            for x in range(W):
                sx = x - du
                if 0 <= sx < W and planes[base + sy * rb + sx // 8] >> (7 - sx % 8) & 1:
                    out[base + y * rb + x // 8] |= 0x80 >> (x % 8)
    return bytes(out)


def shown_after_change(c):
    """The first volume shown with the calibration just set (a frame after
    it names it), captured."""
    c.frame_commit()
    return c.capture()


@case
def reported():
    """get_status sends calibration (after watchers, before status); the
    daemon starts with its config's values."""
    d, wit = shared('axis-offset-u=2')
    c = d.conn()
    check(c.version >= 6, f'version {c.version}')
    c.req(1, 'display.get_status')
    names = []
    while not names or names[-1] != 'display.status':
        names.append(c.wait(lambda e: e.name.startswith('display.'), what='status events').name)
    check(names[-3:] == ['display.watchers', 'display.calibration', 'display.status'], f'order {names}')
    check(calibration(c) == dict(IDENTITY, axis_offset_u=2), f'{calibration(c)}')
    c.close()
    wit.check(exact=False)


@case
def set_and_refused():
    """calibrate answers with the new calibration; out of range (a quarter
    of the 128-pixel image is 32; phase beyond 180; a fraction of a pixel;
    NaN) is refused out_of_range and changes nothing; the connection goes
    on."""
    d, wit = shared('axis-offset-u=2')
    c = d.conn()
    refused, cal = calibrate(c, 'phase_offset', 12.5)
    check(refused is None and cal == dict(IDENTITY, axis_offset_u=2, phase_offset=12.5), f'{refused} {cal}')
    for key, value in (('axis_offset_u', 33.0), ('axis_offset_v', -33.0), ('axis_offset_u', 2.5),
                       ('phase_offset', 180.5), ('vertical_scale', 2.5), ('vertical_scale', math.nan),
                       ('vertical_offset', 0.6)):
        refused, cal = calibrate(c, key, value)
        check(refused is not None and refused['code'] == REFUSAL['out_of_range'] and refused['object'] == 1,
              f'{key} {value}: {refused}')
        check(cal == dict(IDENTITY, axis_offset_u=2, phase_offset=12.5), f'{key} {value}: unchanged, {cal}')
    refused, cal = calibrate(c, 'axis_offset_v', -32.0)
    check(refused is None and cal['axis_offset_v'] == -32, f'{refused} {cal}')
    for key, value in (('phase_offset', 0.0), ('axis_offset_v', 0.0)):
        calibrate(c, key, value)
    c.sync()
    check(not c.errors(), f'{c.errors()}')
    c.close()
    wit.check(exact=False)


@case
def unknown_key():
    """A key past the enum is invalid_value."""
    d, wit = shared('axis-offset-u=2')
    c = d.conn()
    c.req(1, 'display.calibrate', len(KEY), 1.0)
    c.expect_fatal(ERR['invalid_value'], 1)
    wit.check(exact=False)


@case
def denied_unprivileged():
    """uid 65534 gets refused denied: nothing changes, it stays connected."""
    d, wit = shared('axis-offset-u=2')
    c, = connect_as(NOBODY, d.sock, 1)
    c.hello()
    refused, cal = calibrate(c, 'axis_offset_u', 5.0)
    check(refused is not None and refused['code'] == REFUSAL['denied'], f'{refused}')
    check(cal == dict(IDENTITY, axis_offset_u=2), f'unchanged: {cal}')
    c.sync()
    check(not c.errors() and not c.eof, 'still connected')
    c.close()
    wit.check(exact=False)


@case
def offset_shifts_volume():
    """The volume shown at offset (u, v) is the one at (0, 0) moved by u
    columns and v rows, bit for bit, what leaves the image dropped; back at
    (0, 0) it is the same volume again."""
    d, wit = shared()
    c = d.conn()
    scene(c)
    before = c.capture()
    hdr = svol_header(before)
    base = svol_planes(before)
    check(lit(base) > 100, 'the scene lights voxels')
    for du, dv in ((5, -3), (-31, 17), (0, 32)):
        calibrate(c, 'axis_offset_u', float(du))
        calibrate(c, 'axis_offset_v', float(dv))
        got = svol_planes(shown_after_change(c))
        check(got == shifted(base, hdr, du, dv), f'offset ({du}, {dv}): the volume moved by it')
    calibrate(c, 'axis_offset_u', 0.0)
    calibrate(c, 'axis_offset_v', 0.0)
    check(svol_planes(shown_after_change(c)) == base, 'back at (0, 0): the volume as before')
    c.close()
    wit.check(exact=False)


if __name__ == '__main__':
    run()
