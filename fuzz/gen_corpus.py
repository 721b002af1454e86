#!/usr/bin/env python3
"""Writes the fuzz targets' seed corpora: small, valid sessions made from the
protocol as proto/spindle.xml describes it (docs/protocol.md).

    fuzz/gen_corpus.py [OUTDIR]    (default: fuzz/corpus next to this script)

Each seed is one file in OUTDIR/<target>/, named after what it does. The
input formats are the ones the targets' header comments describe; opcodes
and argument layouts come from the XML through proto/gen.py's parser, so
the seeds follow the protocol when it changes (run again, commit the
difference). Python 3 standard library only; the output is reproducible.
"""

import os
import shutil
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "proto"))
import gen  # noqa: E402

VERSION, _, IFACES = gen.load(os.path.join(HERE, "..", "proto", "spindle.xml"))
BY_NAME = {i.name: i for i in IFACES}
IDENTITY = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]

# enum fuzz_fd_kind (fuzz/harness.h)
MEMFD_SEALED, MEMFD_ALL_SEALS, MEMFD_UNSEALED, PIPE, SOCKET, DEV_NULL = range(6)


# ---- the wire format ----

def find(iface, name, kind="request"):
    msgs = BY_NAME[iface].requests if kind == "request" else BY_NAME[iface].events
    for m in msgs:
        if m.name == name:
            return m
    raise KeyError(f"{iface}.{name}")


def pad4(b):
    return b + b"\0" * (-len(b) % 4)


def encode_arg(a, v):
    t = a.type
    if t in ("uint", "object", "new_id"):
        return struct.pack("<I", v)
    if t == "int":
        return struct.pack("<i", v)
    if t == "uint64":
        return struct.pack("<Q", v)
    if t == "float":
        return struct.pack("<f", v)
    if t == "matrix":
        return struct.pack("<16f", *v)
    if t == "string":
        if v is None:
            return struct.pack("<I", 0)
        s = v.encode() + b"\0"
        return struct.pack("<I", len(s)) + pad4(s)
    if t == "array":
        return struct.pack("<I", len(v)) + pad4(v)
    if t == "fd":
        return b""
    raise ValueError(t)


def msg(obj, iface, name, *args, kind="request"):
    """One message to object obj: header and arguments (fd arguments: any
    placeholder, they take no bytes)."""
    m = find(iface, name, kind)
    if len(args) != len(m.args):
        raise TypeError(f"{iface}.{name} takes {len(m.args)} arguments")
    body = b"".join(encode_arg(a, v) for a, v in zip(m.args, args))
    return struct.pack("<IHHI", obj, m.opcode, m.fd_count, 12 + len(body)) + body


def vertices(*xyz):
    return struct.pack(f"<{len(xyz)}f", *xyz)


def translate(x, y, z):
    m = list(IDENTITY)
    m[12:15] = [x, y, z]
    return m


def scale(s):
    return [s, 0, 0, 0, 0, s, 0, 0, 0, 0, s, 0, 0, 0, 0, 1]


# ---- session: chunks of raw bytes with fds (fuzz/fuzz_session.c) ----

def fd_desc(kind, size, pattern=b""):
    return struct.pack("<BHB", kind, size, len(pattern)) + pattern


def chunk(data, fds=(), client=0, close=False, no_run=False):
    ctl = len(fds) | (client << 3) | (0x10 if close else 0) | (0x20 if no_run else 0)
    return struct.pack("<BH", ctl, len(data)) + b"".join(fds) + data


AXIS = vertices(0, -0.5, 0, 0, 0.5, 0)
TRIANGLE = vertices(-0.5, -0.5, 0, 0.5, -0.5, 0, 0, 0.5, 0)
SQUARE = vertices(-0.5, -0.5, 0, 0.5, -0.5, 0, 0.5, 0.5, 0, -0.5, 0.5, 0)


def hello(version=VERSION):
    return msg(1, "display", "hello", version)


