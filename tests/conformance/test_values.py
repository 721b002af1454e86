#!/usr/bin/env python3
"""Out-of-range values: counts and strides that overflow, draws past the
end of their buffer, bad modes, indices out of range or misaligned, point
sizes, priorities, the transform stack, non-affine matrices. Each
case: the offending client alone gets display.error with the documented code
naming the object the request was sent to, then EOF; the witness is served
and its scene shows; the daemon holds no more fds than before."""
import math
import struct

from harness import Abuse, ERR, MODE, IDENTITY, P, case, check, run, shared, w

HDR = w.HEADER
INV_MSG, INV_OBJ, INV_METHOD, INV_VALUE, VERSION = (
    ERR['invalid_message'], ERR['invalid_object'], ERR['invalid_method'], ERR['invalid_value'], ERR['version'])
U16, U32 = w.INDEX['u16'], w.INDEX['u32']


def abuse(version=None, hello=True):
    d, wit = shared()
    return Abuse(d, wit)


def objects(c, nverts=8):
    """A vertex buffer of nverts xyz vertices (then 16 u16 and 16 u32
    indices, all 0), a list and a layer."""
    data = w.vertices([(0.1, 0.0, 0.0)] * nverts)
    ioff = len(data)
    data += bytes(32) + bytes(64)
    buf = c.buffer(data)
    return buf, c.create('create_list'), c.create('create_layer'), ioff


def fatal(raw, code, obj=1, version=1, fds=()):
    """Sends raw bytes after hello; expects code naming obj."""
    with abuse() as a:
        c = a.conn(version)
        c.sync()
        c.send_all(raw(c) if callable(raw) else raw, fds)
        c.expect_fatal(code, obj)


# -- counts, strides, offsets ----------------------------------------------

def draw_fatal(mode, offset, count, stride, code=INV_VALUE, version=1, prelude=None):
    with abuse() as a:
        c = a.conn(version)
        buf, lst, layer, _ = objects(c)
        if prelude:
            prelude(c, lst)
        c.req(lst, 'list.draw', mode, buf, offset, count, stride)
        c.expect_fatal(code, lst)


@case
def draw_count_stride_overflow_32():
    """count * stride = 2^35: wraps to 0 in 32 bits."""
    draw_fatal(MODE['points'], 0, 0x80000000, 64)


@case
def draw_count_stride_overflow_64():
    """offset near 2^64: offset + count * stride wraps in 64 bits."""
    draw_fatal(MODE['points'], 0xffffffffffffffc0, 0xffffffff, 65536)


@case
def draw_offset_wraps():
    draw_fatal(MODE['points'], 0xfffffffffffffff4, 2, 12)


@case
def draw_past_end():
    draw_fatal(MODE['points'], 0, 100, 12)


@case
def draw_offset_past_end():
    draw_fatal(MODE['points'], 4096, 1, 0)


@case
def draw_stride_too_large():
    draw_fatal(MODE['points'], 0, 1, 65540)


@case
def draw_stride_below_format():
    draw_fatal(MODE['points'], 0, 2, 8)


@case
def draw_bad_mode():
    draw_fatal(len(MODE), 0, 1, 0)


@case
def draw_mode_ffffffff():
    draw_fatal(0xffffffff, 0, 1, 0)


@case
def draw_lines_odd():
    draw_fatal(MODE['lines'], 0, 3, 0)


@case
def draw_triangles_not_3n():
    draw_fatal(MODE['triangles'], 0, 4, 0)


@case
def draw_line_strip_one():
    draw_fatal(MODE['line_strip'], 0, 1, 0, version=2)


@case
def draw_rgba_float_stride_16():
    """xyz_rgba_float is 28 bytes: stride 16 is below it."""
    draw_fatal(MODE['points'], 0, 2, 16, version=2,
               prelude=lambda c, lst: c.req(lst, 'list.set_vertex_format', w.FORMAT['xyz_rgba_float']))


def indexed_fatal(mode=MODE['points'], offset=0, vcount=8, stride=0, ioff=None, icount=4, itype=U16,
                  code=INV_VALUE, indices=None):
    with abuse() as a:
        c = a.conn(2)
        buf, lst, layer, base = objects(c)
        ibuf = buf
        if indices is not None:
            ibuf = c.create('create_buffer_inline', indices)
            base = 0
        c.req(lst, 'list.draw_indexed', mode, buf, offset, vcount, stride, ibuf,
              base if ioff is None else ioff, icount, itype)
        c.expect_fatal(code, lst)


