"""The conformance suite's daemon fixture, witness client and checks.

Each test script is run by meson as `python3 test_X.py SPINDLED [CASE...]`; it
starts its own spindled on the simulated device with a socket in a temporary
directory, runs its cases, stops the daemon with SIGTERM and fails unless it
exits 0 (under ASan the daemon's leak report makes the exit status non-zero).
"""
import os
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time
import traceback

import spindlewire as w
from spindlewire import Conn, P, ERR, MODE, IDENTITY

SPINDLED = None
CASES = {}


def case(fn):
    CASES[fn.__name__] = fn
    return fn


class Daemon:
    def __init__(self, *settings, name='d', preexec=None, env=None):
        self.tmp = tempfile.mkdtemp(prefix='spindle-conf-')
        os.chmod(self.tmp, 0o755)
        self.sock = os.path.join(self.tmp, 'spindle.sock')
        self.logpath = os.path.join(self.tmp, 'spindled.log')
        args = [SPINDLED, '-c', '/dev/null', '--device', 'sim', '--profile', 'small',
                '--renderer', 'cpu', '-s', self.sock, '--set', 'render-threads=2']
        for s in settings:
            args += ['--set', s]
        self.args = args
        self.log = open(self.logpath, 'w')
        self.proc = subprocess.Popen(args, stderr=self.log, stdout=self.log, preexec_fn=preexec,
                                     env=dict(os.environ, **env) if env else None)
        self.pid = self.proc.pid
        end = time.monotonic() + 20
        while True:
            if self.proc.poll() is not None:
                raise AssertionError(f'spindled exited {self.proc.returncode} at start: {self.logtext()}')
            if os.path.exists(self.sock):
                try:
                    c = Conn(self.sock)
                    c.close()
                    break
                except OSError:
                    pass
            if time.monotonic() > end:
                raise AssertionError('spindled never served its socket')
            time.sleep(0.02)
        os.chmod(self.sock, 0o777)

    def logtext(self):
        self.log.flush()
        with open(self.logpath) as f:
            return f.read()

    def conn(self, version=None, hello=True):
        c = Conn(self.sock)
        if hello:
            c.hello(version)
        return c

    def nfds(self):
        return len(os.listdir(f'/proc/{self.pid}/fd'))

    def rss_kb(self):
        with open(f'/proc/{self.pid}/status') as f:
            for line in f:
                if line.startswith('VmRSS:'):
                    return int(line.split()[1])
        return 0

    def alive(self):
        return self.proc.poll() is None

    def stop(self):
        """SIGTERM; the daemon must exit 0 (a sanitizer report fails it)."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                rc = self.proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
                raise AssertionError('spindled did not exit within 20 s of SIGTERM')
        else:
            rc = self.proc.returncode
        text = self.logtext()
        self.log.close()
        shutil.rmtree(self.tmp, ignore_errors=True)
        bad = [l for l in text.splitlines() if 'runtime error:' in l or 'AddressSanitizer' in l
               or 'LeakSanitizer' in l]
        if rc != 0 or bad:
            raise AssertionError(f'spindled exit status {rc} after SIGTERM; log:\n{text[-6000:]}')


def axis_line(half=0.5):
    return w.vertices([(0.0, -half, 0.0), (0.0, half, 0.0)])


class Witness:
    """A client connected throughout an abuse case, with a committed scene:
    it must keep getting answers and its scene must keep showing."""

    def __init__(self, d):
        self.d = d
        self.c = d.conn(1)   # version 1: also checks no newer event reaches it
        c = self.c
        self.buf = c.buffer(w.vertices([(0.0, -0.6, 0.0), (0.0, 0.6, 0.0), (0.5, 0.0, 0.0), (0.5, 0.4, 0.0)]))
        self.lst = c.create('create_list')
        self.layer = c.create('create_layer')
        c.req(self.lst, 'list.set_color', 0xffffffff)
        c.req(self.lst, 'list.draw', MODE['lines'], self.buf, 0, 4, 0)
        c.req(self.layer, 'layer.set_list', self.lst)
        c.frame_commit()
        self.svol = svol_planes(c.capture())
        check(lit(self.svol) > 0, 'the witness scene lights voxels')

    def check(self, exact=True):
        """A sync roundtrip and a capture still showing the scene (exactly the
        first capture, when nobody else shows anything). A client that just
        left may still show in the volume on display: a frame callback on an
        empty commit, then captures for up to 2 s."""
        self.c.sync()
        self.c.frame_commit()
        end = time.monotonic() + 2
        while True:
            cap = self.c.capture()
            check(isinstance(cap, bytes), f'witness capture: {cap}')
            planes = svol_planes(cap)
            ok = planes == self.svol if exact else covers(planes, self.svol)
            if ok or time.monotonic() > end:
                break
        check(ok, 'the witness scene shows as before' if exact else 'the witness scene still shows')
        check(not self.c.errors() and not self.c.eof, f'witness untouched: {self.c.errors()}')


def svol_header(data):
    check(data[:4] == b'SVOL', f'svol magic {data[:4]!r}')
    v, hs, W, H, n, N, planes, flags = struct.unpack_from('<HHIIIIBB', data, 4)
    check(v == 1 and hs == 64 and planes == 3, 'svol header')
    h, = struct.unpack_from('<f', data, 28)
    seq, t = struct.unpack_from('<QQ', data, 32)
    rowbytes = (W + 7) // 8
    check(len(data) == 64 + n * 3 * H * rowbytes, f'svol size {len(data)} for {n} images {W}x{H}')
    return dict(W=W, H=H, images=n, N=N, flags=flags, h=h, seq=seq, time=t)


def svol_planes(data):
    check(isinstance(data, bytes), f'capture: {data}')
    svol_header(data)
    return data[64:]


def lit(planes):
    return sum(bin(b).count('1') for b in planes)


def covers(a, b):
    """Every bit set in b is set in a."""
    return all((x & y) == y for x, y in zip(a, b))


class CheckFailed(AssertionError):
    pass


def check(cond, what):
    if not cond:
        raise CheckFailed(what)


def settle_fds(d, before, timeout=3.0):
    """The daemon's fd count goes back to before (closing takes a loop turn)."""
    end = time.monotonic() + timeout
    while True:
        n = d.nfds()
        if n <= before:
            return
        if time.monotonic() > end:
            fds = {f: os.readlink(f'/proc/{d.pid}/fd/{f}') for f in os.listdir(f'/proc/{d.pid}/fd')}
            raise CheckFailed(f'daemon fds {before} -> {n}: {fds}')
        time.sleep(0.02)


