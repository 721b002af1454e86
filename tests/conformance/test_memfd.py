#!/usr/bin/env python3
"""memfd buffers: unsealed, sealed the wrong way, lying about their size,
shrinking (impossible once sealed) and growing after submit, and vertices and
indices changed after the draw request: what shows is what was drawn then
(captures of the changed and the unchanged case compared bit for bit)."""
import errno
import fcntl
import os
import struct

from harness import Abuse, ERR, MODE, case, check, lit, run, shared, svol_planes, with_daemon, w

BAD_FD = ERR['bad_fd']


def abuse():
    d, wit = shared()
    return Abuse(d, wit)


def create_fatal(fd, size, code=BAD_FD):
    with abuse() as a:
        c = a.conn(1)
        c.create('create_buffer', size, fd)
        os.close(fd)
        c.expect_fatal(code, 1)


@case
def unsealed():
    create_fatal(w.memfd(bytes(64), seals=0), 64)


@case
def sealed_grow_only():
    create_fatal(w.memfd(bytes(64), seals=fcntl.F_SEAL_GROW), 64)


@case
def sealing_not_allowed():
    """A memfd made without MFD_ALLOW_SEALING can never be sealed."""
    fd = os.memfd_create('nosealing', os.MFD_CLOEXEC)
    os.ftruncate(fd, 64)
    create_fatal(fd, 64)


@case
def size_lie():
    """Declared size beyond the memfd's real size (fstat)."""
    create_fatal(w.memfd(bytes(64)), 4096)


@case
def size_lie_huge():
    create_fatal(w.memfd(bytes(64)), 0xffffffffffffffff)


@case
def every_seal_ok():
    """Sealed against shrink, grow and write, and the seals sealed: fine."""
    d, wit = shared()
    c = d.conn(1)
    fd = w.memfd(w.vertices([(0.3, 0.1, 0.0)] * 4),
                 seals=fcntl.F_SEAL_SHRINK | fcntl.F_SEAL_GROW | fcntl.F_SEAL_WRITE | fcntl.F_SEAL_SEAL)
    b = c.create('create_buffer', 48, fd)
    os.close(fd)
    lst = c.create('create_list')
    c.req(lst, 'list.draw', MODE['points'], b, 0, 4, 0)
    c.sync()
    check(not c.errors(), f'{c.errors()}')
    c.close()


@case
def bigger_than_declared_ok():
    """A memfd larger than the size declared is fine ("at least size")."""
    d, wit = shared()
    c = d.conn(1)
    fd = w.memfd(bytes(4096))
    c.create('create_buffer', 100, fd)
    os.close(fd)
    c.sync()
    check(not c.errors(), f'{c.errors()}')
    c.close()


@case
def truncate_and_grow_after_submit():
    """Shrinking a sealed memfd is refused by the kernel; growing it is
    allowed and the daemon draws from it as before and survives."""
    with abuse() as a:
        d = a.d
        c = a.conn(1)
        data = w.vertices([(0.0, -0.5, 0.0), (0.0, 0.5, 0.0)])
        fd = w.memfd(data)
        b = c.create('create_buffer', len(data), fd)
        c.sync()
        try:
            os.ftruncate(fd, 0)
            check(False, 'a memfd sealed against shrinking shrank')
        except OSError as e:
            check(e.errno == errno.EPERM, f'ftruncate: {e}')
        os.ftruncate(fd, 1 << 20)
        lst = c.create('create_list')
        layer = c.create('create_layer')
        c.req(lst, 'list.draw', MODE['lines'], b, 0, 2, 0)
        c.req(layer, 'layer.set_list', lst)
        c.frame_commit()
        check(lit(svol_planes(c.capture())) > 0, 'draws from the grown memfd')
        os.close(fd)
        c.req(1, 'display.create_list', c.new_id())
        c.sync()
        check(not c.errors() and d.alive(), f'{c.errors()}')


