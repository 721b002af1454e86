"""The connection: Connection, and connect()."""
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
from ._args import INLINE_MAX, _color_array, _interleave, _uint, _vertices, _volume_samples, _volume_spacing
from ._objects import Batch, Buffer, FrameRequest, Layer, List, Volume
from .capture import Capture
from .errors import (CaptureError, CommitRefused, ConnectionLost, Error, NotConnected, NotSupported, ProtocolError,
                     Timeout)
from .protocol_errors import ERRORS, REFUSALS, RefusedDenied, RefusedOutOfRange
from .types import Calibration, CalibrationKey, DeviceInfo, Frame, IndexType, Refusal, State, Status, VertexFormat


_log = logging.getLogger('spindle')

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
