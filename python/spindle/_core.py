"""The connection and its objects: Connection, Buffer, List, Layer, Volume, FrameRequest."""
import contextlib
import ctypes
import errno
import logging
import os
import select
import time
import weakref

import numpy as np

from . import _lib
from .capture import Capture
from .errors import (CaptureError, CommitRefused, ConnectionLost, Error, NotConnected, NotSupported, ProtocolError,
                     Timeout)
from .protocol_errors import ERRORS, REFUSALS, RefusedDenied, RefusedOutOfRange
from .transform import from_column_major, identity, to_column_major
from .types import (Calibration, CalibrationKey, DeviceInfo, Frame, IndexType, Mode, Refusal, Sampling, State,
                    Status, VertexFormat, VolumeType)

_log = logging.getLogger('spindle')

#: The most bytes a buffer sent inline may hold (SPINDLE_INLINE_MAX).
INLINE_MAX = 65516

#: The most samples along each axis of a volume, and in all (docs/volumes.md).
VOLUME_MAX_SIZE = 4096
VOLUME_MAX_SAMPLES = 2**31
#: The most entries of a volume's lookup table (at least 2).
VOLUME_MAX_LUT = 4096


def load_library(path=None):
    """Loads libspindle from path (a file, or a folder holding
    libspindle.so.0), else from ``$SPINDLE_LIBRARY``, else the soname
    libspindle.so.0 through the dynamic linker's search path. Connecting
    loads it too; call this first only to pick another library. Returns the
    path loaded. Raises :class:`~spindle.LibraryError`."""
    _lib.load(path)
    return _lib.loaded_path()


def library_version():
    """The version of the libspindle loaded ("MAJOR.MINOR.MICRO"), or None for
    a library older than 0.2 that cannot tell."""
    lib = _lib.load()
    if not hasattr(lib, 'spindle_library_version') or lib.spindle_library_version.restype is not ctypes.c_char_p:
        return None
    return lib.spindle_library_version().decode()


def connect(socket=None, *, version=None, library=None):
    """Connects to spindled and returns a :class:`Connection`, to use as a
    context manager (``with spindle.connect() as sp:``) or to close().

    socket: the daemon's socket path; None means ``$SPINDLE_SOCKET``, else
    /run/spindle/spindle.sock. version: the highest protocol version to
    offer (1 .. the library's; None: the newest), for testing how older
    clients are served. library: see :func:`load_library`.

    Raises :class:`~spindle.NotConnected` when no daemon answers there or it
    speaks no common version, :class:`~spindle.LibraryError` when libspindle
    cannot be loaded."""
    return Connection(socket, version=version, library=library)


# ---- argument conversion ----


def _vertices(vertices, what='vertices'):
    """An N x 3 contiguous float32 array of vertices given as anything numpy
    reads: (N, 3), (..., 3) (flattened to (N, 3)) or one point of 3."""
    try:
        a = np.asarray(vertices)
    except (TypeError, ValueError) as e:
        raise TypeError(f'{what}: not an array of numbers: {e}') from None
    if a.dtype == object or not (np.issubdtype(a.dtype, np.number) or a.dtype == np.bool_):
        raise TypeError(f'{what}: expected numbers, not an array of {a.dtype}')
    if np.issubdtype(a.dtype, np.complexfloating):
        raise TypeError(f'{what}: complex numbers')
    if a.ndim == 1 and a.shape[0] == 3:
        a = a.reshape(1, 3)
    if a.ndim < 2 or a.shape[-1] != 3:
        raise ValueError(f'{what}: expected an N x 3 array of x, y, z, not shape {a.shape}')
    return np.ascontiguousarray(a.reshape(-1, 3), dtype=np.float32)


def _color_array(colors, what='colors'):
    """(array of K x 4, format) of colours given as K x 3 or K x 4 (or one
    colour of 3 or 4): floats in 0..1 (XYZ_RGBA_FLOAT) or integers in 0..255
    (XYZ_RGBA8). Alpha defaults to opaque."""
    try:
        a = np.asarray(colors)
    except (TypeError, ValueError) as e:
        raise TypeError(f'{what}: not an array of numbers: {e}') from None
    if a.ndim == 1:
        a = a.reshape(1, -1)
    if a.ndim != 2 or a.shape[1] not in (3, 4):
        raise ValueError(f'{what}: expected a K x 3 (RGB) or K x 4 (RGBA) array, not shape {a.shape}')
    if np.issubdtype(a.dtype, np.floating):
        c = np.ones((a.shape[0], 4), dtype=np.float32)
        c[:, :a.shape[1]] = a
        return c, VertexFormat.XYZ_RGBA_FLOAT
    if np.issubdtype(a.dtype, np.integer) or a.dtype == np.bool_:
        if a.size and (a.min() < 0 or a.max() > 255):
            raise ValueError(f'{what}: integer colours are 0 to 255 (floats 0 to 1), not {a.min()} .. {a.max()}')
        c = np.full((a.shape[0], 4), 255, dtype=np.uint8)
        c[:, :a.shape[1]] = a
        return c, VertexFormat.XYZ_RGBA8
    raise TypeError(f'{what}: expected numbers, not an array of {a.dtype}')


def _interleave(xyz, colors, fmt):
    """The vertices of format fmt, as a structured array."""
    if fmt == VertexFormat.XYZ:
        return xyz
    ctype = np.uint8 if fmt == VertexFormat.XYZ_RGBA8 else np.float32
    out = np.empty(len(xyz), dtype=[('xyz', np.float32, 3), ('rgba', ctype, 4)])
    assert out.dtype.itemsize == fmt.size
    out['xyz'] = xyz
    out['rgba'] = colors
    return out


def _rgba(args, what='color'):
    """(r, g, b, a) bytes of a colour: set_color(r, g, b[, a]), a sequence
    of 3 or 4, or '#rrggbb[aa]'. Any float among them: all are 0..1."""
    if len(args) == 1:
        c = args[0]
        if isinstance(c, str):
            s = c[1:] if c.startswith('#') else c
            if len(s) not in (6, 8) or any(ch not in '0123456789abcdefABCDEF' for ch in s):
                raise ValueError(f'{what}: {c!r} is not #rrggbb or #rrggbbaa')
            v = [int(s[i:i + 2], 16) for i in range(0, len(s), 2)]
            return tuple(v) + (255, ) * (4 - len(v))
        args = tuple(np.asarray(c).reshape(-1).tolist()) if not isinstance(c, (int, float)) else (c, )
    if len(args) not in (3, 4):
        raise TypeError(f'{what}: expected r, g, b[, a], a sequence of 3 or 4, or "#rrggbb", not {len(args)} values')
    if any(isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) for v in args):
        raise TypeError(f'{what}: the channels are numbers: {args!r}')
    if any(isinstance(v, (float, np.floating)) for v in args):
        if any(not 0 <= v <= 1 for v in args):
            raise ValueError(f'{what}: float channels are 0 to 1 (integers 0 to 255): {args!r}')
        v = [int(round(float(x) * 255)) for x in args]
    else:
        v = [int(x) for x in args]
        if any(not 0 <= x <= 255 for x in v):
            raise ValueError(f'{what}: integer channels are 0 to 255 (floats 0 to 1): {args!r}')
    return tuple(v) + (255, ) * (4 - len(v))


def _uint(value, what, top=0xffffffff):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f'{what}: an integer, not {type(value).__name__}')
    if not 0 <= value <= top:
        raise ValueError(f'{what}: {value} is not 0 to {top}')
    return int(value)