def scene_v1(mode, data, count, color=0xff8000ff, transform=None, base=2):
    """hello, a sealed memfd buffer, a list drawing it, a layer, commit,
    frame: as one chunk, the memfd with it."""
    buf, lst, lay, cb = base, base + 1, base + 2, base + 3
    reqs = [msg(1, "display", "create_buffer", buf, len(data), 0),
            msg(1, "display", "create_list", lst),
            msg(lst, "list", "set_color", color)]
    if transform:
        reqs.append(msg(lst, "list", "set_transform", transform))
    reqs += [msg(lst, "list", "draw", mode, buf, 0, count, 0),
             msg(1, "display", "create_layer", lay),
             msg(lay, "layer", "set_list", lst),
             msg(1, "display", "frame", cb),
             msg(1, "display", "commit")]
    return b"".join(reqs), fd_desc(MEMFD_SEALED, len(data), data)


def session_seeds():
    s = {}
    s["hello-v1"] = chunk(hello(1))
    s["hello-v2"] = chunk(hello(2))
    s["status-sync"] = chunk(hello() + msg(1, "display", "get_status") + msg(1, "display", "sync", 2))
    for name, mode, data, count, t in (("points", 0, AXIS, 2, None),
                                       ("lines", 1, AXIS, 2, translate(0.25, 0, 0)),
                                       ("triangles", 2, TRIANGLE, 3, scale(0.5))):
        reqs, fd = scene_v1(mode, data, count, transform=t)
        s["scene-" + name] = chunk(hello(1)) + chunk(reqs, [fd])
    reqs, fd = scene_v1(1, AXIS, 2)
    s["scene-split"] = (chunk(hello()) + chunk(reqs[:30], [fd], no_run=True) + chunk(reqs[30:70])
                        + chunk(reqs[70:]))
    s["two-clients"] = (chunk(hello()) + chunk(hello(1), client=1)
                        + chunk(scene_v1(0, AXIS, 2)[0], [scene_v1(0, AXIS, 2)[1]])
                        + chunk(scene_v1(2, TRIANGLE, 3, base=10)[0], [scene_v1(2, TRIANGLE, 3)[1]],
                                client=1, close=True)
                        + chunk(msg(1, "display", "get_status")))
    reqs, fd = scene_v1(0, AXIS, 2)
    s["destroy-shown"] = chunk(hello()) + chunk(reqs, [fd]) + chunk(
        msg(3, "list", "destroy") + msg(2, "buffer", "destroy") + msg(1, "display", "commit")
        + msg(4, "layer", "set_visible", 0) + msg(1, "display", "commit") + msg(4, "layer", "destroy")
        + msg(1, "display", "commit"))
    s["capture"] = chunk(hello()) + chunk(reqs, [fd]) + chunk(msg(1, "display", "capture", 9))
    s["layer-transform"] = chunk(hello()) + chunk(reqs + msg(4, "layer", "set_transform", translate(0, 0.2, 0))
                                                  + msg(1, "display", "commit"), [fd])
    # Version 2: an inline buffer, indices, per-vertex colour, point size,
    # nested transforms, a line strip, priority and exclusive.
    idx = struct.pack("<6H", 0, 1, 2, 0, 2, 3)
    rgba = b"".join(SQUARE[12 * i:12 * i + 12] + bytes([255, 64 * i, 0, 255]) for i in range(4))
    v2 = b"".join([
        hello(2),
        msg(1, "display", "create_buffer_inline", 2, SQUARE),
        msg(1, "display", "create_buffer_inline", 3, idx),
        msg(1, "display", "create_buffer_inline", 4, rgba),
        msg(1, "display", "create_list", 5),
        msg(5, "list", "draw_indexed", 2, 2, 0, 4, 0, 3, 0, 6, 2),
        msg(5, "list", "push"),
        msg(5, "list", "multiply_transform", scale(0.5)),
        msg(5, "list", "set_vertex_format", 1),
        msg(5, "list", "draw", 3, 4, 0, 4, 16),
        msg(5, "list", "pop"),
        msg(5, "list", "set_point_size", 3),
        msg(5, "list", "draw", 0, 2, 0, 4, 0),
        msg(1, "display", "create_layer", 6),
        msg(6, "layer", "set_list", 5),
        msg(6, "layer", "set_priority", 5),
        msg(6, "layer", "set_exclusive", 1),
        msg(1, "display", "frame", 7),
        msg(1, "display", "commit"),
    ])
    s["v2-features"] = chunk(v2)
    # Errors the daemon must answer and survive.
    s["error-no-hello"] = chunk(msg(1, "display", "get_status"))
    s["error-unsealed"] = chunk(hello()) + chunk(msg(1, "display", "create_buffer", 2, 36, 0),
                                                 [fd_desc(MEMFD_UNSEALED, 36, AXIS)])
    s["error-not-memfd"] = chunk(hello()) + chunk(msg(1, "display", "create_buffer", 2, 36, 0),
                                                  [fd_desc(PIPE, 0)])
    s["error-draw-range"] = chunk(hello()) + chunk(
        msg(1, "display", "create_buffer", 2, 24, 0) + msg(1, "display", "create_list", 3)
        + msg(3, "list", "draw", 1, 2, 12, 2, 0), [fd_desc(MEMFD_SEALED, 24, AXIS)])
    s["error-bad-size"] = chunk(hello() + struct.pack("<IHHI", 1, 7, 0, 13))
    s["error-fd-missing"] = chunk(hello() + msg(1, "display", "create_buffer", 2, 36, 0))
    s["error-too-many-fds"] = chunk(hello()) + chunk(b"\0", [fd_desc(DEV_NULL, 0)] * 7, no_run=True) * 5
    s["error-transform"] = chunk(hello() + msg(1, "display", "create_list", 2)
                                 + msg(2, "list", "set_transform", [float("nan")] * 16))
    s["error-mid-message"] = chunk(hello() + msg(1, "display", "create_list", 2)[:10], close=True)
    return s


