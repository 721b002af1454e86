#!/usr/bin/env python3
"""Versions: hello and welcome at every version, every request at every
version it exists in (since= in docs/protocol.md) accepted with valid
arguments, requests and enum values newer than the version agreed fatal, and
no event newer than it sent (checked on every event by spindlewire)."""
import struct

from harness import (Abuse, P, ERR, MODE, IDENTITY, case, check, run, shared, svol_planes, lit, w)

INDEX_TYPE = w.INDEX
FORMAT = w.FORMAT


@case
def hello_versions():
    """welcome gives the lower of the client's and the daemon's versions;
    device follows, and state from version 2 on (Conn.hello waits for them)."""
    d, wit = shared()
    for v in (1, 2, 3, 7, 0xffffffff):
        c = d.conn(v)
        check(c.version == min(v, P.version), f'hello {v}: welcome {c.version}')
        check(c.device['width'] > 0 and c.device['images_per_rev'] > 0, f'device {c.device}')
        if c.version >= 2:
            st = c.state
            check(st is not None, 'state after device at version 2')
            check(c.log[2].name == 'display.state', f'order welcome, device, state: {c.log}')
        else:
            check(len(c.log) == 2, f'version 1: welcome and device only: {c.log}')
        c.sync()
        c.close()
    wit.check()


@case
def hello_zero():
    """No common version with 0: error version."""
    d, wit = shared()
    with Abuse(d, wit) as a:
        c = a.conn(hello=False)
        c.req(1, 'display.hello', 0)
        c.expect_fatal(ERR['version'], 1)


def valid_requests(c, version):
    """Sends every request that exists at version, with valid arguments,
    each mode, vertex format and index type the version has."""
    pts = [(0.1 * i, 0.05 * i - 0.3, 0.2) for i in range(12)]
    xyz = w.vertices(pts)
    buf = c.buffer(xyz + bytes(64))
    idx = None
    lst = c.create('create_list')
    layer = c.create('create_layer')
    if version >= 2:
        inline = c.create('create_buffer_inline', xyz)
        idx = c.create('create_buffer_inline', struct.pack('<6H', 0, 1, 2, 3, 4, 5) + struct.pack('<6I', 6, 7, 8, 9, 10, 11))
    c.req(lst, 'list.set_color', 0xff8040ff)
    c.req(lst, 'list.set_transform', (0.5, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 0.5, 0, 0.1, 0.1, 0, 1))
    for name, (mode, since) in P.enums['list.mode'].items():
        if since <= version:
            c.req(lst, 'list.draw', mode, buf, 0, 6, 0)
            c.req(lst, 'list.draw', mode, buf, 12, 6, 12)
    if version >= 2:
        for name, (fmt, since) in P.enums['list.vertex_format'].items():
            size = {'xyz': 12, 'xyz_rgba8': 16, 'xyz_rgba_float': 28}[name]
            data = w.vertices(pts[:6], name, [(255, 0, 0, 255) if name == 'xyz_rgba8' else (1.0, 0.5, 0.0, 1.0)] * 6)
            vb = c.create('create_buffer_inline', data)
            c.req(lst, 'list.set_vertex_format', fmt)
            c.req(lst, 'list.draw', MODE['triangles'], vb, 0, 6, size)
        c.req(lst, 'list.set_vertex_format', FORMAT['xyz'])
        c.req(lst, 'list.set_point_size', 4)
        c.req(lst, 'list.push')
        c.req(lst, 'list.multiply_transform', (1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0.2, 0, 1))
        c.req(lst, 'list.draw', MODE['points'], inline, 0, 12, 0)
        c.req(lst, 'list.pop')
        c.req(lst, 'list.draw_indexed', MODE['lines'], buf, 0, 12, 12, idx, 0, 6, INDEX_TYPE['u16'])
        c.req(lst, 'list.draw_indexed', MODE['points'], buf, 0, 12, 0, idx, 12, 6, INDEX_TYPE['u32'])
    c.req(lst, 'list.clear')
    c.req(lst, 'list.draw', MODE['lines'], buf, 0, 12, 0)
    c.req(layer, 'layer.set_list', lst)
    c.req(layer, 'layer.set_transform', IDENTITY)
    c.req(layer, 'layer.set_visible', 1)
    if version >= 2:
        c.req(layer, 'layer.set_priority', -1000)
        c.req(layer, 'layer.set_priority', 1000)
        c.req(layer, 'layer.set_priority', 0)
        c.req(layer, 'layer.set_exclusive', 0)
    c.frame_commit()
    cap = c.capture()
    check(lit(svol_planes(cap)) > 0, 'the scene shows')
    st = c.status()
    check(st['clients'] >= 1, f'status counts this client: {st}')
    c.req(layer, 'layer.set_list', 0)
    c.req(layer, 'layer.destroy')
    c.req(lst, 'list.destroy')
    c.req(buf, 'buffer.destroy')
    if idx:
        c.req(idx, 'buffer.destroy')
    c.req(1, 'display.commit')
    c.sync()
    c.sync()


