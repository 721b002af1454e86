"""An independent client side of the Spindle wire format, written from the
generated reference document docs/protocol.md alone.

The document is parsed at import time: interfaces, requests and events with
their opcodes, since versions, argument types and documented fixed sizes, and
enums with the version that introduced each value ("version N:" in its
meaning). Nothing here comes from the C codec.

Wire format (docs/protocol.md, "Wire format"): a 12-byte little-endian header
(object id u32, opcode u16, fd count u16, size u32), then the arguments.
"""
import array
import errno
import fcntl
import os
import re
import select
import socket
import struct
import time

DOC = os.environ.get('SPINDLE_PROTOCOL_DOC') or os.path.join(
    os.path.dirname(os.path.abspath(__file__)), '..', '..', 'docs', 'protocol.md')

HEADER = struct.Struct('<IHHI')
MAX_MESSAGE = 65536
FIXED = {'uint': 4, 'int': 4, 'float': 4, 'object': 4, 'new_id': 4, 'uint64': 8,
         'matrix': 64, 'string': 4, 'array': 4, 'fd': 0}


class Arg:
    def __init__(self, name, type_):
        self.name, self.type = name, type_
        self.interface = None   # for object / new_id
        self.enum = None        # "mode" or "display.error"
        self.nullable = False


class Message:
    def __init__(self, interface, name, args, kind):
        self.interface, self.name, self.args, self.kind = interface, name, args, kind
        self.opcode = self.since = self.size = None
        self.nfds = 0
        self.destructor = False
        self.variable = False

    @property
    def full(self):
        return f'{self.interface}.{self.name}'

    def __repr__(self):
        return f'<{self.kind} {self.full} op {self.opcode} since {self.since}>'


class Protocol:
    """The parsed reference document."""

    def __init__(self, path=DOC):
        with open(path) as f:
            self.text = f.read()
        self.interfaces = {}   # name -> version
        self.requests = {}     # "iface.name" -> Message
        self.events = {}
        self.enums = {}        # "iface.enum" -> {name: (value, since)}
        self.version = int(re.search(r'^# .*protocol, version (\d+)$', self.text, re.M).group(1))
        self._parse()

    def _parse(self):
        iface = kind = msg = enum = None
        lines = self.text.splitlines()
        for i, line in enumerate(lines):
            m = re.match(r'^## Interface `(\w+)` \(version (\d+)\)$', line)
            if m:
                iface, kind, msg, enum = m.group(1), None, None, None
                self.interfaces[iface] = int(m.group(2))
                continue
            if line == '### Requests':
                kind, msg, enum = 'request', None, None
                continue
            if line == '### Events':
                kind, msg, enum = 'event', None, None
                continue
            m = re.match(r'^### Enum `(\w+)\.(\w+)`$', line)
            if m:
                enum, msg = f'{m.group(1)}.{m.group(2)}', None
                self.enums[enum] = {}
                continue
            m = re.match(r'^#### `(\w+)\.(\w+)\((.*)\)`$', line)
            if m:
                assert m.group(1) == iface, line
                args = []
                for a in filter(None, (s.strip() for s in m.group(3).split(','))):
                    n, t = (s.strip() for s in a.split(':'))
                    assert t in FIXED, f'unknown type {t} in {line}'
                    args.append(Arg(n, t))
                msg = Message(iface, m.group(2), args, kind)
                (self.requests if kind == 'request' else self.events)[msg.full] = msg
                enum = None
                continue
            if msg is not None:
                m = re.match(r'^Opcode (\d+), since version (\d+), (.*)\.$', line)
                if m:
                    msg.opcode, msg.since = int(m.group(1)), int(m.group(2))
                    rest = m.group(3)
                    msg.destructor = 'destructor' in rest
                    sm = re.search(r'(\d+) bytes', rest)
                    msg.size = int(sm.group(1))
                    msg.variable = 'plus' in rest
                    fm = re.search(r'(\d+) fds?', rest)
                    msg.nfds = int(fm.group(1)) if fm else 0
                    continue
                m = re.match(r'^\| (\w+) \| ([^|]*) \|', line)
                if m and m.group(1) != 'argument':
                    arg = next(a for a in msg.args if a.name == m.group(1))
                    desc = m.group(2)
                    im = re.search(r'(?:object|new_id) \((\w+)\)', desc)
                    if im:
                        arg.interface = im.group(1)
                    em = re.search(r'enum (\w+)', desc)
                    if em:
                        arg.enum = em.group(1) if '.' in em.group(1) else f'{iface}.{em.group(1)}'
                    arg.nullable = 'may be 0' in desc
                continue
            if enum is not None:
                m = re.match(r'^\| (\w+) \| (\d+) \|(.*)\|$', line)
                if m and m.group(1) != 'name':
                    vm = re.match(r'\s*version (\d+):', m.group(3))
                    self.enums[enum][m.group(1)] = (int(m.group(2)), int(vm.group(1)) if vm else 1)
        # Self-check: the sizes we compute are the sizes the document states.
        for m in list(self.requests.values()) + list(self.events.values()):
            assert m.opcode is not None, m
            size = 12 + sum(FIXED[a.type] for a in m.args)
            assert size == m.size, f'{m.full}: computed {size}, doc says {m.size}'
            assert m.nfds == sum(a.type == 'fd' for a in m.args), m
            assert m.variable == any(a.type in ('string', 'array') for a in m.args), m

    def request(self, full):
        return self.requests[full]

    def event_by_opcode(self, iface, opcode):
        for m in self.events.values():
            if m.interface == iface and m.opcode == opcode:
                return m
        return None

    def requests_of(self, iface=None, version=None):
        return [m for m in self.requests.values()
                if (iface is None or m.interface == iface) and (version is None or m.since <= version)]

    def enum(self, name, value_name):
        return self.enums[name][value_name][0]


