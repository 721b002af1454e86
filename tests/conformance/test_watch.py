#!/usr/bin/env python3
"""Watchers (protocol 5, display.watch): the volumes shown, sparse, in the
watch volume layout of docs/formats.md, the same bits a capture of the same
volume gives; at most one in flight (nothing more until release; volumes
shown meanwhile skipped and counted); at most the watcher's and the daemon's
rate; max-watchers refused and capture's policy denied with watcher.failed,
the connection going on; all of it counted in the watchers event."""
import math
import os
import struct
import time

from harness import (ERR, NOBODY, P, MODE, case, check, connect_as, run, shared, svol_header, svol_planes, lit, w)

FAILURE = {n: v for n, (v, _) in P.enums['watcher.failure'].items()}
SETTINGS = ('max-watch-rate=8', 'max-watchers=2')


def wvol_dense(data):
    """A watch volume as (header dict, the dense planes of every image, as
    .svol stores them)."""
    check(data[:4] == b'SPWV' and data[4] == 1 and data[6] == 64 and data[24] == 3, f'wvol magic {data[:8]!r}')
    W, H, n, N = struct.unpack_from('<IIII', data, 8)
    seq, t = struct.unpack_from('<QQ', data, 32)
    tx, ty, mask_bytes, total = struct.unpack_from('<IIII', data, 48)
    check(tx == (W + 31) // 32 and ty == (H + 31) // 32 and mask_bytes == (tx * ty + 7) // 8, 'wvol tiles')
    rowbytes = (W + 7) // 8
    out = bytearray(n * 3 * H * rowbytes)
    p = 64
    pad = (mask_bytes + 3) & ~3
    tiles = 0
    for k in range(n):
        count, = struct.unpack_from('<I', data, p)
        mask = data[p + 4:p + 4 + mask_bytes]
        p += 4 + pad
        stored = [t for t in range(tx * ty) if mask[t // 8] >> (t % 8) & 1]
        check(len(stored) == count, f'image {k}: mask has {len(stored)} tiles, count {count}')
        base = k * 3 * H * rowbytes
        for t in stored:
            x0, y0 = (t % tx) * 32, (t // tx) * 32
            tile = data[p:p + 384]
            p += 384
            for c in range(3):
                for r in range(32):
                    y = y0 + r
                    if y >= H:
                        break
                    for b in range(4):
                        xb = x0 // 8 + b
                        if xb < rowbytes:
                            out[base + c * H * rowbytes + y * rowbytes + xb] = tile[c * 128 + r * 4 + b]
        tiles += count
    check(p == len(data) and tiles == total, f'wvol size {len(data)}, parsed {p}; tiles {tiles} of {total}')
    return dict(W=W, H=H, images=n, N=N, seq=seq), bytes(out)


def rot_scene(c, angle):
    """A layer of lines turned by angle about the axis; returns (list, layer)."""
    pts = [(0.1, -0.5, 0.0), (0.8, 0.3, 0.0), (0.0, 0.0, 0.0), (0.6, 0.0, 0.4)]
    buf = c.create('create_buffer_inline', w.vertices(pts))
    lst = c.create('create_list')
    layer = c.create('create_layer')
    c.req(lst, 'list.set_color', 0xff8000ff)
    c.req(lst, 'list.draw', MODE['lines'], buf, 0, 4, 0)
    c.req(layer, 'layer.set_list', lst)
    turn(c, layer, angle)
    return lst, layer


def turn(c, layer, angle):
    ca, sa = math.cos(angle), math.sin(angle)
    c.req(layer, 'layer.set_transform', (ca, 0, -sa, 0, 0, 1, 0, 0, sa, 0, ca, 0, 0, 0, 0, 1))


def watch(c, rate=0):
    wid = c.new_id()
    c.req(1, 'display.watch', wid, rate)
    return wid


def next_volume(c, wid, timeout=5.0):
    ev = c.wait(lambda e: e.obj == wid, timeout, f'watcher {wid} event')
    if ev.name == 'watcher.failed':
        c.objects.pop(wid, None)
        return ev
    return ev, w.read_memfd(ev)


def watch_stats(c):
    c.req(1, 'display.get_status')
    ev = c.wait('display.watchers')
    c.wait('display.status')
    return ev


@case
def watch_matches_capture():
    """The first volume is the one on display; it holds what a capture of
    the same volume holds."""
    d, wit = shared(*SETTINGS)
    c = d.conn()
    check(c.version >= 5, f'version {c.version}')
    rot_scene(c, 0.3)
    c.frame_commit()
    cap = c.capture()
    hdr = svol_header(cap)
    wid = watch(c)
    ev, data = next_volume(c, wid)
    whdr, dense = wvol_dense(data)
    check(ev['seq'] == whdr['seq'] == hdr['seq'], f'seq: event {ev["seq"]}, wvol {whdr["seq"]}, svol {hdr["seq"]}')
    check((whdr['W'], whdr['H'], whdr['images'], whdr['N']) == (hdr['W'], hdr['H'], hdr['images'], hdr['N']),
          f'geometry {whdr} vs {hdr}')
    check(lit(dense) > 0, 'the watched volume lights voxels')
    check(dense == svol_planes(cap), 'the watched volume is the captured one, bit for bit')
    c.req(wid, 'watcher.destroy')
    c.sync()
    check(not c.errors(), f'{c.errors()}')
    c.close()
    wit.check(exact=False)


@case
def one_in_flight():
    """Nothing more is sent until release; the volumes shown meanwhile are
    skipped and counted; after release the newest comes."""
    d, wit = shared(*SETTINGS)
    c = d.conn()
    lst, layer = rot_scene(c, 0.0)
    c.frame_commit()
    wid = watch(c, 100)
    ev, data = next_volume(c, wid)
    first = ev['seq']
    for i in range(6):
        turn(c, layer, 0.2 * (i + 1))
        c.frame_commit()
    time.sleep(0.3)
    c.pump(0.1)
    check(not [e for e in c.events if e.obj == wid], 'no volume while one is in flight')
    c.req(wid, 'watcher.release')
    ev, data = next_volume(c, wid)
    check(ev['seq'] > first, f'a newer volume after release: {ev["seq"]} after {first}')
    check(ev['skipped'] >= 1, f'the volumes shown in between were skipped: {ev["skipped"]}')
    whdr, dense = wvol_dense(data)
    check(dense == svol_planes(c.capture()), 'it is the volume on display')
    st = watch_stats(c)
    check(st['watchers'] == 1 and st['volumes_sent'] >= 2 and st['volumes_skipped'] >= 1, f'counted: {st}')
    c.req(wid, 'watcher.release')
    c.req(wid, 'watcher.destroy')
    c.sync()
    check(watch_stats(c)['watchers'] == 0, 'the destroyed watcher is gone')
    c.close()
    wit.check(exact=False)


def rate_of(c, layer, wid, seconds):
    """Animates the scene and releases every volume at once; volumes a second."""
    got = 0
    end = time.monotonic() + seconds
    a = 0.0
    while time.monotonic() < end:
        a += 0.1
        turn(c, layer, a)
        c.frame_commit()
        c.pump(0)
        for e in [e for e in c.events if e.obj == wid]:
            c.events.remove(e)
            check(e.name == 'watcher.volume', f'{e}')
            os.close(e['fd'])
            got += 1
            c.req(wid, 'watcher.release')
    return got / seconds


@case
def max_rate():
    """A watcher gets at most its rate, and at most max-watch-rate (8 here)."""
    d, wit = shared(*SETTINGS)
    c = d.conn()
    lst, layer = rot_scene(c, 0.0)
    c.frame_commit()
    for asked, limit in ((3, 3), (0, 8), (500, 8)):
        wid = watch(c, asked)
        r = rate_of(c, layer, wid, 2.0)
        check(1.0 <= r <= limit * 1.15 + 0.5, f'asked {asked}: {r:.1f} volumes/s, limit {limit}')
        c.req(wid, 'watcher.destroy')
        c.sync()
    c.close()
    wit.check(exact=False)


@case
def max_watchers():
    """Beyond max-watchers (2 here) a watcher gets failed limit; the client
    stays connected, and the refusal is counted."""
    d, wit = shared(*SETTINGS)
    c = d.conn()
    before = watch_stats(c)
    a, b = watch(c), watch(c)
    next_volume(c, a)
    next_volume(c, b)
    x = watch(c)
    ev = next_volume(c, x)
    check(getattr(ev, 'name', None) == 'watcher.failed' and ev['code'] == FAILURE['limit'], f'{ev}')
    c.sync()
    st = watch_stats(c)
    check(st['watchers'] == 2 and st['max_watchers'] == 2 and st['refused'] == before['refused'] + 1, f'{st}')
    check(not c.errors() and not c.eof, 'still connected')
    c.req(a, 'watcher.destroy')
    y = watch(c)   # room again
    ev, _ = next_volume(c, y)
    check(ev.name == 'watcher.volume', f'{ev}')
    c.close()   # its watchers go with it
    c2 = d.conn()
    check(watch_stats(c2)['watchers'] == 0, 'a departed client\'s watchers are gone')
    c2.close()
    wit.check(exact=False)


@case
def denied_unprivileged():
    """Watching follows capture's policy: uid 65534 gets failed denied and
    stays connected."""
    d, wit = shared(*SETTINGS)
    c, = connect_as(NOBODY, d.sock, 1)
    c.hello()
    wid = watch(c)
    ev = next_volume(c, wid)
    check(getattr(ev, 'name', None) == 'watcher.failed' and ev['code'] == FAILURE['denied'], f'{ev}')
    c.sync()
    check(not c.errors() and not c.eof, 'still connected')
    check(watch_stats(c)['denied'] >= 1, 'counted')
    c.close()
    wit.check(exact=False)


@case
def rate_out_of_range():
    """max_rate_hz over 1000 is invalid_value."""
    d, wit = shared(*SETTINGS)
    c = d.conn()
    c.req(1, 'display.watch', c.new_id(), 1001)
    c.expect_fatal(ERR['invalid_value'], 1)
    wit.check(exact=False)


if __name__ == '__main__':
    run()