# ---- lists: requests as ops (fuzz/fuzz_lists.c) ----

(OP_BUFFER, OP_BUFFER_INLINE, OP_LIST, OP_DESTROY, OP_CLEAR, OP_COLOR, OP_TRANSFORM, OP_DRAW,
 OP_DRAW_INDEXED, OP_FORMAT, OP_POINT_SIZE, OP_PUSH, OP_POP, OP_MULTIPLY, OP_LAYER, OP_COMMIT,
 OP_RAW, OP_LAYER_STATE, OP_VOLUME, OP_DRAW_VOLUME, OP_VOLUME_LUT) = range(21)
POLICY_NONE, POLICY_ADMIN, POLICY_ANY = range(3)


def start(version, policy=POLICY_ADMIN):
    """The first byte: version and exclusive policy."""
    return bytes([(version - 1) | policy << 4])


def num(v):
    """fuzz_num()."""
    return bytes([v]) if v < 0x80 else b"\x80" + struct.pack("<I", v)


def num64(v):
    return bytes([v]) if v < 0x80 else b"\x80" + struct.pack("<Q", v)


def oid(i):
    return bytes([i - 2])


def op_buffer(i, data, kind=MEMFD_SEALED, size=None):
    """A memfd of size bytes (default len(data)): data repeated."""
    size = len(data) if size is None else size
    return bytes([OP_BUFFER]) + oid(i) + struct.pack("<BH", kind, size) + num64(0) + bytes([len(data)]) + data


def op_inline(i, data):
    return bytes([OP_BUFFER_INLINE]) + oid(i) + struct.pack("<HB", len(data), len(data)) + data


def op_draw(lst, mode, buf, offset, count, stride=0):
    return bytes([OP_DRAW]) + oid(lst) + num(mode) + oid(buf) + num64(offset) + num(count) + num(stride)


def op_draw_indexed(lst, mode, vb, offset, vcount, stride, ib, ioff, icount, itype):
    return (bytes([OP_DRAW_INDEXED]) + oid(lst) + num(mode) + oid(vb) + num64(offset) + num(vcount) + num(stride)
            + oid(ib) + num64(ioff) + num(icount) + num(itype))