P = Protocol()
ERR = {k: v for k, (v, _) in P.enums['display.error'].items()}
REFUSAL = {k: v for k, (v, _) in P.enums['display.refusal'].items()}
FAILURE = {k: v for k, (v, _) in P.enums['capture.failure'].items()}
STATUS = {k: v for k, (v, _) in P.enums['display.status_flags'].items()}
MODE = {k: v for k, (v, _) in P.enums['list.mode'].items()}
FORMAT = {k: v for k, (v, _) in P.enums['list.vertex_format'].items()}
INDEX = {k: v for k, (v, _) in P.enums['list.index_type'].items()}
ERR_NAME = {v: k for k, v in ERR.items()}

IDENTITY = (1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0)


def pad4(b):
    return b + b'\0' * (-len(b) % 4)


def encode_args(msg, args):
    """Argument bytes and fds for msg; args in document order."""
    if len(args) != len(msg.args):
        raise TypeError(f'{msg.full} takes {len(msg.args)} arguments, got {len(args)}')
    out, fds = b'', []
    for a, v in zip(msg.args, args):
        t = a.type
        if t in ('uint', 'object', 'new_id'):
            out += struct.pack('<I', v & 0xffffffff)
        elif t == 'int':
            out += struct.pack('<i', v)
        elif t == 'float':
            out += struct.pack('<f', v)
        elif t == 'uint64':
            out += struct.pack('<Q', v & 0xffffffffffffffff)
        elif t == 'matrix':
            out += struct.pack('<16f', *v)
        elif t == 'string':
            if v is None:
                out += struct.pack('<I', 0)
            else:
                b = v.encode() + b'\0'
                out += struct.pack('<I', len(b)) + pad4(b)
        elif t == 'array':
            out += struct.pack('<I', len(v)) + pad4(bytes(v))
        elif t == 'fd':
            fds.append(v)
    return out, fds


def encode(obj, msg, args, nfds=None, size=None, opcode=None):
    body, fds = encode_args(msg, args)
    n = len(fds) if nfds is None else nfds
    s = 12 + len(body) if size is None else size
    return HEADER.pack(obj, msg.opcode if opcode is None else opcode, n, s) + body, fds


