"""The objects of a connection: Buffer, List, Layer, Volume, and FrameRequest, Batch."""
import contextlib
import ctypes

import numpy as np

from ._args import (_PER_PRIMITIVE, _check_count, _color_array, _float32, _interleave, _lut, _rgba, _uint,
                    _vertices, _window)
from .errors import NotConnected
from .transform import from_column_major, identity, to_column_major
from .types import IndexType, Mode, Sampling, VertexFormat


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