_PER_PRIMITIVE = {Mode.POINTS: 1, Mode.LINES: 2, Mode.TRIANGLES: 3}

# (dtype kind, itemsize): the volume type of samples of that dtype (either byte order).
_VOLUME_TYPES = {
    ('u', 1): VolumeType.U8,
    ('u', 2): VolumeType.U16,
    ('i', 2): VolumeType.I16,
    ('f', 4): VolumeType.F32
}


def _volume_samples(samples):
    """(VolumeType, (nx, ny, nz), the samples as a C-contiguous
    little-endian array) of a volume given as a 3-D array [z, y, x] of
    uint8, uint16, int16 or float32, or a 4-D uint8 array [z, y, x, 4]
    (RGBA8)."""
    try:
        a = np.asarray(samples)
    except (TypeError, ValueError) as e:
        raise TypeError(f'volume: not an array of samples: {e}') from None
    vtype = _VOLUME_TYPES.get((a.dtype.kind, a.dtype.itemsize))
    if vtype is None or a.dtype.fields is not None:
        raise TypeError(f'volume: samples of uint8, uint16, int16 or float32 (or uint8 RGBA), not {a.dtype}: convert '
                        'them with astype()')
    if a.ndim == 4:
        if vtype != VolumeType.U8 or a.shape[3] != 4:
            raise ValueError(f'volume: a 4-D array is RGBA, uint8 [z, y, x, 4], not {a.dtype} of shape {a.shape}')
        vtype = VolumeType.RGBA8
    elif a.ndim != 3:
        raise ValueError(f'volume: expected a 3-D array [z, y, x] (or uint8 [z, y, x, 4] for RGBA), '
                         f'not shape {a.shape}')
    nz, ny, nx = (int(n) for n in a.shape[:3])
    for n, axis in ((nx, 'x'), (ny, 'y'), (nz, 'z')):
        if not 1 <= n <= VOLUME_MAX_SIZE:
            raise ValueError(f'volume: {n} samples along {axis} (1 to {VOLUME_MAX_SIZE}), shape {a.shape}')
    if nx * ny * nz > VOLUME_MAX_SAMPLES:
        raise ValueError(f'volume: {nx * ny * nz} samples (at most 2^31), shape {a.shape}')
    return vtype, (nx, ny, nz), np.ascontiguousarray(a, dtype=a.dtype.newbyteorder('<'))


def _volume_spacing(spacing):
    """The spacing (sx, sy, sz) as 3 float32, finite and above 0: 3 numbers or one for all."""
    try:
        s = np.asarray(spacing, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f'spacing: 3 numbers (x, y, z), not {spacing!r}') from None
    if s.ndim == 0:
        s = np.repeat(s, 3)
    if s.shape != (3, ):
        raise ValueError(f'spacing: 3 numbers (x, y, z) or one for all, not shape {s.shape}')
    with np.errstate(over='ignore'):
        f = s.astype(np.float32)
    if not (np.all(np.isfinite(f)) and np.all(f > 0)):
        raise ValueError(f'spacing: finite and above 0, not {s.tolist()}')
    return f


def _float32(value, what):
    """value as a finite float32 (a Python float)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f'{what}: a number, not {type(value).__name__}')
    with np.errstate(over='ignore'):
        f = np.float32(value)
    if not np.isfinite(f):
        raise ValueError(f'{what}: {value} is not a finite float32')
    return float(f)


#: The window of each volume type when draw_volume is given none: its whole range (0..1 for float32).
_DEFAULT_WINDOW = {
    VolumeType.U8: (127.5, 255.0),
    VolumeType.U16: (32767.5, 65535.0),
    VolumeType.I16: (-0.5, 65535.0),
    VolumeType.F32: (0.5, 1.0),
    VolumeType.RGBA8: (127.5, 255.0),
}


def _window(window, vtype):
    """(center, width, low end) of a draw_volume window, as the daemon computes them in float32."""
    if window is None:
        window = _DEFAULT_WINDOW[vtype]
    try:
        center, width = window
    except (TypeError, ValueError):
        raise TypeError(f'window: (center, width), not {window!r}') from None
    center, width = _float32(center, 'window center'), _float32(width, 'window width')
    if not width > 0:
        raise ValueError(f'window: the width is above 0, not {width}')
    c, half = np.float32(center), np.float32(width) / np.float32(2)
    lo, hi = c - half, c + half
    if not hi > lo:
        raise ValueError(f'window: {center}/{width} is empty at float32 precision')
    return center, width, float(lo)


def _lut(colors):
    """A lookup table as an N x 4 uint8 array (N = 0: none): K x 3 or K x 4
    colours, integers 0..255 or floats 0..1."""
    if colors is None:
        return np.zeros((0, 4), dtype=np.uint8)
    try:
        a = np.asarray(colors)
    except (TypeError, ValueError) as e:
        raise TypeError(f'lookup table: not an array of colours: {e}') from None
    if a.size == 0 and a.ndim <= 2:
        return np.zeros((0, 4), dtype=np.uint8)
    if a.ndim != 2 and not (a.ndim == 1 and a.shape[0] in (3, 4)):
        raise ValueError(f'lookup table: expected an N x 4 (RGBA) or N x 3 (RGB) array, not shape {a.shape}')
    c, fmt = _color_array(a, 'lookup table')
    if fmt == VertexFormat.XYZ_RGBA_FLOAT:
        if not np.all((c >= 0) & (c <= 1)):
            raise ValueError('lookup table: float colours are 0 to 1 (integers 0 to 255)')
        c = np.round(c * 255).astype(np.uint8)
    if not 2 <= len(c) <= VOLUME_MAX_LUT:
        raise ValueError(f'lookup table: {len(c)} entries (2 to {VOLUME_MAX_LUT}; None or an empty table: the '
                         'list\'s colour again)')
    return np.ascontiguousarray(c, dtype=np.uint8)


def _check_count(mode, count):
    if mode == Mode.LINES and count % 2:
        raise ValueError(f'lines: {count} vertices do not make whole segments (2 each)')
    if mode == Mode.TRIANGLES and count % 3:
        raise ValueError(f'triangles: {count} vertices do not make whole triangles (3 each)')


class _Object:
    """What Buffer, List and Layer share: the handle and the connection."""
    _destroy_fn = None
    _kind = 'object'

    def __init__(self, conn, handle):
        self._conn = conn
        self._handle = handle
        conn._objects.add(self)

    @property
    def connection(self):
        """The :class:`Connection` this object belongs to."""
        return self._conn

    @property
    def destroyed(self):
        """True once destroyed, or once its connection was closed."""
        return self._handle is None

    def _h(self):
        self._conn._enter()
        if self._handle is None:
            raise NotConnected(f'this {self._kind} was destroyed')
        return self._handle

    def destroy(self):
        """Destroys the object (the daemon forgets it). Its handle is freed at
        once; doing it twice, or after the connection was closed, does
        nothing."""
        h, self._handle = self._handle, None
        if h is not None and self._conn._sp is not None:
            getattr(self._conn._lib, self._destroy_fn)(h)
            self._conn._objects.discard(self)
            self._conn._forget(self)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.destroy()

    def _collect(self):
        """Garbage collected: destroyed at the connection's next call."""
        h, self._handle = self._handle, None
        conn = getattr(self, '_conn', None)
        if h is not None and conn is not None and conn._sp is not None:
            conn._graveyard.append((self._destroy_fn, h))

    def _call(self, name, *args, what=None):
        h = self._h()
        return self._conn._check(getattr(self._conn._lib, name)(h, *args), what or name)