class Abuse:
    """with Abuse(d, witness) as a: c = a.conn(); ... c.expect_fatal(...):
    on leaving, the witness is served, its scene shows, and the daemon holds
    no more fds than before."""

    def __init__(self, d, witness, exact=True):
        self.d, self.witness, self.exact = d, witness, exact
        self.conns = []

    def __enter__(self):
        self.before = self.d.nfds()
        return self

    def conn(self, version=None, hello=True):
        c = self.d.conn(version, hello)
        self.conns.append(c)
        return c

    def __exit__(self, typ, val, tb):
        for c in self.conns:
            c.close()
        if typ is None:
            check(self.d.alive(), 'the daemon is running')
            self.witness.check(self.exact)
            settle_fds(self.d, self.before)
        return False


SHARED = {}


NOBODY = 65534  # nobody: no capture, watch or admin rights


def connect_as(uid, path, n):
    """n sockets connected to path by uid (a forked child that dropped to
    it, connected, and passed them back over a socketpair)."""
    a, b = socket.socketpair(socket.AF_UNIX, socket.SOCK_STREAM)
    pid = os.fork()
    if pid == 0:
        a.close()
        code = 0
        try:
            os.setgroups([])
            os.setresgid(uid, uid, uid)
            os.setresuid(uid, uid, uid)
            socks = []
            for _ in range(n):
                s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
                s.connect(path)
                socks.append(s)
            socket.send_fds(b, [b'x'], [s.fileno() for s in socks])
        except BaseException:
            code = 1
        os._exit(code)
    b.close()
    _, fds, _, _ = socket.recv_fds(a, 1, n)
    a.close()
    _, status = os.waitpid(pid, 0)
    check(status == 0 and len(fds) == n, f'child connecting as uid {uid} failed')
    return [Conn(path, sock=socket.socket(fileno=fd)) for fd in fds]


def shared(*settings):
    """A daemon and witness shared by the cases of one script (the abuse
    cases each leave it as they found it); stopped and checked by run()."""
    if settings not in SHARED:
        d = Daemon(*settings)
        SHARED[settings] = (d, Witness(d))
    return SHARED[settings]


def run_as(uid, gid, groups, fn):
    """fn() in a forked child that dropped to uid/gid/groups first; returns
    what fn returned (repr-able), or raises what it raised, as text."""
    r, wfd = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(r)
        try:
            os.setgroups(groups)
            os.setresgid(gid, gid, gid)
            os.setresuid(uid, uid, uid)
            out = 'ok ' + repr(fn())
        except BaseException:
            out = 'exc ' + traceback.format_exc()
        os.write(wfd, out.encode())
        os._exit(0)
    os.close(wfd)
    chunks = []
    while True:
        b = os.read(r, 65536)
        if not b:
            break
        chunks.append(b)
    os.close(r)
    os.waitpid(pid, 0)
    out = b''.join(chunks).decode()
    if not out.startswith('ok '):
        raise CheckFailed(f'unprivileged child: {out}')
    return eval(out[3:])


def run(default_cases=None):
    """main(): argv[1] is spindled, then optional case names."""
    global SPINDLED
    SPINDLED = sys.argv[1]
    names = sys.argv[2:] or list(CASES)
    failed = []
    for n in names:
        t0 = time.monotonic()
        try:
            CASES[n]()
            print(f'ok   {n} ({time.monotonic() - t0:.1f} s)', flush=True)
        except Exception:
            failed.append(n)
            print(f'FAIL {n} ({time.monotonic() - t0:.1f} s)', flush=True)
            traceback.print_exc()
            sys.stdout.flush()
    for settings, (d, wit) in SHARED.items():
        try:
            wit.c.close()
            d.stop()
            print(f'ok   shared daemon {list(settings)} exits 0')
        except Exception:
            failed.append('shared-daemon-exit')
            traceback.print_exc()
    print(f'{len(names) - len(failed)} passed, {len(failed)} failed' + (f': {" ".join(failed)}' if failed else ''))
    sys.exit(1 if failed else 0)


def with_daemon(*settings):
    """Decorator: the case gets a fresh daemon (and a witness), and fails if
    the daemon does not exit cleanly afterwards."""
    def wrap(fn):
        def run_case():
            d = Daemon(*settings)
            try:
                fn(d)
            except BaseException:
                try:
                    d.stop()
                except AssertionError as e:
                    print(e)
                raise
            d.stop()
        run_case.__name__ = fn.__name__
        return case(run_case)
    return wrap


__all__ = ['shared', 'run_as', 'Daemon', 'Witness', 'Abuse', 'check', 'case', 'run', 'with_daemon', 'svol_planes',
           'lit', 'covers', 'settle_fds', 'axis_line', 'w', 'Conn', 'P', 'ERR', 'MODE', 'IDENTITY']