def op_matrix(op, lst, kind, floats=()):
    """Floats in read_float()'s one-byte form: (b - 124) / 16."""
    return bytes([op]) + oid(lst) + bytes([kind]) + bytes(int(f * 16) + 124 for f in floats)


def lists_seeds():
    s = {}
    v2 = start(2, POLICY_ANY)
    v1 = start(1)
    def show(lst):
        """Layer 15 showing list lst, and commit."""
        return bytes([OP_LAYER]) + oid(15) + bytes([lst - 2]) + bytes([OP_COMMIT])
    s["points"] = v1 + op_buffer(2, AXIS) + bytes([OP_LIST]) + oid(3) + op_draw(3, 0, 2, 0, 2) + show(3)
    s["lines-color"] = (v1 + op_buffer(2, AXIS) + bytes([OP_LIST]) + oid(3) + bytes([OP_COLOR]) + oid(3)
                        + struct.pack("<I", 0x00ff00ff) + op_draw(3, 1, 2, 0, 2) + show(3))
    s["triangles-transform"] = (v1 + op_buffer(2, TRIANGLE) + bytes([OP_LIST]) + oid(3)
                                + op_matrix(OP_TRANSFORM, 3, 1, (0.25, 0, 0))
                                + op_draw(3, 2, 2, 0, 3) + show(3))
    s["stride-offset"] = (v1 + op_buffer(2, b"\0" * 4 + SQUARE) + bytes([OP_LIST]) + oid(3)
                          + op_draw(3, 0, 2, 4, 2, 24) + bytes([OP_CLEAR]) + oid(3) + op_draw(3, 1, 2, 4, 4, 12)
                          + show(3))
    s["destroy"] = (v1 + op_buffer(2, AXIS) + bytes([OP_LIST]) + oid(3) + op_draw(3, 1, 2, 0, 2) + show(3)
                    + bytes([OP_DESTROY]) + oid(3) + bytes([OP_DESTROY]) + oid(2) + bytes([OP_COMMIT])
                    + bytes([OP_DESTROY]) + oid(15) + bytes([OP_COMMIT]))
    idx16 = struct.pack("<6H", 0, 1, 2, 0, 2, 3)
    idx32 = struct.pack("<4I", 0, 1, 2, 3)
    s["v2-indexed"] = (v2 + op_inline(2, SQUARE) + op_inline(3, idx16) + op_buffer(4, idx32)
                       + bytes([OP_LIST]) + oid(5) + op_draw_indexed(5, 2, 2, 0, 4, 0, 3, 0, 6, 2)
                       + op_draw_indexed(5, 3, 2, 0, 4, 12, 4, 0, 4, 4) + show(5))
    rgba = b"".join(SQUARE[12 * i:12 * i + 12] + bytes([255, 64 * i, 0, 255]) for i in range(4))
    rgbaf = b"".join(SQUARE[12 * i:12 * i + 12] + struct.pack("<4f", 1, i / 4, 0, 1) for i in range(4))
    s["v2-formats"] = (v2 + op_inline(2, rgba) + op_inline(3, rgbaf) + bytes([OP_LIST]) + oid(4)
                       + bytes([OP_FORMAT]) + oid(4) + num(1) + op_draw(4, 1, 2, 0, 4)
                       + bytes([OP_FORMAT]) + oid(4) + num(2) + op_draw(4, 3, 3, 0, 4)
                       + bytes([OP_FORMAT]) + oid(4) + num(0) + op_draw(4, 0, 2, 0, 4, 16))
    s["v2-stack"] = (v2 + op_inline(2, AXIS) + bytes([OP_LIST]) + oid(3) + bytes([OP_PUSH]) + oid(3)
                     + op_matrix(OP_MULTIPLY, 3, 2, (0.5, 0.5, 0.5)) + bytes([OP_POINT_SIZE]) + oid(3) + num(4)
                     + op_draw(3, 0, 2, 0, 2) + bytes([OP_POP]) + oid(3) + op_draw(3, 1, 2, 0, 2)
                     + bytes([OP_POP]) + oid(3))
    def layer(y, lst, *state):
        """Layer y showing list lst, then (what, value bytes) pairs."""
        out = bytes([OP_LAYER]) + oid(y) + bytes([lst - 2])
        for what, value in state:
            out += bytes([OP_LAYER_STATE]) + oid(y) + bytes([what]) + value
        return out
    s["v2-layers"] = (v2 + op_inline(2, TRIANGLE) + bytes([OP_LIST]) + oid(3) + op_draw(3, 2, 2, 0, 3)
                      + layer(4, 3, (2, num(0xfffffff6))) + layer(5, 3, (2, num(7)), (1, bytes([1, 130, 124, 124])))
                      + layer(6, 3, (3, num(1))) + bytes([OP_COMMIT])
                      + bytes([OP_LAYER_STATE]) + oid(6) + bytes([0]) + num(0) + bytes([OP_COMMIT]))
    s["v2-exclusive-denied"] = (start(2, POLICY_NONE) + op_inline(2, AXIS) + bytes([OP_LIST]) + oid(3)
                                + op_draw(3, 0, 2, 0, 2) + layer(4, 3, (3, num(1))) + bytes([OP_COMMIT]))
    # 1500 points shown by two layers: over max-primitives (2048), refused.
    s["v2-refused"] = (v2 + op_buffer(2, AXIS, size=18000) + bytes([OP_LIST]) + oid(3) + op_draw(3, 0, 2, 0, 1500)
                       + layer(4, 3) + layer(5, 3) + bytes([OP_COMMIT]) + bytes([OP_DESTROY]) + oid(5)
                       + bytes([OP_COMMIT]))
    # 3000 vertices (1500 lines) committed, cleared, 3000 more drawn: the
    # list holds 6000, within max-vertices (4096), which counts the
    # pending state, and under twice it.
    s["quota-held-twice"] = (v1 + op_buffer(2, AXIS, size=36000) + bytes([OP_LIST]) + oid(3)
                             + op_draw(3, 1, 2, 0, 3000) + layer(4, 3) + bytes([OP_COMMIT])
                             + bytes([OP_CLEAR]) + oid(3) + op_draw(3, 1, 2, 0, 2990, 12))
    # Draws of nothing from empty buffers (the daemon computed map + 0 with
    # map NULL: undefined behaviour clang's UBSan reports; fixed).
    s["draw-empty-buffer"] = v1 + op_buffer(2, b"") + bytes([OP_LIST]) + oid(3) + op_draw(3, 0, 2, 0, 0)
    s["draw-indexed-empty-buffer"] = (v2 + op_inline(2, AXIS) + op_buffer(3, b"") + bytes([OP_LIST]) + oid(4)
                                      + op_draw_indexed(4, 0, 2, 0, 2, 0, 3, 0, 0, 2))
    # A vertex that the transform takes past the float range (finite in
    # double): the renderer's slot lookup divided inf by inf and cast the
    # NaN to an index (clang's UBSan: float-cast-overflow in slot_of();
    # fixed).
    huge = vertices(3e38, 0, 3e38, 0.5, 0, 0, 0, 0.5, 0)
    s["huge-vertex"] = (v2 + op_inline(2, huge) + bytes([OP_LIST]) + oid(3)
                        + op_matrix(OP_TRANSFORM, 3, 2, (2, 2, 2)) + op_draw(3, 2, 2, 0, 3) + show(3))
    s["error-quota"] = v1 + op_buffer(2, AXIS) + bytes([OP_LIST]) + oid(3) + op_draw(3, 0, 2, 0, 2, 1)
    s["error-raw"] = v1 + bytes([OP_LIST]) + oid(3) + bytes([OP_RAW, 3, 9, 4, 1, 2, 3, 4])
    # Volumes (protocol 6): a 4x4x4 uint8 volume from an inline buffer,
    # drawn through a two-entry table and shown, then destroyed while
    # shown; floats are read_float() bytes ((b - 124) / 16).
    v6 = start(6, POLICY_ANY)

    def fl(x):
        return bytes([int(round(x * 16)) + 124])
    ramp = bytes(range(0, 256, 4))
    volume = bytes([OP_VOLUME]) + oid(3) + oid(2) + num64(0) + num(1) + bytes([4, 4, 4]) + fl(0.25) * 3
    draw = (bytes([OP_DRAW_VOLUME]) + oid(4) + oid(3) + num(1) + fl(1) + fl(4) + fl(7))
    lut = bytes([OP_VOLUME_LUT]) + oid(4) + oid(5) + num64(0) + num(2)
    s["v6-volume"] = (v6 + op_inline(2, ramp) + volume + op_inline(5, bytes([255, 0, 0, 255, 0, 255, 0, 128]))
                      + bytes([OP_LIST]) + oid(4) + draw + lut + draw + layer(6, 4) + bytes([OP_COMMIT])
                      + bytes([OP_DESTROY]) + oid(3) + bytes([OP_COMMIT]))
    s["v6-volume-errors"] = (v6 + op_inline(2, ramp) + bytes([OP_VOLUME]) + oid(3) + oid(2) + num64(1) + num(1)
                             + bytes([4, 4, 4]) + fl(0.25) * 3)
    return s