class Buffer(_Object):
    """A buffer of vertex or index data in the daemon
    (:meth:`Connection.create_buffer`, :meth:`Connection.create_index_buffer`,
    :meth:`Connection.create_raw_buffer`, :meth:`Connection.create_buffer_from_fd`).

    Attributes: ``size`` (bytes), ``format`` (the :class:`VertexFormat` of
    its vertices, None for raw and index data), ``count`` (vertices or
    indices it holds, None for raw data), ``index_type`` (:class:`IndexType`
    of an index buffer, else None).

    Lists keep their own copy of what they drew from a buffer: destroy it
    (destroy(), a ``with`` block, or dropping every reference to it) as soon
    as it is not drawn from any more.
    """
    _destroy_fn = 'spindle_buffer_destroy'
    _kind = 'buffer'

    def __init__(self, conn, handle, size, format=None, count=None, index_type=None):
        super().__init__(conn, handle)
        self.size = size
        self.format = format
        self.count = count
        self.index_type = index_type

    def __del__(self):
        self._collect()

    def __repr__(self):
        what = (f'{self.count} vertices {self.format.name}' if self.format is not None else
                f'{self.count} indices {self.index_type.name}' if self.index_type is not None else 'raw')
        return f'<spindle.Buffer {self.size} bytes, {what}{", destroyed" if self.destroyed else ""}>'


