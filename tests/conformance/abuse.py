"""Helpers shared by the malformed-input and out-of-range-value cases:
a client that misbehaves beside the shared daemon's witness, the objects a
draw needs, and a raw fatal message."""
from harness import Abuse, ERR, shared, w

HDR = w.HEADER
INV_MSG, INV_OBJ, INV_METHOD, INV_VALUE, VERSION = (
    ERR['invalid_message'], ERR['invalid_object'], ERR['invalid_method'], ERR['invalid_value'], ERR['version'])
U16, U32 = w.INDEX['u16'], w.INDEX['u32']


def abuse():
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