def decode_args(msg, body, fds):
    vals, off = {}, 0
    for a in msg.args:
        t = a.type
        if t in ('uint', 'object', 'new_id'):
            vals[a.name] = struct.unpack_from('<I', body, off)[0]
            off += 4
        elif t == 'int':
            vals[a.name] = struct.unpack_from('<i', body, off)[0]
            off += 4
        elif t == 'float':
            vals[a.name] = struct.unpack_from('<f', body, off)[0]
            off += 4
        elif t == 'uint64':
            vals[a.name] = struct.unpack_from('<Q', body, off)[0]
            off += 8
        elif t == 'matrix':
            vals[a.name] = struct.unpack_from('<16f', body, off)
            off += 64
        elif t in ('string', 'array'):
            n = struct.unpack_from('<I', body, off)[0]
            off += 4
            raw = body[off:off + n]
            if len(raw) != n:
                raise ProtocolViolation(f'{msg.full}: {a.name} runs past the message')
            off += n + (-n % 4)
            if t == 'string':
                if n == 0:
                    vals[a.name] = None
                else:
                    if raw[-1] != 0 or 0 in raw[:-1]:
                        raise ProtocolViolation(f'{msg.full}: bad string {raw!r}')
                    vals[a.name] = raw[:-1].decode(errors='replace')
            else:
                vals[a.name] = raw
        elif t == 'fd':
            if not fds:
                raise ProtocolViolation(f'{msg.full}: fd missing')
            vals[a.name] = fds.pop(0)
    if off != len(body):
        raise ProtocolViolation(f'{msg.full}: size {12 + len(body)} does not match its arguments ({12 + off})')
    return vals


class ProtocolViolation(Exception):
    """The daemon sent something the document does not allow."""


class Event:
    def __init__(self, obj, msg, args):
        self.obj, self.msg, self.args = obj, msg, args
        self.name = msg.full

    def __getitem__(self, k):
        return self.args[k]

    def __repr__(self):
        a = {k: v for k, v in self.args.items()}
        if self.name == 'display.error':
            a['code'] = f"{a['code']} ({ERR_NAME.get(a['code'], '?')})"
        return f'{self.name}@{self.obj}{a}'


class Closed(Exception):
    pass


def memfd(data=b'', size=None, seals=fcntl.F_SEAL_SHRINK, name='conformance'):
    """A memfd holding data, truncated to size (default len(data)), sealed."""
    fd = os.memfd_create(name, os.MFD_ALLOW_SEALING | os.MFD_CLOEXEC)
    os.ftruncate(fd, len(data) if size is None else size)
    if data:
        os.pwrite(fd, data, 0)
    if seals:
        fcntl.fcntl(fd, fcntl.F_ADD_SEALS, seals)
    return fd


def vertices(points, fmt='xyz', colors=None):
    """Packed vertex bytes: xyz floats, plus rgba8 or rgba float per vertex."""
    out = b''
    for i, p in enumerate(points):
        out += struct.pack('<3f', *p)
        if fmt == 'xyz_rgba8':
            out += bytes(colors[i])
        elif fmt == 'xyz_rgba_float':
            out += struct.pack('<4f', *colors[i])
    return out


def read_memfd(ev):
    """The bytes of the sealed memfd an event (capture.ready, watcher.volume)
    carries as fd and size; the fd is closed."""
    fd = ev['fd']
    try:
        return os.pread(fd, ev['size'], 0)
    finally:
        os.close(fd)


