#!/usr/bin/env python3
"""Quotas (max-objects, max-buffer-bytes, max-vertices: fatal; max-primitives:
a refused commit of which nothing shows, fixed and committed again), and the
policies: exclusive layers (exclusive = any | none | admin: refused busy or
denied) and capture (denied to an unprivileged client, allowed to a member of
admin-group). Unprivileged clients are forked children that drop to uid and
gid 65534 before they connect (SO_PEERCRED is taken at connect)."""
import grp
import time

from harness import (Abuse, ERR, MODE, Witness, check, covers, lit, run, run_as, svol_planes, w,
                     with_daemon)

QUOTA = ERR['quota']
NOBODY = 65534


def points(n, x=0.3):
    return w.vertices([(x, -0.5 + i / max(n, 1), 0.0) for i in range(n)])


@with_daemon('max-objects=8')
def max_objects(d):
    """max-objects - 2 objects (and a sync's callback) fit, whether or not
    the display counts; 3 more do not. Destroyed objects free their place."""
    wit = Witness(d)
    with Abuse(d, wit) as a:
        c = a.conn(1)
        ids = [c.create('create_list') for _ in range(6)]
        c.sync()
        check(not c.errors(), f'6 objects: {c.errors()}')
        for i in ids:
            c.req(i, 'list.destroy')
        ids = [c.create('create_layer') for _ in range(6)]
        c.sync()
        check(not c.errors(), f'6 objects again after destroying 6: {c.errors()}')
        for _ in range(3):
            c.create('create_list')
        c.expect_fatal(QUOTA, 1)


@with_daemon('max-buffer-bytes=4096')
def max_buffer_bytes(d):
    wit = Witness(d)
    with Abuse(d, wit) as a:
        c = a.conn(2)
        b = c.create('create_buffer_inline', bytes(4096))
        c.sync()
        check(not c.errors(), f'4096 bytes inline: {c.errors()}')
        c.req(b, 'buffer.destroy')
        b = c.buffer(bytes(4096))
        c.sync()
        check(not c.errors(), f'4096 bytes in a memfd after destroying the first: {c.errors()}')
        c.create('create_buffer_inline', bytes(4))
        c.expect_fatal(QUOTA, 1)
    with Abuse(d, wit) as a:
        c = a.conn(1)
        c.buffer(bytes(4100))
        c.expect_fatal(QUOTA, 1)
    with Abuse(d, wit) as a:
        c = a.conn(1)
        fd = w.memfd(bytes(64))
        c.create('create_buffer', 1 << 40, fd)   # the quota, or the size lie: fatal either way
        c.expect_fatal((QUOTA, ERR['bad_fd']), 1)


@with_daemon('max-vertices=100')
def max_vertices(d):
    wit = Witness(d)
    with Abuse(d, wit) as a:
        c = a.conn(1)
        b = c.buffer(points(100))
        lst = c.create('create_list')
        c.req(lst, 'list.draw', MODE['points'], b, 0, 96, 0)
        c.req(lst, 'list.clear')
        c.req(lst, 'list.draw', MODE['points'], b, 0, 100, 0)
        c.sync()
        check(not c.errors(), f'100 vertices (after a clear): {c.errors()}')
        other = c.create('create_list')
        c.req(other, 'list.draw', MODE['points'], b, 0, 1, 0)
        c.expect_fatal(QUOTA, other)


@with_daemon('max-vertices=100')
def max_vertices_pending_and_committed(d):
    """max-vertices counts the pending state: 96 committed, cleared, and 8
    pending is 8 (the committed 96 go at the next commit); 96 + 8 pending
    is over."""
    wit = Witness(d)
    with Abuse(d, wit, exact=False) as a:
        c = a.conn(1)
        b = c.buffer(points(100))
        lst = c.create('create_list')
        layer = c.create('create_layer')
        c.req(lst, 'list.draw', MODE['points'], b, 0, 96, 0)
        c.req(layer, 'layer.set_list', lst)
        c.frame_commit()
        c.req(lst, 'list.clear')
        c.req(lst, 'list.draw', MODE['points'], b, 0, 8, 0)
        c.sync()
        check(not c.errors(), f'8 pending after a clear are within the quota: {c.errors()}')
        c.req(lst, 'list.draw', MODE['points'], b, 0, 93, 0)
        c.expect_fatal(QUOTA, lst)