@case
def indexed_control_ok():
    """The valid form of the draw_indexed cases below is accepted."""
    d, wit = shared()
    c = d.conn(2)
    buf, lst, layer, base = objects(c)
    c.req(lst, 'list.draw_indexed', MODE['points'], buf, 0, 8, 0, buf, base, 16, U16)
    c.req(lst, 'list.draw_indexed', MODE['points'], buf, 0, 8, 0, buf, base + 32, 16, U32)
    c.sync()
    check(not c.errors(), f'{c.errors()}')
    c.close()


@case
def indexed_count_overflow():
    """index_count * 4 wraps in 32 bits; index_offset + that wraps in 64."""
    indexed_fatal(icount=0x40000001, itype=U32)


@case
def indexed_offset_wraps():
    indexed_fatal(ioff=0xfffffffffffffffc, icount=4, itype=U32)


@case
def indexed_vertex_count_stride_overflow():
    """vertex_count * stride = 2^36 (wraps to 0 in 32 bits)."""
    indexed_fatal(vcount=0x100000, stride=65536)


@case
def indexed_vertices_past_end():
    indexed_fatal(vcount=1000)


@case
def indexed_index_out_of_range():
    indexed_fatal(vcount=4, indices=struct.pack('<4H', 0, 1, 2, 4))


@case
def indexed_index_ffffffff():
    indexed_fatal(vcount=8, itype=U32, indices=struct.pack('<4I', 0, 1, 0xffffffff, 2))


@case
def indexed_misaligned_offset_u32():
    indexed_fatal(ioff=2, itype=U32, indices=bytes(32))


@case
def indexed_misaligned_offset_u16():
    indexed_fatal(ioff=1, itype=U16, indices=bytes(32))


@case
def indexed_bad_type():
    indexed_fatal(itype=3)


@case
def indexed_indices_past_end():
    indexed_fatal(icount=8, indices=bytes(8))


@case
def indexed_lines_odd():
    indexed_fatal(mode=MODE['lines'], icount=3)


# -- values -------------------------------------------------------------------

def value_fatal(iface, name, *args, code=INV_VALUE, prelude=None):
    version = max(P.request(f'{iface}.{name}').since, 1)
    with abuse() as a:
        c = a.conn(2 if prelude else version)
        buf, lst, layer, _ = objects(c)
        obj = {'list': lst, 'layer': layer, 'display': 1}[iface]
        if prelude:
            prelude(c, obj)
        c.req(obj, f'{iface}.{name}', *args)
        c.expect_fatal(code, obj)


@case
def point_size_0():
    value_fatal('list', 'set_point_size', 0)


@case
def point_size_17():
    value_fatal('list', 'set_point_size', 17)


@case
def point_size_1_and_16_ok():
    d, wit = shared()
    c = d.conn(2)
    lst = c.create('create_list')
    c.req(lst, 'list.set_point_size', 1)
    c.req(lst, 'list.set_point_size', 16)
    c.sync()
    check(not c.errors(), f'{c.errors()}')
    c.close()


@case
def vertex_format_bad():
    value_fatal('list', 'set_vertex_format', len(w.FORMAT))


@case
def priority_below():
    value_fatal('layer', 'set_priority', -1001)


@case
def priority_above():
    value_fatal('layer', 'set_priority', 1001)


@case
def pop_empty():
    value_fatal('list', 'pop')


@case
def pop_after_clear():
    """clear empties the stack."""
    value_fatal('list', 'pop', prelude=lambda c, lst: (c.req(lst, 'list.push'), c.req(lst, 'list.clear')))


@case
def push_17_deep():
    value_fatal('list', 'push', prelude=lambda c, lst: [c.req(lst, 'list.push') for _ in range(16)])


@case
def push_16_deep_ok():
    d, wit = shared()
    c = d.conn(2)
    lst = c.create('create_list')
    for _ in range(16):
        c.req(lst, 'list.push')
    for _ in range(16):
        c.req(lst, 'list.pop')
    c.sync()
    check(not c.errors(), f'{c.errors()}')
    c.close()


NOT_AFFINE = (1, 0, 0, 0.5, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1)   # bottom row 0.5 0 0 1
NAN = (math.nan,) + IDENTITY[1:]
INF = IDENTITY[:12] + (math.inf, 0, 0, 1)


@case
def list_transform_not_affine():
    value_fatal('list', 'set_transform', NOT_AFFINE)


@case
def list_transform_nan():
    value_fatal('list', 'set_transform', NAN)


@case
def list_multiply_transform_inf():
    value_fatal('list', 'multiply_transform', INF)


@case
def list_multiply_transform_not_affine():
    value_fatal('list', 'multiply_transform', IDENTITY[:15] + (2.0,))


@case
def layer_transform_not_affine():
    value_fatal('layer', 'set_transform', NOT_AFFINE)


@case
def layer_transform_nan():
    value_fatal('layer', 'set_transform', NAN)



if __name__ == '__main__':
    run()