# ---- framing: chunks of bytes and fds (fuzz/fuzz_framing.c) ----

def routes():
    """(iface, kind) in the order of fuzz/gen_echo.py's routes."""
    out = []
    for i in IFACES:
        if i.requests:
            out.append((i.name, "request"))
        if i.events:
            out.append((i.name, "event"))
    return out


SAMPLE = {"uint": 7, "int": -3, "uint64": 1 << 40, "float": 0.5, "object": 5, "new_id": 9,
          "matrix": IDENTITY, "string": "spindle", "array": b"\x01\x02\x03\x04\x05", "fd": 0}


def framing_chunk(data, nfds=0, kind=0, no_read=False):
    return struct.pack("<BH", nfds | (kind << 5) | (0x80 if no_read else 0), len(data)) + data


def framing_seeds():
    s = {}
    rs = routes()
    for r, (iface, kind) in enumerate(rs):
        obj = r + len(rs)  # object % routes picks the route
        msgs = BY_NAME[iface].requests if kind == "request" else BY_NAME[iface].events
        data, nfds = b"", 0
        for m in msgs:
            data += msg(obj, iface, m.name, *[SAMPLE[a.type] for a in m.args], kind=kind)
            nfds += m.fd_count
        s[f"{iface}-{kind}s"] = bytes([VERSION - 1]) + framing_chunk(data, nfds)
    hello_msg = msg(len(rs), "display", "hello", VERSION)
    s["split"] = bytes([0]) + framing_chunk(hello_msg[:5], no_read=True) + framing_chunk(hello_msg[5:])
    # The fd with the first bytes of its message, the rest after (fds
    # travel with a chunk's first byte: a chunk of no bytes passes none).
    create = msg(len(rs), "display", "create_buffer", 2, 64, 0)
    s["fd-ahead"] = bytes([0]) + framing_chunk(create[:4], 1, no_read=True) + framing_chunk(create[4:])
    s["fd-queue-full"] = bytes([0]) + framing_chunk(create[:4], 20, no_read=True) + framing_chunk(create[4:8], 20)
    s["too-many-fds"] = bytes([0]) + framing_chunk(b"\0" * 4, 29)
    s["partial-at-end"] = bytes([0]) + framing_chunk(hello_msg[:8])
    # An error event whose string's padding is not zero: decodes, and
    # comes back from the writer with the padding zeroed.
    err = find("display", "error", "event").opcode
    s["padding"] = bytes([1]) + framing_chunk(struct.pack("<IHHIIII", 1 + len(rs), err, 0, 28, 1, 3, 3)
                                              + b"ab\0\xff")
    return s


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, "corpus")
    for target, seeds in (("framing", framing_seeds()), ("lists", lists_seeds()), ("session", session_seeds())):
        d = os.path.join(out, target)
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)
        for name, data in sorted(seeds.items()):
            with open(os.path.join(d, name), "wb") as f:
                f.write(data)


if __name__ == "__main__":
    main()
