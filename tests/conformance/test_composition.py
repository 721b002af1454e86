#!/usr/bin/env python3
"""display.composition (version 4): what the object cache and compositor
did, sent just before status; and the compositor's promise, end to end: a
volume composed from cached layers is the volume the same commits give
with the cache off (key cache = false), capture for capture."""
import math
import struct

from harness import Daemon, MODE, case, check, lit, run, svol_planes, w

CACHE = w.P.enums['display.composition_flags']['cache'][0]
STATIC = [(0.0, -0.6, 0.0), (0.0, 0.6, 0.0), (0.5, 0.0, 0.0), (0.5, 0.4, 0.0),
          (-0.3, -0.2, 0.4), (0.3, 0.5, -0.4)]
MOVING = [(-0.2, -0.2, 0.0), (0.2, 0.2, 0.0), (0.0, 0.2, 0.2), (0.1, -0.3, -0.2), (0.25, 0.0, 0.1), (-0.1, 0.3, 0.2)]


def rot_y(a, t=(0.0, 0.0, 0.0)):
    c, s = math.cos(a), math.sin(a)
    return [c, 0, -s, 0, 0, 1, 0, 0, s, 0, c, 0, t[0], t[1], t[2], 1]


def layer_of(c, verts, colour, mode='lines'):
    buf = c.buffer(w.vertices(verts))
    lst = c.create('create_list')
    layer = c.create('create_layer')
    c.req(lst, 'list.set_color', colour)
    c.req(lst, 'list.draw', MODE[mode], buf, 0, len(verts), 0)
    c.req(layer, 'layer.set_list', lst)
    return layer


def script(d, frames=12):
    """Three static layers of one client; of another, one layer turning and
    moving every frame, one turning by whole images and one moving up and
    down the axis by whole rows; the capture after the last frame, and the
    composition event of a status taken then."""
    a, b = d.conn(), d.conn()
    for i, colour in enumerate((0xffffffff, 0xff8000ff, 0x40c0ffff)):
        layer = layer_of(a, [(x + 0.1 * i, y, z) for x, y, z in STATIC], colour)
        a.req(layer, 'layer.set_transform', rot_y(0.7 * i))
    a.frame_commit()
    mover = layer_of(b, MOVING, 0x00ff80ff, 'triangles')
    # A turntable: turned by whole images every frame (composed from its
    # canvas with the CPU renderer).
    device = next(e for e in b.log if e.name == 'display.device')
    images = device['images_per_rev']
    spinner = layer_of(b, [(x + 0.4, y, z - 0.2) for x, y, z in STATIC], 0xc0c0c0ff)
    # A bobber: moved along the axis by whole rows (lifted: composed from
    # its canvas shifted by rows).
    row = 2 * device['half_height'] / device['height']
    bobber = layer_of(b, [(0.5 * x - 0.3, 0.5 * y, 0.5 * z + 0.1) for x, y, z in STATIC], 0xff40ffff, 'triangles')
    for f in range(frames):
        b.req(mover, 'layer.set_transform', rot_y(0.37 * f, (0.3 * math.cos(f), 0.1, 0.3 * math.sin(f))))
        b.req(spinner, 'layer.set_transform', rot_y(2 * math.pi * 3 * f / images))
        b.req(bobber, 'layer.set_transform', rot_y(0.2, (0.0, row * (f % 7 - 3), 0.0)))
        b.frame_commit()
    cap = svol_planes(b.capture())
    b.req(1, 'display.get_status')
    comp = b.wait('display.composition')
    b.wait('display.status')
    a.close()
    b.close()
    return cap, comp


def on_and_off(*settings):
    """script() on a daemon with the cache and on one without it (both
    with settings): the captures and composition events of each."""
    on, off = Daemon(*settings), Daemon(*settings, 'cache=false')
    try:
        return script(on) + script(off)
    finally:
        on.stop()
        off.stop()


@case
def composition_exact():
    cap_on, comp, cap_off, comp_off = on_and_off()
    check(lit(cap_on) > 0, 'the scene lights voxels')
    check(cap_on == cap_off, 'the composed volume is the volume rendered whole, bit for bit')
    check(comp['flags'] & CACHE, f'cache on: {comp}')
    check(comp['objects'] == 6 and comp['cached'] >= 5,
          f'six layers followed, the static three, the turntable and the bobber cached: {comp}')
    check(comp['hits'] >= 3 * 8, f'the static layers were reused: {comp}')
    check(comp['objects_reused'] >= 5 and comp['objects_rendered'] >= 1, f'the last volume: {comp}')
    check(0 < comp['cache_bytes'] <= comp['cache_budget'], f'within the budget: {comp}')
    check(comp_off['flags'] == 0 and comp_off['hits'] == 0, f'cache off: {comp_off}')
    print(f'  composition: {comp}')


@case
def composition_exact_calibrated():
    """With an axis offset the cache moves each part it renders and keeps
    its entries moved (cache_set_offset()), so that it composes and patches
    moved volumes as it does unmoved ones: what is shown is still the
    volume rendered whole and moved, bit for bit."""
    cap_on, comp, cap_off, _ = on_and_off('axis-offset-u=3', 'axis-offset-v=-2')
    check(lit(cap_on) > 0, 'the scene lights voxels')
    check(cap_on == cap_off, 'calibrated: the composed volume is the volume rendered whole, bit for bit')
    check(comp['hits'] >= 3 * 8 and comp['objects_reused'] >= 5, f'the static layers were reused: {comp}')


@case
def cache_yields_to_clients():
    """The cache holds at most what of memory-budget the clients leave:
    with 2 MiB in all and a client holding 1.5 MiB of buffers, its budget
    is the 0.5 MiB left, and it holds no more."""
    d = Daemon('memory-budget=2097152')
    try:
        a = d.conn()
        buf = a.buffer(struct.pack('<%df' % (3 * 131072), *([0.0] * 3 * 131072)))   # 1.5 MiB of xyz
        for i, colour in enumerate((0xffffffff, 0xff8000ff)):
            layer_of(a, [(x + 0.1 * i, y, z) for x, y, z in STATIC], colour)
        for _ in range(4):
            a.frame_commit()
        a.req(1, 'display.get_status')
        comp = a.wait('display.composition')
        a.wait('display.status')
        left = 2097152 - 131072 * 12
        check(comp['cache_budget'] <= left, f'the budget is what the clients leave ({left}): {comp}')
        check(comp['cache_bytes'] <= comp['cache_budget'], f'held within it: {comp}')
        a.req(buf, 'buffer.destroy')
        a.close()
    finally:
        d.stop()


if __name__ == '__main__':
    run()