class Conn:
    """One client connection. Requests by name; events decoded and kept in
    order; the version negotiated is checked against every event."""

    def __init__(self, path, connect=True, sock=None):
        self.path = path
        self.sock = sock or socket.socket(socket.AF_UNIX, socket.SOCK_STREAM | socket.SOCK_CLOEXEC)
        if connect and sock is None:
            self.sock.connect(path)
        self.buf = b''
        self.fds = []
        self.events = []       # decoded, not yet taken
        self.log = []          # every event, for messages
        self.objects = {1: 'display'}
        # Objects the client destroyed (destructor requests): id ->
        # (interface, the first id made after the destroy). The daemon may
        # have sent them events before it read the destroy; those still
        # arrive, until the event of a callback or capture made after the
        # destroy shows that it read it.
        self.zombies = {}
        self.next_id = 2
        self.version = None
        self.eof = False
        self.device = None
        self.state = None
        self.sent = set()      # names of the requests sent

    # -- sending ---------------------------------------------------------
    def send_raw(self, data, fds=(), flags=0):
        anc = [(socket.SOL_SOCKET, socket.SCM_RIGHTS, array.array('i', fds))] if fds else []
        return self.sock.sendmsg([data], anc, flags)

    def send_all(self, data, fds=()):
        sent = self.send_raw(data, fds)
        if sent < len(data):
            self.sock.sendall(data[sent:])

    def new_id(self):
        i = self.next_id
        self.next_id += 1
        return i

    def encode(self, obj, name, *args, **kw):
        msg = P.request(name)
        return encode(obj, msg, args, **kw)

    def req(self, obj, name, *args, nfds=None, size=None, send_fds=None):
        """Sends request name ("list.draw") to obj. new_id arguments are
        recorded as objects of their interface."""
        msg = P.request(name)
        data, fds = encode(obj, msg, args, nfds=nfds, size=size)
        for a, v in zip(msg.args, args):
            if a.type == 'new_id':
                self.objects[v] = a.interface
                self.zombies.pop(v, None)
        self.send_all(data, fds if send_fds is None else send_fds)
        self.sent.add(name)
        if msg.destructor:
            iface = self.objects.pop(obj, None)
            if iface is not None:
                self.zombies[obj] = (iface, self.next_id)

    # convenience constructors, returning the new id
    def create(self, what, *args):
        i = self.new_id()
        self.req(1, f'display.{what}', i, *args)
        return i

    def buffer(self, data, seals=fcntl.F_SEAL_SHRINK, size=None):
        fd = memfd(data, seals=seals)
        try:
            return self.create('create_buffer', len(data) if size is None else size, fd)
        finally:
            os.close(fd)

    # -- receiving -------------------------------------------------------
    def _read(self, timeout):
        r, _, _ = select.select([self.sock], [], [], timeout)
        if not r:
            return False
        try:
            data, anc, flags, _ = self.sock.recvmsg(1 << 16, socket.CMSG_SPACE(16 * 4))
        except (ConnectionResetError, BrokenPipeError):
            data, anc = b'', []
        for level, typ, cdata in anc:
            if level == socket.SOL_SOCKET and typ == socket.SCM_RIGHTS:
                a = array.array('i')
                a.frombytes(cdata[:len(cdata) - len(cdata) % a.itemsize])
                self.fds.extend(a)
        if not data:
            self.eof = True
            return True
        self.buf += data
        self._parse()
        return True

    def _parse(self):
        while len(self.buf) >= 12:
            obj, op, nfds, size = HEADER.unpack_from(self.buf)
            if size < 12 or size % 4 or size > MAX_MESSAGE:
                raise ProtocolViolation(f'event size {size}')
            if len(self.buf) < size:
                return
            body, self.buf = self.buf[12:size], self.buf[size:]
            iface = self.objects.get(obj)
            zombie = iface is None and obj in self.zombies
            if zombie:
                iface = self.zombies[obj][0]
            if iface is None:
                raise ProtocolViolation(f'event for unknown object {obj} (opcode {op})')
            msg = P.event_by_opcode(iface, op)
            if msg is None:
                raise ProtocolViolation(f'unknown event {iface} opcode {op}')
            if nfds != msg.nfds:
                raise ProtocolViolation(f'{msg.full}: fd count {nfds}')
            if not msg.variable and size != msg.size:
                raise ProtocolViolation(f'{msg.full}: size {size}, doc says {msg.size}')
            # Events newer than the version agreed are never sent.
            v = self.version if self.version is not None else 1
            if msg.since > v:
                raise ProtocolViolation(f'{msg.full} (since {msg.since}) sent at version {v}')
            args = decode_args(msg, body, self.fds)
            if zombie:   # sent before the daemon read the destroy: dropped
                for a in msg.args:
                    if a.type == 'fd':
                        os.close(args[a.name])
                continue
            ev = Event(obj, msg, args)
            if ev.name == 'display.welcome':
                self.version = args['version']
            elif ev.name == 'display.device':
                self.device = ev
            elif ev.name == 'display.state':
                self.state = ev
            for a in msg.args:   # enum values newer than the version, never
                if a.enum and a.enum in P.enums and ev.name != 'display.error':
                    for n, (val, since) in P.enums[a.enum].items():
                        if val == args[a.name] and since > v:
                            raise ProtocolViolation(f'{ev}: {n} is newer than version {v}')
            if iface in ('callback', 'capture'):
                self.objects.pop(obj)   # destroyed after their one event
                self.zombies = {z: v for z, v in self.zombies.items() if v[1] > obj}
            self.log.append(ev)
            self.events.append(ev)

    def pump(self, timeout=0.0):
        """Reads what has arrived (waiting up to timeout for the first)."""
        got = self._read(timeout)
        while got and not self.eof and self._read(0):
            pass

    def wait(self, pred, timeout=5.0, what='event'):
        """The first kept event matching pred (removed from the queue)."""
        if isinstance(pred, str):
            name = pred
            what = name if what == 'event' else what
            pred = lambda e: e.name == name  # noqa: E731
        end = time.monotonic() + timeout
        while True:
            for i, e in enumerate(self.events):
                if pred(e):
                    return self.events.pop(i)
            if self.eof:
                raise Closed(f'connection closed waiting for {what}; events {self.log[-8:]}')
            left = end - time.monotonic()
            if left <= 0:
                raise TimeoutError(f'no {what} within {timeout} s; events {self.log[-8:]}')
            self._read(left)

    def errors(self):
        return [e for e in self.log if e.name == 'display.error']

    def hello(self, version=None, timeout=5.0):
        self.req(1, 'display.hello', P.version if version is None else version)
        w = self.wait('display.welcome', timeout)
        self.wait('display.device', timeout)
        if self.version >= 2:
            self.wait('display.state', min(timeout, 2.0))
        return w['version']

    def sync(self, timeout=5.0):
        cb = self.new_id()
        self.req(1, 'display.sync', cb)
        return self.wait(lambda e: e.obj == cb and e.name == 'callback.done', timeout, 'sync done')

    def frame_commit(self, timeout=5.0):
        """commit with a frame callback; waits for its done."""
        cb = self.new_id()
        self.req(1, 'display.frame', cb)
        self.req(1, 'display.commit')
        return self.wait(lambda e: e.obj == cb and e.name == 'callback.done', timeout, 'frame done')

    def capture(self, timeout=5.0):
        """The next volume as (svol bytes) or the capture.failed event."""
        cid = self.new_id()
        self.req(1, 'display.capture', cid)
        ev = self.wait(lambda e: e.obj == cid, timeout, 'capture')
        if ev.name == 'capture.failed':
            return ev
        return read_memfd(ev)

    def status(self, timeout=5.0):
        self.req(1, 'display.get_status')
        return self.wait('display.status', timeout)

    def expect_fatal(self, code, obj=None, timeout=5.0):
        """The documented fatal error: display.error with code (and object),
        then the daemon closes the connection. Returns the error event."""
        try:
            ev = self.wait('display.error', timeout, f'display.error {ERR_NAME.get(code, code)}')
        except (Closed, TimeoutError) as e:
            raise AssertionError(f'expected display.error {ERR_NAME.get(code, code)}: {e}') from None
        codes = code if isinstance(code, (tuple, set, list)) else (code,)
        if ev['code'] not in codes:
            raise AssertionError(f'expected error {[ERR_NAME.get(c, c) for c in codes]}, got {ev}')
        objs = obj if isinstance(obj, (tuple, set, list)) else (obj,)
        if obj is not None and ev['object'] not in objs:
            raise AssertionError(f'error names object {ev["object"]}, expected {obj}: {ev}')
        self.expect_eof(timeout)
        return ev

    def expect_eof(self, timeout=5.0):
        end = time.monotonic() + timeout
        while not self.eof:
            left = end - time.monotonic()
            if left <= 0:
                raise AssertionError(f'connection not closed; events {self.log[-8:]}')
            self._read(left)
        extra = [e for e in self.events if e.name == 'display.error']
        if len(self.errors()) > 1:
            raise AssertionError(f'more than one error: {self.errors()}')
        return extra

    def close(self):
        for fd in self.fds:
            os.close(fd)
        self.fds = []
        self.sock.close()


def send_ignoring_close(conn, data, fds=()):
    """Sends, treating a connection the daemon already closed as sent."""
    try:
        conn.send_all(data, fds)
    except OSError as e:
        if e.errno not in (errno.EPIPE, errno.ECONNRESET):
            raise