def scene(c, n, layers=1):
    b = c.buffer(points(n, 0.4))
    lst = c.create('create_list')
    c.req(lst, 'list.draw', MODE['points'], b, 0, n, 0)
    ls = []
    for _ in range(layers):
        layer = c.create('create_layer')
        c.req(layer, 'layer.set_list', lst)
        ls.append(layer)
    return b, lst, ls


def refused(c, code, objs):
    ev = c.wait('display.refused', what='display.refused')
    check(ev['code'] == code, f'refusal code {ev}')
    check(ev['object'] in objs, f'refusal names {ev["object"]}, expected one of {objs}')
    return ev


@with_daemon('max-primitives=10')
def max_primitives_refused(d):
    """11 points: refused, nothing shows, the frame callback stays pending;
    cut to 10 and committed again: shows, the callbacks are done."""
    wit = Witness(d)
    c = d.conn(2)
    b, lst, (layer,) = scene(c, 11)
    cb = c.new_id()
    c.req(1, 'display.frame', cb)
    c.req(1, 'display.commit')
    refused(c, w.REFUSAL['quota'], (1, layer))
    wit.check(exact=True)   # nothing of it shows
    c.sync()
    check(not any(e.obj == cb for e in c.log), 'the frame callback stays pending')
    c.req(lst, 'list.clear')
    c.req(lst, 'list.draw', MODE['points'], b, 0, 10, 0)
    done = c.frame_commit()
    c.wait(lambda e: e.obj == cb, what='the first frame callback')
    cap = svol_planes(c.capture())
    check(covers(cap, wit.svol) and cap != wit.svol, 'the fixed commit shows')
    check(not c.errors() and not any(e.name == 'display.refused' for e in c.events), f'{c.log[-5:]}')
    st = c.status()
    check(done['volume_seq'] > 0, f'{done}')
    c.close()
    wit.check()
    del st


@with_daemon('max-primitives=10')
def max_primitives_per_layer(d):
    """A list of 6 shown by two layers counts 12."""
    wit = Witness(d)
    c = d.conn(2)
    b, lst, layers = scene(c, 6, layers=2)
    c.req(1, 'display.commit')
    refused(c, w.REFUSAL['quota'], (1, *layers))
    c.req(layers[1], 'layer.set_visible', 0)
    c.frame_commit()
    c.sync()
    check(not [e for e in c.log if e.name == 'display.refused'][1:], 'one layer of 6 fits')
    check(not c.errors(), f'{c.errors()}')
    c.close()
    wit.check()


@with_daemon('max-primitives=10')
def max_primitives_version_1(d):
    """At version 1 there is no refused event (spindlewire fails on any
    event newer than the version): going over max-primitives is the fatal
    quota error, and nothing of that commit shows."""
    wit = Witness(d)
    with Abuse(d, wit, exact=False) as a:
        c = a.conn(1)
        scene(c, 11)
        c.req(1, 'display.commit')
        c.expect_fatal(QUOTA, 1)


def exclusive_scene(c, x=0.6):
    b = c.buffer(w.vertices([(x, -0.4, 0.0), (x, 0.4, 0.0)]))
    lst = c.create('create_list')
    layer = c.create('create_layer')
    c.req(lst, 'list.draw', MODE['lines'], b, 0, 2, 0)
    c.req(layer, 'layer.set_list', lst)
    return layer