def every_request(version):
    d, wit = shared()
    c = d.conn(version)
    check(c.version == version, f'welcome {c.version}')
    valid_requests(c, version)
    want = {m.full for m in P.requests_of(version=version)}
    check(want - c.sent == set(), f'requests not exercised at version {version}: {want - c.sent}')
    check(not c.errors() and not c.eof, f'no error: {c.errors()}')
    c.close()
    wit.check()


@case
def every_request_v1():
    every_request(1)


@case
def every_request_v2():
    every_request(2)


def setup_objects(c):
    buf = c.buffer(w.vertices([(0, 0, 0)] * 8) + struct.pack('<8H', *range(8)))
    return {'display': 1, 'buffer': buf, 'list': c.create('create_list'), 'layer': c.create('create_layer')}


def valid_args(c, msg, objs):
    """Valid arguments for msg, any version."""
    vals = {'display.create_buffer_inline': (c.new_id(), b'\0' * 12),
            'list.draw_indexed': (MODE['points'], objs['buffer'], 0, 8, 0, objs['buffer'], 96, 8,
                                  INDEX_TYPE['u16']),
            'list.set_vertex_format': (FORMAT['xyz'],),
            'list.set_point_size': (2,),
            'list.push': (), 'list.pop': (),
            'list.multiply_transform': (IDENTITY,),
            'layer.set_priority': (1,),
            'layer.set_exclusive': (0,),
            'display.watch': (c.new_id(), 0),
            'display.calibrate': (0, 0.0),
            'display.create_volume': (c.new_id(), objs['buffer'], 0, 1, 2, 2, 2, 1.0, 1.0, 1.0),
            'list.draw_volume': (objs['buffer'], 0, 0.0, 0.0, 1.0),
            'list.set_volume_lut': (objs['buffer'], 0, 2)}
    return vals[msg.full]


@case
def newer_requests_fatal():
    """After hello 1 each version-2 request (valid arguments) is
    invalid_method naming its object."""
    d, wit = shared()
    newer = [m for m in P.requests.values() if m.since > 1]
    check(newer, 'the document has requests newer than version 1')
    for m in newer:
        if m.interface in ('watcher', 'volume'):
            continue   # none exists below version 5 (6): display.watch (create_volume) is the one tried
        with Abuse(d, wit) as a:
            c = a.conn(1)
            objs = setup_objects(c)
            c.sync()
            obj = objs[m.interface]
            c.req(obj, m.full, *valid_args(c, m, objs))
            try:
                c.expect_fatal(ERR['invalid_method'], obj)
            except AssertionError as e:
                raise AssertionError(f'{m.full} at version 1: {e}') from None


@case
def newer_enum_values_fatal():
    """Enum values newer than the version (list.mode line_strip at version 1)
    are invalid_value, for each such value of each version-1 request."""
    d, wit = shared()
    tried = 0
    for m in P.requests_of(version=1):
        for a in m.args:
            if not a.enum:
                continue
            for name, (val, since) in P.enums[a.enum].items():
                if since <= 1:
                    continue
                with Abuse(d, wit) as ab:
                    c = ab.conn(1)
                    objs = setup_objects(c)
                    check(m.full == 'list.draw', f'no valid arguments known for {m.full}')
                    c.req(objs['list'], 'list.draw', val, objs['buffer'], 0, 4, 0)
                    try:
                        c.expect_fatal(ERR['invalid_value'], objs['list'])
                    except AssertionError as e:
                        raise AssertionError(f'{m.full} {a.name} {name} at version 1: {e}') from None
                    tried += 1
    check(tried >= 1, 'line_strip at version 1 tried')


@case
def v2_values_accepted_at_v2():
    """The same line_strip at version 2 is fine (the control)."""
    d, wit = shared()
    c = d.conn(2)
    objs = setup_objects(c)
    c.req(objs['list'], 'list.draw', MODE['line_strip'], objs['buffer'], 0, 4, 0)
    c.sync()
    check(not c.errors(), f'{c.errors()}')
    c.close()


if __name__ == '__main__':
    run()