class List(_Object):
    """A display list: a retained stream of drawing commands
    (:meth:`Connection.create_list`). Commands append; :meth:`clear` empties
    it. Changes show at the next commit. Every method returns the list, so
    calls chain: ``lst.clear().set_color('#ff8000').triangles(v)``.

    The state that applies to the draws that follow: colour
    (:meth:`set_color`, default opaque white), transform
    (:meth:`set_transform`, :meth:`multiply_transform`, default identity),
    point size (:meth:`set_point_size`, default 1) and vertex format (set
    by the draws themselves from their buffer's format, or
    :meth:`set_vertex_format`); :meth:`push` and :meth:`pop` save and
    restore it (16 deep).

    Draws take vertices as an N x 3 array (float32, converted when it is
    not; anything numpy reads) or a :class:`Buffer`, and colours per vertex
    or per primitive as a K x 3 or K x 4 array (floats 0..1 or integers
    0..255). An array is sent in a buffer made for the draw and destroyed
    right after it.

    Volumes (protocol version 6): :meth:`draw_volume` draws a
    :class:`Volume`, through the lookup table of :meth:`set_volume_lut` if
    one is set; the list holds on to the volumes it draws until
    :meth:`clear`.

    Dropping every reference to a list that no layer shows destroys it;
    :meth:`destroy` does it at once.
    """
    _destroy_fn = 'spindle_list_destroy'
    _kind = 'list'

    def __init__(self, conn, handle):
        super().__init__(conn, handle)
        self._format = VertexFormat.XYZ
        self._stack = []
        self._volumes = set()  # drawn: alive while the list draws them

    def __del__(self):
        self._collect()

    def __repr__(self):
        return f'<spindle.List{" destroyed" if self.destroyed else ""}>'

    def clear(self):
        """Empties the list and resets its state (colour, transform, point size, vertex format, stack)."""
        self._call('spindle_list_clear')
        self._format = VertexFormat.XYZ
        self._stack = []
        self._volumes = set()
        return self

    def set_color(self, *color):
        """Colour of the primitives that follow (without a colour per vertex):
        ``set_color(r, g, b[, a])``, a sequence of 3 or 4, or ``'#rrggbb[aa]'``.
        Integers are 0..255; if any channel is a float, all are 0..1. The
        display emits light: alpha scales intensity."""
        r, g, b, a = _rgba(color)
        self._call('spindle_list_set_color', r, g, b, a)
        return self

    def set_transform(self, matrix):
        """Transform of the primitives that follow (model to layer space): a
        4x4 matrix (``spindle.transform``), or 16 numbers in column-major
        order. The daemon refuses one that is not finite and affine
        (InvalidValueError)."""
        m = to_column_major(matrix)
        self._call('spindle_list_set_transform', m.ctypes.data_as(ctypes.POINTER(ctypes.c_float)))
        return self

    def multiply_transform(self, matrix):
        """Post-multiplies the current transform by matrix (it applies to the
        model first): ``current @ matrix``. Protocol version 2."""
        m = to_column_major(matrix)
        self._call('spindle_list_multiply_transform', m.ctypes.data_as(ctypes.POINTER(ctypes.c_float)))
        return self

    def set_point_size(self, size):
        """Size of the points that follow, 1 to 16 pixels square (the daemon
        refuses other sizes: InvalidValueError). Protocol version 2."""
        self._call('spindle_list_set_point_size', _uint(size, 'point size'))
        return self

    def set_vertex_format(self, format):
        """Layout of the vertices of the draws that follow (a
        :class:`VertexFormat`). Draws from a buffer that knows its format set
        it themselves; this is for raw buffers. Protocol version 2."""
        fmt = VertexFormat(format)
        self._call('spindle_list_set_vertex_format', int(fmt))
        self._format = fmt
        return self

    def push(self):
        """Saves the transform, colour, point size and vertex format (16 deep). Protocol version 2."""
        self._call('spindle_list_push')
        self._stack.append(self._format)
        return self

    def pop(self):
        """Restores what the last push() saved (the daemon refuses a pop
        without a push: InvalidValueError). Protocol version 2."""
        self._call('spindle_list_pop')
        if self._stack:
            self._format = self._stack.pop()
        return self

    @contextlib.contextmanager
    def pushed(self):
        """``with lst.pushed():`` push() on entry, pop() on exit."""
        self.push()
        try:
            yield self
        finally:
            if self._conn._sp is not None and self._handle is not None and self._conn.error is None:
                self.pop()

    def _use_format(self, fmt):
        if fmt is not None and fmt != self._format:
            self.set_vertex_format(fmt)

    def _vertex_source(self, mode, vertices, colors, offset, count, stride, indexed=False):
        """(buffer, temporary, offset, count, stride) for a draw."""
        if isinstance(vertices, Buffer):
            if colors is not None:
                raise ValueError('colors come with the vertices: create_buffer(vertices, colors)')
            if vertices._conn is not self._conn:
                raise ValueError('the buffer belongs to another connection')
            if vertices.index_type is not None:
                raise ValueError('an index buffer holds no vertices: pass it as the indices of draw_indexed()')
            fmt = vertices.format if vertices.format is not None else self._format
            vsize = fmt.size
            stride = _uint(stride, 'stride', 65536)
            offset = _uint(offset, 'offset', 2**64 - 1)
            if count is None:
                if vertices.format is not None and offset == 0 and stride in (0, vsize):
                    count = vertices.count
                else:
                    room = vertices.size - offset
                    step = stride or vsize
                    count = 0 if room < vsize else (room - vsize) // step + 1
            self._use_format(vertices.format)
            return vertices, False, offset, _uint(count, 'count'), stride
        if offset or stride or count is not None:
            raise ValueError('offset, count and stride apply to a Buffer, not to an array')
        xyz = _vertices(vertices)
        n = len(xyz)
        fmt = VertexFormat.XYZ
        c = None
        if colors is not None:
            c, fmt = _color_array(colors)
            per = _PER_PRIMITIVE.get(mode, 0) if not indexed else 0
            if len(c) == 1:
                c = np.repeat(c, n, axis=0)
            elif len(c) != n:
                if per > 1 and n % per == 0 and len(c) == n // per:
                    c = np.repeat(c, per, axis=0)
                else:
                    prims = f' or one per primitive ({n // per})' if per > 1 else ''
                    raise ValueError(f'colors: {len(c)} colours for {n} vertices: give one per vertex{prims}')
        if not indexed:
            _check_count(mode, n)
        buf = self._conn.create_buffer(xyz, None) if c is None else self._conn._vertex_buffer(
            _interleave(xyz, c, fmt), fmt, n)
        self._use_format(fmt)
        return buf, True, 0, n, 0

    def draw(self, mode, vertices, colors=None, *, offset=0, count=None, stride=0):
        """Draws vertices in a :class:`Mode`. vertices: an N x 3 array, or a
        :class:`Buffer` (then offset in bytes, count vertices, default all
        from offset, stride in bytes, 0 = tightly packed). colors: one per
        vertex, or (lines, triangles) one per primitive, or one for all;
        None: the list's colour (or the buffer's own colours)."""
        mode = Mode(mode)
        buf, temp, offset, count, stride = self._vertex_source(mode, vertices, colors, offset, count, stride)
        try:
            _check_count(mode, count)
            self._call('spindle_list_draw', int(mode), buf._h(), offset, count, stride, what=f'draw {mode.name}')
        finally:
            if temp:
                buf.destroy()
        return self

    def points(self, vertices, colors=None, **kw):
        """Draws each vertex as a point (:meth:`draw` with Mode.POINTS); see
        :meth:`set_point_size`."""
        return self.draw(Mode.POINTS, vertices, colors, **kw)

    def lines(self, vertices, colors=None, **kw):
        """Draws segments between vertices 2i and 2i+1 (N x 3, or M x 2 x 3); colours per vertex or per segment."""
        return self.draw(Mode.LINES, vertices, colors, **kw)

    def line_strip(self, vertices, colors=None, **kw):
        """Joins vertex i to vertex i+1 for every i; colours per vertex. Protocol version 2."""
        return self.draw(Mode.LINE_STRIP, vertices, colors, **kw)

    def triangles(self, vertices, colors=None, **kw):
        """Draws triangles of vertices 3i .. 3i+2 (N x 3, or M x 3 x 3);
        colours per vertex (interpolated across the triangle) or per
        triangle."""
        return self.draw(Mode.TRIANGLES, vertices, colors, **kw)

    def draw_indexed(self, mode, vertices, indices, colors=None, *, offset=0, vertex_count=None, stride=0,
                     index_offset=0, index_count=None, index_type=None):
        """Draws the vertices that indices pick, in a :class:`Mode`.
        Protocol version 2.

        vertices: an N x 3 array (colors: one per vertex, or one for all), or
        a :class:`Buffer` (offset in bytes, vertex_count, stride as in
        :meth:`draw`). indices: an array of integers below the vertex count
        (any shape, flattened: M x 3 triangles work), or an index
        :class:`Buffer` (index_offset in bytes, index_count; index_type for
        a raw buffer)."""
        mode = Mode(mode)
        vbuf, vtemp, offset, vcount, stride = self._vertex_source(mode, vertices, colors, offset, vertex_count,
                                                                  stride, indexed=True)
        ibuf = None
        try:
            if isinstance(indices, Buffer):
                if indices._conn is not self._conn:
                    raise ValueError('the index buffer belongs to another connection')
                itype = IndexType(index_type if index_type is not None else indices.index_type or IndexType.U32)
                index_offset = _uint(index_offset, 'index_offset', 2**64 - 1)
                if index_count is None:
                    index_count = (indices.size - index_offset) // itype
                ibuf, itemp = indices, False
            else:
                if index_offset or index_count is not None:
                    raise ValueError('index_offset and index_count apply to a Buffer, not to an array')
                ibuf = self._conn.create_index_buffer(indices, vertex_count=vcount, type=index_type)
                itype, index_count, itemp = ibuf.index_type, ibuf.count, True
            index_count = _uint(index_count, 'index_count')
            _check_count(mode, index_count)
            self._call('spindle_list_draw_indexed', int(mode), vbuf._h(), offset, vcount, stride, ibuf._h(),
                       index_offset, index_count, int(itype), what=f'draw_indexed {mode.name}')
        finally:
            if vtemp:
                vbuf.destroy()
            if ibuf is not None and itemp:
                ibuf.destroy()
        return self

    def mesh(self, vertices, triangles, colors=None):
        """Draws an indexed triangle mesh: vertices N x 3, triangles M x 3
        indices into them, colors one per vertex (or one for all).
        Protocol version 2."""
        return self.draw_indexed(Mode.TRIANGLES, vertices, triangles, colors)

    def destroy(self):
        """Destroys the list (the daemon forgets it; layers showing it show
        nothing). Doing it twice, or after the connection was closed, does
        nothing."""
        self._volumes = set()
        super().destroy()

    def draw_volume(self, volume, sampling='trilinear', threshold=None, window=None):
        """Draws a :class:`Volume` (:meth:`Connection.volume`) with the
        list's transform (from the volume's model units: its box is
        ``(0, 0, 0)`` to ``volume.extent``, y up) and colour. Protocol
        version 6.

        Every pixel whose centre lies in the volume's box shows the sample
        there, read by sampling: ``'trilinear'`` (the default: smooth) or
        ``'nearest'`` (blocks), or a :class:`Sampling`. A sample below
        threshold (for RGBA8: an alpha below it), or NaN, is dark; the
        others are mapped through window, (center, width): the fraction
        ``g = (value - (center - width / 2)) / width``, clamped to 0..1,
        scales the list's colour, or picks entry ``round(g (N - 1))`` of the
        lookup table (:meth:`set_volume_lut`). An RGBA8 sample is its own
        colour times its alpha (the window does not apply).

        window None: the type's whole range (uint8 0..255, uint16 0..65535,
        int16 -32768..32767, float32 0..1). threshold None: the window's low
        end, so that what is below the window is dark. A window of width 0
        or less, a value that is not a finite float32, an unknown sampling,
        or a volume of another connection raise ValueError or TypeError
        before anything is sent; NotSupported below protocol version 6."""
        if not isinstance(volume, Volume):
            raise TypeError(f'draw_volume: a spindle.Volume, not {type(volume).__name__}')
        if volume._conn is not self._conn:
            raise ValueError('draw_volume: the volume belongs to another connection')
        try:
            sampling = Sampling(sampling)
        except ValueError:
            raise ValueError(f"draw_volume: sampling is 'nearest', 'trilinear' or a spindle.Sampling, not "
                             f'{sampling!r}') from None
        center, width, low = _window(window, volume.type)
        threshold = low if threshold is None else _float32(threshold, 'threshold')
        self._conn._need_v6('spindle_list_draw_volume', 'draw_volume')
        self._call('spindle_list_draw_volume', volume._h(), int(sampling), threshold, center, width,
                   what='draw_volume')
        self._volumes.add(volume)
        return self

    def set_volume_lut(self, colors):
        """The lookup table of the :meth:`draw_volume` calls that follow:
        an N x 4 (RGBA) or N x 3 (RGB, opaque) array of colours, integers
        0..255 (uint8) or floats 0..1, N from 2 to 4096; alpha scales each
        entry. Entry 0 is the window's low end, entry N - 1 its high end.
        None (or an empty table): the list's colour again. Not saved by
        :meth:`push`; :meth:`clear` resets it. Protocol version 6
        (NotSupported below it); a table of the wrong shape or size raises
        ValueError before anything is sent."""
        table = _lut(colors)
        self._conn._need_v6('spindle_list_set_volume_lut', 'set_volume_lut')
        buf = Buffer(self._conn, self._conn._create(table, False, 'set_volume_lut'), table.nbytes)
        try:
            self._call('spindle_list_set_volume_lut', buf._h(), 0, len(table), what='set_volume_lut')
        finally:
            buf.destroy()
        return self