LINE_A = [(0.0, -0.6, 0.0), (0.0, 0.6, 0.0)]
LINE_B = [(0.7, -0.3, 0.0), (-0.7, 0.3, 0.5)]


def scene_capture(d, draw):
    """A fresh client shows what draw(c, lst) draws; its capture's planes."""
    c = d.conn(2)
    lst = c.create('create_list')
    layer = c.create('create_layer')
    draw(c, lst)
    c.req(layer, 'layer.set_list', lst)
    c.frame_commit()
    planes = svol_planes(c.capture())
    check(not c.errors(), f'{c.errors()}')
    c.close()
    return planes


def plain(points):
    def draw(c, lst):
        b = c.create('create_buffer_inline', w.vertices(points))
        c.req(lst, 'list.draw', MODE['lines'], b, 0, len(points), 0)
    return draw


def flipped(before, after):
    """Drawn from a memfd holding before, which then holds after."""
    def draw(c, lst):
        data = w.vertices(before)
        fd = w.memfd(data)
        b = c.create('create_buffer', len(data), fd)
        c.req(lst, 'list.draw', MODE['lines'], b, 0, len(before), 0)
        c.sync()
        os.pwrite(fd, w.vertices(after), 0)
        os.close(fd)
    return draw


def compare(d, drawn, other, changed):
    """Shows the same as the reference, and differs from the other."""
    ref = scene_capture(d, drawn)
    got = scene_capture(d, changed)
    alt = scene_capture(d, other)
    check(ref != alt, 'the two scenes differ (the test can tell them apart)')
    check(lit(ref) > 0, 'the scene lights voxels')
    check(got == ref, 'what shows is what was drawn at the draw request, not the memfd changed after it')


@with_daemon()
def flip_vertices(d):
    """Vertices changed after list.draw (before commit)."""
    compare(d, plain(LINE_A), plain(LINE_B), flipped(LINE_A, LINE_B))


@with_daemon()
def flip_indices(d):
    """Indices changed after list.draw_indexed: the indices drawn were
    copied and checked then (a changed index may even be out of range)."""
    pts = LINE_A + LINE_B

    def indexed(indices, after=None):
        def draw(c, lst):
            vb = c.create('create_buffer_inline', w.vertices(pts))
            data = struct.pack('<2I', *indices)
            fd = w.memfd(data)
            ib = c.create('create_buffer', len(data), fd)
            c.req(lst, 'list.draw_indexed', MODE['lines'], vb, 0, 4, 0, ib, 0, 2, w.INDEX['u32'])
            c.sync()
            if after is not None:
                os.pwrite(fd, struct.pack('<2I', *after), 0)
            os.close(fd)
        return draw
    compare(d, indexed((0, 1)), indexed((2, 3)), indexed((0, 1), (2, 3)))
    ref = scene_capture(d, indexed((0, 1)))
    check(scene_capture(d, indexed((0, 1), (0xffffffff, 7))) == ref, 'indices made out of range after the draw')


@with_daemon()
def flip_after_commit(d):
    """Changed after the commit, and the buffer destroyed: still the same."""
    ref = scene_capture(d, plain(LINE_A))
    c = d.conn(1)
    data = w.vertices(LINE_A)
    fd = w.memfd(data)
    b = c.create('create_buffer', len(data), fd)
    lst = c.create('create_list')
    layer = c.create('create_layer')
    c.req(lst, 'list.draw', MODE['lines'], b, 0, 2, 0)
    c.req(layer, 'layer.set_list', lst)
    c.frame_commit()
    os.pwrite(fd, w.vertices(LINE_B), 0)
    c.req(b, 'buffer.destroy')
    c.frame_commit()
    os.close(fd)
    check(svol_planes(c.capture()) == ref, 'the committed scene is what was drawn')
    check(not c.errors(), f'{c.errors()}')
    c.close()


if __name__ == '__main__':
    run()