@with_daemon('exclusive=any')
def exclusive_busy(d):
    wit = Witness(d)
    a = d.conn(2)
    la = exclusive_scene(a, 0.6)
    a.req(la, 'layer.set_exclusive', 1)
    a.frame_commit()
    alone = svol_planes(a.capture())
    check(lit(alone) > 0 and not covers(alone, wit.svol), 'the exclusive layer shows alone')
    b = d.conn(2)
    lb = exclusive_scene(b, -0.6)
    b.req(lb, 'layer.set_exclusive', 1)
    b.req(1, 'display.commit')
    refused(b, w.REFUSAL['busy'], (1, lb))
    b.sync()
    check(svol_planes(a.capture()) == alone, 'still A alone')
    a.req(la, 'layer.set_exclusive', 0)
    a.frame_commit()
    b.req(1, 'display.commit')   # the pending exclusive commit again: granted now
    b.sync()
    check(not [e for e in b.log if e.name == 'display.refused'][1:], f'granted once A withdrew: {b.log[-4:]}')
    check(not a.errors() and not b.errors(), f'{a.errors()} {b.errors()}')
    a.close()
    b.close()
    wit.check()


@with_daemon('exclusive=none')
def exclusive_none(d):
    wit = Witness(d)
    c = d.conn(2)
    layer = exclusive_scene(c)
    c.req(layer, 'layer.set_exclusive', 1)
    c.req(1, 'display.commit')
    refused(c, w.REFUSAL['denied'], (1, layer))
    wit.check()   # nothing of it shows
    c.req(layer, 'layer.set_exclusive', 0)
    c.frame_commit()
    c.sync()
    check(len([e for e in c.log if e.name == 'display.refused']) == 1, 'granted once not exclusive')
    c.close()
    wit.check()


def unprivileged_session(sock, what):
    """In the dropped child: hello 2 and capture or an exclusive commit."""
    def fn():
        c = w.Conn(sock)
        c.hello(2)
        if what == 'capture':
            r = c.capture()
            out = ('failed', r['code']) if isinstance(r, w.Event) else ('ready', len(r))
        else:
            layer = exclusive_scene(c)
            c.req(layer, 'layer.set_exclusive', 1)
            c.req(1, 'display.commit')
            c.sync()
            time.sleep(0.05)
            c.pump(0.05)
            ref = [e for e in c.log if e.name == 'display.refused']
            out = ('refused', ref[0]['code']) if ref else ('granted', 0)
        check_errors = [str(e) for e in c.errors()]
        c.close()
        return out, check_errors
    return fn


def admin_group():
    for name in ('users', 'nogroup'):
        try:
            return grp.getgrnam(name)
        except KeyError:
            pass
    return None


@with_daemon()
def capture_denied(d):
    wit = Witness(d)
    out, errs = run_as(NOBODY, NOBODY, [], unprivileged_session(d.sock, 'capture'))
    check(out == ('failed', w.FAILURE['denied']) and not errs, f'unprivileged capture: {out} {errs}')
    out, errs = run_as(NOBODY, NOBODY, [], unprivileged_session(d.sock, 'exclusive'))
    check(out == ('refused', w.REFUSAL['denied']) and not errs,
          f'unprivileged exclusive under the default policy (admin): {out} {errs}')
    wit.check()


def admin_group_case(d, g):
    wit = Witness(d)
    out, errs = run_as(NOBODY, NOBODY, [g.gr_gid], unprivileged_session(d.sock, 'capture'))
    check(out[0] == 'ready' and not errs, f'capture by a member of admin-group {g.gr_name}: {out} {errs}')
    out, errs = run_as(NOBODY, NOBODY, [g.gr_gid], unprivileged_session(d.sock, 'exclusive'))
    check(out == ('granted', 0) and not errs, f'exclusive for a member of admin-group: {out} {errs}')
    wit.check()


G = admin_group()


@with_daemon(f'admin-group={G.gr_name if G else "users"}', 'exclusive=admin')
def capture_admin_group(d):
    check(G is not None, 'a group to use as admin-group')
    admin_group_case(d, G)


if __name__ == '__main__':
    run()