class Layer(_Object):
    """A layer: shows a :class:`List` in the shared volume
    (:meth:`Connection.create_layer`). New layers are visible, show no list,
    and have the identity transform and priority 0. Changes show at the
    next commit.

    The properties ``list``, ``transform``, ``visible``, ``priority`` and
    ``exclusive`` read what was last set and set it when assigned; the
    set_* methods do the same and return the layer. A layer lives until
    :meth:`destroy` or the connection's close, referenced or not.
    """
    _destroy_fn = 'spindle_layer_destroy'
    _kind = 'layer'

    def __init__(self, conn, handle):
        super().__init__(conn, handle)
        self._list = None
        self._transform = identity()
        self._visible = True
        self._priority = 0
        self._exclusive = False

    def __repr__(self):
        return (f'<spindle.Layer {"visible" if self._visible else "hidden"}, priority {self._priority}'
                f'{", destroyed" if self.destroyed else ""}>')

    def set_list(self, lst):
        """Shows lst (a :class:`List` of the same connection), or nothing (None)."""
        if lst is not None and not isinstance(lst, List):
            raise TypeError(f'set_list: a spindle.List or None, not {type(lst).__name__}')
        if lst is not None and lst._conn is not self._conn:
            raise ValueError('set_list: the list belongs to another connection')
        self._call('spindle_layer_set_list', lst._h() if lst is not None else None)
        self._list = lst
        return self

    def set_transform(self, matrix):
        """The layer's placement (layer to volume space): a 4x4 matrix or 16
        column-major numbers, finite and affine."""
        m = to_column_major(matrix)
        self._call('spindle_layer_set_transform', m.ctypes.data_as(ctypes.POINTER(ctypes.c_float)))
        self._transform = from_column_major(m)
        return self

    def set_visible(self, visible):
        """Shows (True) or hides (False) the layer."""
        self._call('spindle_layer_set_visible', bool(visible))
        self._visible = bool(visible)
        return self

    def set_priority(self, priority):
        """-1000 .. 1000 (default 0): when the scene holds more than the
        daemon's max-scene-primitives, the lowest-priority layers are left
        out, whole. Protocol version 2."""
        if isinstance(priority, bool) or not isinstance(priority, (int, np.integer)):
            raise TypeError(f'priority: an integer, not {type(priority).__name__}')
        if not -2**31 <= priority < 2**31:
            raise ValueError(f'priority: {priority} is out of range (-1000 .. 1000)')
        self._call('spindle_layer_set_priority', int(priority))
        self._priority = int(priority)
        return self

    def set_exclusive(self, exclusive):
        """While visible, show this client's layers alone. Granted at commit by
        the daemon's policy: a refused commit raises RefusedDenied or
        RefusedBusy from commit(wait=True). Protocol version 2."""
        self._call('spindle_layer_set_exclusive', bool(exclusive))
        self._exclusive = bool(exclusive)
        return self

    list = property(lambda self: self._list, set_list, doc='The :class:`List` shown, or None.')
    transform = property(lambda self: self._transform.copy(), set_transform,
                         doc='The transform last set, as a 4x4 float32 array.')
    visible = property(lambda self: self._visible, set_visible, doc='Whether the layer is shown.')
    priority = property(lambda self: self._priority, set_priority, doc='The layer\'s priority.')
    exclusive = property(lambda self: self._exclusive, set_exclusive, doc='Whether the layer asks to show alone.')


class Volume(_Object):
    """A volume: a 3-D grid of samples, such as a CT scan, held by the
    daemon (:meth:`Connection.volume`, protocol version 6) and drawn by
    lists (:meth:`List.draw_volume`).

    Its model space: sample (x, y, z) is centred at
    ``((x + 0.5) sx, (y + 0.5) sy, (z + 0.5) sz)``, so the volume fills the
    box from (0, 0, 0) to ``extent``; y is its up axis (the display's
    rotation axis once drawn without rotation).

    Attributes: ``type`` (:class:`VolumeType`), ``size`` (nx, ny, nz:
    samples along x, y, z), ``spacing`` (sx, sy, sz in model units).

    Its samples count against the client's max-buffer-bytes and the
    daemon's memory budget while it lives. :meth:`destroy` (or a ``with``
    block) gives them back at once: a list that still draws it shows
    nothing of it from the next volume shown on. Otherwise it lives while
    referenced, by the program or by a list drawing it (until the list's
    clear()).
    """
    _destroy_fn = 'spindle_volume_destroy'
    _kind = 'volume'

    def __init__(self, conn, handle, type, size, spacing):
        super().__init__(conn, handle)
        self.type = type
        self.size = size
        self.spacing = spacing

    def __del__(self):
        self._collect()

    def __repr__(self):
        nx, ny, nz = self.size
        return f'<spindle.Volume {nx}x{ny}x{nz} {self.type.name}{", destroyed" if self.destroyed else ""}>'

    @property
    def extent(self):
        """The size of its box in model units: (nx sx, ny sy, nz sz)."""
        return tuple(n * s for n, s in zip(self.size, self.spacing))

    @property
    def nbytes(self):
        """Bytes of samples it holds in the daemon."""
        nx, ny, nz = self.size
        return nx * ny * nz * self.type.size


class FrameRequest:
    """A frame callback asked for with :meth:`Connection.request_frame`: it
    fires once the state of the next commit is first shown.

    Attributes: ``done``, ``frame`` (the :class:`Frame`, once done),
    ``callback`` (called with the Frame, from dispatch()).
    """

    def __init__(self, conn, callback):
        self._conn = conn
        self.callback = callback
        self.done = False
        self.frame = None
        self._refusals = conn._refusals

    def __repr__(self):
        return f'<spindle.FrameRequest {"shown in volume %d" % self.frame.volume_seq if self.done else "pending"}>'

    def _fire(self, frame):
        self.done = True
        self.frame = frame
        if self.callback is not None:
            self.callback(frame)

    def wait(self, timeout=None):
        """Dispatches events until the frame is shown and returns it (a
        :class:`Frame`). Raises :class:`~spindle.Timeout` after timeout
        seconds (None: no limit), and the :class:`~spindle.CommitRefused`
        subclass when the daemon refuses a commit meanwhile (the request then
        stays pending: it fires with a later commit)."""
        conn = self._conn

        def ready():
            if conn._refusals != self._refusals and not self.done:
                self._refusals = conn._refusals
                raise conn._refusal_error()
            return self.done

        conn._wait_until(ready, timeout, 'waiting for a frame')
        return self.frame


class Batch:
    """What :meth:`Connection.batch` yields: ``frame`` is the :class:`Frame`
    the changes were first shown in (after the block, with wait=True)."""

    def __init__(self):
        self.frame = None


class Connection:
    """A connection to spindled (:func:`spindle.connect`).

    Use it as a context manager, or close() it: closing disconnects and
    frees every object made with it (they raise NotConnected afterwards).
    Objects: :meth:`create_buffer` (vertices), :meth:`create_index_buffer`,
    :meth:`create_list`, :meth:`create_layer`, :meth:`volume`; everything
    set since the last commit shows together at :meth:`commit`.

    Events (frame callbacks, the state and refused listeners) are handled by
    :meth:`dispatch` and while the blocking calls wait. A connection and its
    objects are used from one thread at a time.

    Attributes: ``socket`` (the path asked for, None for the default),
    ``device`` (:class:`DeviceInfo`), ``version`` (the protocol version
    agreed), ``on_state`` (called with a :class:`State` when the display's
    state changes; version 2), ``on_refused`` (called with the
    :class:`Refusal`, the object id at fault, 1 for the display, and the
    daemon's message when a commit, or a calibration, is refused).
    """

    def __init__(self, socket=None, *, version=None, library=None):
        self._sp = None
        self._objects = weakref.WeakSet()
        self._layers = set()
        self._graveyard = []
        self._frames = {}
        self._next_token = 1
        self._pending = None
        self._in_callback = 0
        self._close_later = False
        self._refusals = 0
        self._last_refusal = (0, '')
        self.on_state = None
        self.on_refused = None
        self._log_handler = None
        self._lib = lib = _lib.load(library)
        self.socket = os.fspath(socket) if socket is not None else None
        path = os.fsencode(self.socket) if self.socket is not None else None
        if version is None:
            sp = lib.spindle_connect(path)
        else:
            sp = lib.spindle_connect_version(path, _uint(version, 'version'))
        if not sp:
            e = ctypes.get_errno()
            raise NotConnected(self._connect_message(e), e)
        self._sp = sp
        self.version = lib.spindle_get_version(sp)
        self.device = DeviceInfo._from_c(lib.spindle_get_device_info(sp).contents)
        # Callbacks from C hold the connection weakly: dropping it closes it.
        ref = weakref.ref(self)

        def guard(fn):

            def call(*args):
                conn = ref()
                if conn is None:
                    return
                conn._in_callback += 1
                try:
                    fn(conn, *args)
                except BaseException as e:
                    if conn._pending is None:
                        conn._pending = e
                finally:
                    conn._in_callback -= 1

            return call

        self._frame_func = _lib.FRAME_FUNC(guard(Connection._on_frame))
        self._log_func = _lib.LOG_FUNC(guard(Connection._on_log))
        self._listener = _lib.Listener(_lib.STATE_FUNC(guard(Connection._on_state)),
                                       _lib.REFUSED_FUNC(guard(Connection._on_refused)))
        lib.spindle_set_listener(sp, ctypes.byref(self._listener), None)
        lib.spindle_set_log_handler(sp, self._log_func, None)

    def _connect_message(self, e):
        where = self.socket or os.environ.get('SPINDLE_SOCKET') or '/run/spindle/spindle.sock'
        text = f'cannot connect to spindled at {where}: {os.strerror(e) if e else "unknown error"}'
        if e in (errno.ENOENT, errno.ECONNREFUSED):
            text += ' (is spindled running?)'
        elif e == errno.EACCES:
            text += ' (the socket belongs to the group spindle-clients)'
        elif e == errno.EPROTO:
            text += ' (spindled refused the connection, or speaks no common protocol version)'
        elif e == errno.EINVAL:
            text += ' (protocol version out of range)'
        return text

    # ---- life ----

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass

    def __repr__(self):
        if self._sp is None:
            return '<spindle.Connection closed>'
        return f'<spindle.Connection to {self.socket or "the default socket"}, version {self.version}, ' \
               f'{self.device.name}>'

    @property
    def closed(self):
        """True once close() was called."""
        return self._sp is None

    def close(self):
        """Disconnects, freeing every object made with the connection. Calling
        it again does nothing. From a callback, it happens once the call that
        ran the callback returns."""
        if self._in_callback:
            self._close_later = True
            return
        sp, self._sp = self._sp, None
        if sp is None:
            return
        for obj in list(self._objects):
            obj._handle = None
        self._objects = weakref.WeakSet()
        self._layers.clear()
        self._graveyard.clear()
        self._frames.clear()
        self._lib.spindle_disconnect(sp)

    def _enter(self, blocking=None):
        if self._sp is None or self._close_later:
            raise NotConnected('the connection is closed')
        if blocking and self._in_callback:
            raise RuntimeError(f'{blocking} waits for the daemon: it cannot be called from a callback')
        while self._graveyard:
            fn, h = self._graveyard.pop()
            getattr(self._lib, fn)(h)

    def _forget(self, obj):
        self._layers.discard(obj)

    # ---- errors ----

    @property
    def error(self):
        """Why the connection failed (spindle_get_error()): the daemon's error
        message or a local one; None while it is healthy."""
        if self._sp is None:
            return None
        e = self._lib.spindle_get_error(self._sp)
        return e.decode('utf-8', 'replace') if e is not None else None

    @property
    def error_code(self):
        """The code of the daemon's fatal error (enum spindle_error_code), 0
        while healthy or when the failure was local."""
        return self._lib.spindle_get_error_code(self._sp) if self._sp is not None else 0

    def _raise_pending(self):
        if self._close_later and not self._in_callback:
            self._close_later = False
            self.close()
        if self._pending is not None:
            e, self._pending = self._pending, None
            raise e

    def _exception(self, err, what):
        if self._sp is None:
            return NotConnected('the connection is closed', err)
        if err == errno.EPIPE:
            message = self.error or f'{what}: the connection to spindled is broken'
            code = self.error_code
            if code:
                cls = ERRORS.get(code)
                return cls(message) if cls is not None else ProtocolError(message, code)
            return ConnectionLost(message)
        if err in (errno.ENOTSUP, errno.EPROTONOSUPPORT):
            return NotSupported(f'{what}: needs a newer protocol version than this connection\'s {self.version}', err)
        return Error.from_errno(err, what)

    def _check(self, r, what):
        self._raise_pending()
        if r < 0:
            raise self._exception(-r, what)
        return r

    def _new(self, handle, what):
        self._raise_pending()
        if not handle:
            raise self._exception(ctypes.get_errno() or errno.EIO, what)
        return handle

    def _refusal_error(self):
        code, message = self._last_refusal
        cls = REFUSALS.get(code)
        text = f'spindled refused the commit: {message}'
        return cls(text) if cls is not None else CommitRefused(text, code=code)

    # ---- callbacks from C ----

    def _on_frame(self, data, frame):
        req = self._frames.pop(data or 0, None)
        if req is not None:
            req._fire(Frame._from_c(frame.contents))

    def _on_log(self, data, message):
        text = message.decode('utf-8', 'replace') if message else ''
        if self._log_handler is not None:
            self._log_handler(text)
        else:
            _log.debug('%s', text)

    def _on_state(self, data, state):
        if self.on_state is not None:
            self.on_state(State._from_c(state.contents))

    def _on_refused(self, data, code, obj, message):
        text = message.decode('utf-8', 'replace') if message else ''
        self._refusals += 1
        self._last_refusal = (code, text)
        if self.on_refused is not None:
            try:
                refusal = Refusal(code)
            except ValueError:
                refusal = code
            self.on_refused(refusal, obj, text)

    def set_log_handler(self, handler):
        """Diagnostics of libspindle: handler(message) is called with each;
        None (the default) sends them to the logger ``spindle`` at DEBUG
        level."""
        self._log_handler = handler

    # ---- the event loop ----

    def fileno(self):
        """The socket (owned by the library), to poll for reading
        (selectors, asyncio's add_reader); call :meth:`dispatch` when it is
        readable."""
        self._enter()
        return self._lib.spindle_get_fd(self._sp)

    def flush(self):
        """Writes the requests queued. True when all went out; False when the
        socket is full (poll for writing and call again)."""
        self._enter()
        r = self._lib.spindle_flush(self._sp)
        if r == -errno.EAGAIN:
            return False
        self._check(r, 'flush')
        return True

    def dispatch(self, timeout=0):
        """Waits at most timeout seconds (0: not at all, None: until something
        arrives) for events, handles those that came (frame callbacks, state
        and refusals) and returns how many."""
        self._enter('dispatch()')
        self._poll(timeout)
        return self._check(self._lib.spindle_dispatch(self._sp), 'dispatch')

    def _poll(self, timeout):
        flushed = self.flush()
        fd = self._lib.spindle_get_fd(self._sp)
        p = select.poll()
        p.register(fd, select.POLLIN | (0 if flushed else select.POLLOUT))
        ms = -1 if timeout is None else max(0, int(timeout * 1000 + 0.999))
        try:
            return p.poll(ms)
        except InterruptedError:
            return []

    def _wait_until(self, ready, timeout, what):
        deadline = None if timeout is None else time.monotonic() + timeout
        while not ready():
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                raise Timeout(f'{what}: nothing in {timeout} s')
            self.dispatch(left)

    def roundtrip(self):
        """Blocks until the daemon has handled every request sent so far
        (handling events meanwhile). A fatal error the requests caused is
        raised here."""
        self._enter('roundtrip()')
        self._check(self._lib.spindle_roundtrip(self._sp), 'roundtrip')

    # ---- objects ----

    def create_buffer(self, vertices, colors=None, *, inline=False):
        """A :class:`Buffer` of vertices: an N x 3 array of x, y, z (converted
        to float32), with colors (optional) one per vertex, K x 3 or K x 4:
        floats 0..1 give format XYZ_RGBA_FLOAT, integers 0..255 XYZ_RGBA8.
        inline: always sent inside the request (at most 65516 bytes;
        otherwise a buffer over that goes in a sealed memfd)."""
        xyz = _vertices(vertices)
        if colors is None:
            return self._vertex_buffer(xyz, VertexFormat.XYZ, len(xyz), inline)
        c, fmt = _color_array(colors)
        if len(c) == 1:
            c = np.repeat(c, len(xyz), axis=0)
        if len(c) != len(xyz):
            raise ValueError(f'colors: {len(c)} colours for {len(xyz)} vertices')
        return self._vertex_buffer(_interleave(xyz, c, fmt), fmt, len(xyz), inline)

    def _vertex_buffer(self, array, fmt, count, inline=False):
        h = self._create(array, inline, 'create_buffer')
        return Buffer(self, h, array.nbytes, format=fmt, count=count)

    def _create(self, array, inline, what):
        self._enter()
        fn = self._lib.spindle_buffer_create_inline if inline else self._lib.spindle_buffer_create
        if inline and array.nbytes > INLINE_MAX:
            raise ValueError(f'{what}: {array.nbytes} bytes do not go inline (at most {INLINE_MAX})')
        return self._new(fn(self._sp, array.ctypes.data if array.nbytes else None, array.nbytes), what)

    def create_index_buffer(self, indices, *, vertex_count=None, type=None, inline=False):
        """A :class:`Buffer` of indices (integers, any shape, flattened), for
        :meth:`List.draw_indexed`. type: IndexType.U16 or U32 (None: U16 when
        every index fits). vertex_count: when given, every index must be below
        it (the daemon checks at the draw anyway)."""
        try:
            a = np.asarray(indices)
        except (TypeError, ValueError) as e:
            raise TypeError(f'indices: not an array of integers: {e}') from None
        a = a.reshape(-1)
        if a.size and not np.issubdtype(a.dtype, np.integer):
            raise TypeError(f'indices: expected integers, not {a.dtype}')
        top = int(a.max()) if a.size else 0
        if a.size and a.min() < 0:
            raise ValueError(f'indices: {int(a.min())} is negative')
        if vertex_count is not None and a.size and top >= vertex_count:
            raise ValueError(f'indices: index {top} is not below the {vertex_count} vertices')
        itype = IndexType(type) if type is not None else (IndexType.U16 if top < 65536 else IndexType.U32)
        if itype == IndexType.U16 and top >= 65536:
            raise ValueError(f'indices: {top} does not fit in 16 bits')
        if top >= 2**32:
            raise ValueError(f'indices: {top} does not fit in 32 bits')
        arr = np.ascontiguousarray(a, dtype=np.uint16 if itype == IndexType.U16 else np.uint32)
        h = self._create(arr, inline, 'create_index_buffer')
        return Buffer(self, h, arr.nbytes, count=len(arr), index_type=itype)

    def create_raw_buffer(self, data, *, inline=False):
        """A :class:`Buffer` holding a copy of data (bytes, or anything with
        the buffer protocol: a numpy array of any dtype, used as its bytes),
        exactly as spindle_buffer_create() takes it. Draws from it use the
        list's vertex format (:meth:`List.set_vertex_format`)."""
        try:
            arr = np.frombuffer(memoryview(data).cast('B'), dtype=np.uint8)
        except (TypeError, ValueError):
            arr = np.ascontiguousarray(np.asarray(data)).view(np.uint8).reshape(-1)
        h = self._create(arr, inline, 'create_raw_buffer')
        return Buffer(self, h, arr.nbytes)

    def create_buffer_from_fd(self, fd, size, *, format=None, count=None):
        """Zero copy: a :class:`Buffer` over the caller's memfd (an int or
        an object with fileno()) of at least size bytes, sealed at least
        against shrinking (F_SEAL_SHRINK). The caller keeps the fd. format
        and count describe its vertices when it holds some (for the draws'
        defaults)."""
        self._enter()
        fd = fd.fileno() if hasattr(fd, 'fileno') else fd
        h = self._new(self._lib.spindle_buffer_create_from_fd(self._sp, _uint(fd, 'fd', 2**31 - 1),
                                                              _uint(size, 'size', 2**64 - 1)),
                      'create_buffer_from_fd')
        return Buffer(self, h, size, format=VertexFormat(format) if format is not None else None, count=count)

    def create_list(self):
        """A new, empty :class:`List`."""
        self._enter()
        return List(self, self._new(self._lib.spindle_list_create(self._sp), 'create_list'))

    def create_layer(self, lst=None):
        """A new :class:`Layer` (visible, identity transform), showing lst if given."""
        self._enter()
        layer = Layer(self, self._new(self._lib.spindle_layer_create(self._sp), 'create_layer'))
        self._layers.add(layer)
        if lst is not None:
            layer.set_list(lst)
        return layer

    def volume(self, samples, spacing=(1, 1, 1)):
        """A :class:`Volume` of samples (protocol version 6): a 3-D numpy
        array indexed [z, y, x] (so that its C order has x fastest, as the
        daemon takes it) of uint8, uint16, int16 or float32, or a 4-D uint8
        array [z, y, x, 4] of RGBA colours. y is the volume's up axis: a
        stack of axial CT slices indexed [slice, row, column] shows lying on
        its side; ``np.transpose`` it to stand it up (docs/volumes.md, "The
        display's convention"). 1 to 4096 samples along each axis, at most
        2^31 in all. Other byte orders and layouts are converted.

        spacing: (sx, sy, sz), the distance between sample centres along x,
        y and z in model units (millimetres, say), finite and above 0; one
        number for all three.

        One call sends the samples in a buffer, makes the volume from it and
        destroys the buffer: the daemon keeps its own copy. Another dtype
        (int32, float64: convert with ``astype()``) raises TypeError, another
        shape ValueError, before anything is sent; NotSupported below
        protocol version 6."""
        vtype, size, arr = _volume_samples(samples)
        spacing = _volume_spacing(spacing)
        self._enter()
        create = self._need_v6('spindle_volume_create', 'volume')
        buf = Buffer(self, self._create(arr.reshape(-1).view(np.uint8), False, 'volume'), arr.nbytes)
        try:
            h = self._new(
                create(self._sp, buf._h(), 0, int(vtype), (ctypes.c_uint32 * 3)(*size),
                       (ctypes.c_float * 3)(*spacing.tolist())), 'volume')
        finally:
            buf.destroy()
        return Volume(self, h, vtype, size, tuple(float(s) for s in spacing))

    def _need_v6(self, name, what):
        """libspindle's function name, refusing (NotSupported) a libspindle or a connection older than protocol 6."""
        fn = getattr(self._lib, name, None)  # OPTIONAL: missing from a libspindle older than SPINDLE_0.4
        if fn is None:
            raise NotSupported(f'{what}: {name} is not in this libspindle ({_lib.loaded_path()}): it is older than '
                               'protocol version 6', errno.EPROTONOSUPPORT)
        if self.version < 6:
            raise NotSupported(f'{what}: needs protocol version 6, this connection\'s is {self.version}',
                               errno.EPROTONOSUPPORT)
        return fn

    # ---- commits and frames ----

    def request_frame(self, callback=None):
        """Asks to be told when the state of the next commit is first shown:
        returns a :class:`FrameRequest` (wait() on it, or poll its
        ``done``); callback, if given, is called with the :class:`Frame` from
        dispatch(). Call before commit()."""
        self._enter()
        token = self._next_token
        self._next_token += 1
        req = FrameRequest(self, callback)
        self._frames[token] = req
        r = self._lib.spindle_request_frame(self._sp, self._frame_func, token)
        if r < 0:
            self._frames.pop(token, None)
        self._check(r, 'request_frame')
        return req

    def commit(self, wait=False):
        """Makes everything set since the last commit show together.

        wait=False: queues the commit and returns None (a refusal is told to
        ``on_refused``, and to FrameRequest.wait()). wait=True: as
        :meth:`commit_and_wait`."""
        if wait:
            return self.commit_and_wait()
        self._enter()
        self._check(self._lib.spindle_commit(self._sp), 'commit')
        return None

    def commit_and_wait(self):
        """Commits and blocks until the state is shown; returns the
        :class:`Frame` it was first shown in. A refused commit raises
        RefusedQuota (over max-primitives), RefusedDenied (exclusive layer
        not allowed) or RefusedBusy (another client's exclusive layer shows),
        with every change still pending."""
        self._enter('commit_and_wait()')
        frame = _lib.Frame()
        r = self._lib.spindle_commit_and_wait(self._sp, ctypes.byref(frame))
        self._raise_pending()
        if r in (-errno.EDQUOT, -errno.EACCES, -errno.EBUSY):
            e = self._refusal_error()
            e.errno = -r
            raise e
        self._check(r, 'commit_and_wait')
        return Frame._from_c(frame)

    @contextlib.contextmanager
    def batch(self, wait=True):
        """``with sp.batch() as b:`` the changes made in the block are
        committed together when it ends (not when it raises: they stay
        pending), and with wait=True waited for: ``b.frame`` is the
        :class:`Frame` they were first shown in."""
        self._enter()
        b = Batch()
        yield b
        b.frame = self.commit(wait=wait)

    # ---- queries ----

    @property
    def state(self):
        """The last :class:`State` the daemon pushed (protocol version 2;
        NotSupported at version 1)."""
        self._enter()
        out = _lib.State()
        self._check(self._lib.spindle_get_state(self._sp, ctypes.byref(out)), 'state')
        return State._from_c(out)

    def status(self):
        """Blocks for the daemon's current :class:`Status`."""
        self._enter('status()')
        room = _lib.StatusRoom()
        # room.status is the start of room: a newer library's longer struct fits.
        self._check(self._lib.spindle_get_status(self._sp, ctypes.byref(room.status)), 'status')
        return Status._from_c(room.status)

    def capture(self):
        """Blocks for the next volume shown and returns it as a
        :class:`~spindle.Capture` (the .svol format). Raises CaptureError
        (errno EACCES) for a client the daemon's policy denies captures (only
        root, the daemon's own user and its admin group may), or when the
        daemon could not make one (EIO)."""
        self._enter('capture()')
        fd, size = ctypes.c_int(-1), ctypes.c_size_t(0)
        r = self._lib.spindle_capture(self._sp, ctypes.byref(fd), ctypes.byref(size))
        self._raise_pending()
        if r in (-errno.EACCES, -errno.EIO):
            raise CaptureError.from_errno(r, 'capture')
        self._check(r, 'capture')
        with os.fdopen(fd.value, 'rb') as f:
            data = f.read(size.value)
        return Capture(data)

    # ---- calibration (protocol version 6) ----

    def _calibration_fn(self, name):
        fn = getattr(self._lib, name, None)  # OPTIONAL: missing from a libspindle older than SPINDLE_0.4
        if fn is None:
            raise NotSupported(f'{name}: not in this libspindle ({_lib.loaded_path()}): it is older than '
                               'protocol version 6', errno.EPROTONOSUPPORT)
        return fn

    def calibration(self):
        """Blocks for the display's :class:`Calibration` in use (the
        identity, 0, 0, 0, 1.0, 0.0, until calibrated). Raises NotSupported from
        a daemon or libspindle older than protocol version 6."""
        self._enter('calibration()')
        out = _lib.Calibration()
        self._check(self._calibration_fn('spindle_get_calibration')(self._sp, ctypes.byref(out)), 'calibration')
        return Calibration._from_c(out)

    def calibrate(self, key, value):
        """Sets one calibration value from the next volume on and returns
        the new :class:`Calibration` (blocking; the daemon's config file is
        not written: ``spindlectl calibrate --save`` does that). key: a
        :class:`CalibrationKey` (or its number) or its config name
        ('phase-offset', 'axis-offset-u', 'axis-offset-v', 'vertical-scale',
        'vertical-offset'); value: degrees (-180 to 180), whole pixels (at most
        a quarter of the image either way), a factor (0.5 to 2), or volume
        units (-0.5 to 0.5).

        A refusal changes nothing and the connection goes on: RefusedDenied
        (errno EACCES) for a client other than root and the daemon's own
        user, RefusedOutOfRange (errno ERANGE) for a value out of its range
        for this display, a non-integer offset included (both are
        CommitRefused subclasses; ``on_refused`` is called too). An unknown
        key raises ValueError, a value that is not a number TypeError,
        before anything is sent; NotSupported from a daemon or libspindle
        older than protocol version 6."""
        try:
            key = CalibrationKey(key)
        except ValueError:
            names = ', '.join(k.config_name for k in CalibrationKey)
            raise ValueError(f'calibrate: {key!r} is not a calibration key ({names})') from None
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise TypeError(f'calibrate: the value is a number, not {type(value).__name__}')
        self._enter('calibrate()')
        fn = self._calibration_fn('spindle_calibrate')
        out = _lib.Calibration()
        refusals, last = self._refusals, self._last_refusal
        r = fn(self._sp, int(key), float(value), ctypes.byref(out))
        if r in (-errno.EACCES, -errno.ERANGE):
            message = os.strerror(-r)
            if self._refusals > refusals:
                message = self._last_refusal[1]
                # The calibration's refused event is no commit's: FrameRequest.wait() must not raise it.
                self._refusals -= 1
                if self._refusals == refusals:
                    self._last_refusal = last
            self._raise_pending()
            cls = RefusedDenied if r == -errno.EACCES else RefusedOutOfRange
            raise cls(f'spindled refused the calibration: {message}', -r)
        self._check(r, 'calibrate')
        return Calibration._from_c(out)
