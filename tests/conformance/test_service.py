#!/usr/bin/env python3
"""The daemon as a service no local user can lock out: the client limits
(one slot kept for an admin, per user, connections still in their
handshake, the handshake timeout), running out of fds (accepting pauses,
serving goes on, it recovers by itself) and the signals that must take the
shutdown path. The unprivileged attacker is uid 65534, connected by a child
that dropped to it and handed its sockets back (the daemon knows a peer by
its credentials at connect); those cases need root and are skipped
without it."""
import os
import resource
import shutil
import signal
import socket
import subprocess
import tempfile
import threading
import time

import harness

from harness import Abuse, Daemon, ERR, NOBODY, Witness, case, check, connect_as, run, settle_fds, w, with_daemon
from spindlewire import Closed, Conn

def refused(c, timeout=3.0):
    """Whether the daemon refused c (too_many_clients, then EOF) rather than
    serving it (nothing within timeout)."""
    try:
        c.expect_fatal(ERR['too_many_clients'], timeout=timeout)
        return True
    except AssertionError as e:
        if 'expected display.error' in str(e) and not c.eof:
            return False
        raise


def privileged():
    if os.geteuid() != 0:
        print('  skipped: needs root to connect as another user')
        return False
    return True


@with_daemon('max-clients=8', 'handshake-timeout-ms=60000')
def idle_lockout(d):
    """Idle connections of a user fill all but the admin's slot;
    `spindlectl status` (an admin) still gets in."""
    if not privileged():
        return
    wit = Witness(d)                      # client 1 (root)
    before = d.nfds()
    idle = connect_as(NOBODY, d.sock, 10)  # room for 6: one slot is kept
    verdicts = [refused(c, 0.5) for c in idle]
    check(verdicts.count(False) == 6 and verdicts.count(True) == 4, f'admitted/refused: {verdicts}')
    admin = d.conn()                      # client 8: the kept slot
    st = admin.status()
    check(st['clients'] >= 2, f'status answered: {st}')
    over = Conn(d.sock)                   # a ninth: nobody's slot left
    check(refused(over), 'the ninth connection is refused')
    over.close()
    for c in idle:
        c.close()
    admin.close()
    wit.check()
    settle_fds(d, before)
    check('over max-clients' in d.logtext() or 'too many clients' in d.logtext(), 'refusals are logged')


@with_daemon('max-clients-per-user=3', 'max-incomplete-clients=100', 'handshake-timeout-ms=60000')
def per_user_cap(d):
    if not privileged():
        return
    wit = Witness(d)
    before = d.nfds()
    mine = connect_as(NOBODY, d.sock, 5)
    verdicts = [refused(c, 0.5) for c in mine]
    check(verdicts == [False, False, False, True, True], f'per user: {verdicts}')
    for c in mine[:3]:
        c.hello()
        c.sync()
    other = connect_as(NOBODY - 1, d.sock, 1)[0]   # another user is not affected
    other.hello()
    other.sync()
    for c in mine + [other]:
        c.close()
    wit.check()
    settle_fds(d, before)


@with_daemon('max-incomplete-clients=3', 'max-clients-per-user=100', 'handshake-timeout-ms=60000')
def incomplete_cap(d):
    if not privileged():
        return
    wit = Witness(d)
    before = d.nfds()
    first = connect_as(NOBODY, d.sock, 4)
    verdicts = [refused(c, 0.5) for c in first]
    check(verdicts == [False, False, False, True], f'in handshake: {verdicts}')
    first[0].hello()                    # one completes: room for another
    late = connect_as(NOBODY, d.sock, 1)[0]
    check(not refused(late, 0.5), 'admitted once one completed its handshake')
    late.hello()
    late.sync()
    for c in first + [late]:
        c.close()
    wit.check()
    settle_fds(d, before)


@with_daemon('handshake-timeout-ms=300')
def handshake_timeout(d):
    """No hello in time: the version error, then closed; whoever it is."""
    wit = Witness(d)
    with Abuse(d, wit) as a:
        quiet = a.conn(hello=False)
        t0 = time.monotonic()
        ev = quiet.expect_fatal(ERR['version'], obj=1, timeout=3.0)
        took = time.monotonic() - t0
        check(0.25 <= took <= 2.0, f'closed after {took:.2f} s')
        check('hello' in ev['message'], f'says why: {ev}')
        prompt = a.conn()                 # a client that said hello stays
        time.sleep(0.6)
        prompt.sync()
    if privileged():
        other = connect_as(NOBODY, d.sock, 1)[0]
        other.expect_fatal(ERR['version'], obj=1, timeout=3.0)
        other.close()


def daemon_cpu_s(d):
    with open(f'/proc/{d.pid}/stat') as f:
        fields = f.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


class ServiceManager:
    """systemd's side of sd_notify(): a datagram socket the daemon is
    told of (NOTIFY_SOCKET, and WATCHDOG_USEC when watchdog_us), drained by
    a thread that notes when each message came."""
    def __init__(self, watchdog_us=None):
        self.dir = tempfile.mkdtemp(prefix='spindle-notify-')
        os.chmod(self.dir, 0o755)
        self.path = os.path.join(self.dir, 'notify')
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        self.sock.bind(self.path)
        os.chmod(self.path, 0o777)       # the daemon may have dropped root
        self.sock.settimeout(0.1)
        self.messages = []               # (monotonic time, text)
        self.env = {'NOTIFY_SOCKET': self.path}
        if watchdog_us:
            self.env['WATCHDOG_USEC'] = str(watchdog_us)
        self.running = True
        self.thread = threading.Thread(target=self._drain, daemon=True)
        self.thread.start()

    def _drain(self):
        while self.running:
            try:
                data = self.sock.recv(4096)
            except socket.timeout:
                continue
            except OSError:
                break
            self.messages.append((time.monotonic(), data.decode(errors='replace')))

    def feeds(self, start=0.0, end=float('inf')):
        return sum(1 for t, m in self.messages if start <= t < end and 'WATCHDOG=1' in m.split('\n'))

    def said(self, what):
        return any(what in m.split('\n') for _, m in self.messages)

    def close(self):
        self.running = False
        self.thread.join()
        self.sock.close()
        shutil.rmtree(self.dir, ignore_errors=True)


def small_fd_limit():
    resource.setrlimit(resource.RLIMIT_NOFILE, (96, 96))


@case
def fd_exhaustion():
    """Out of fds: the daemon stops accepting for a while instead of
    spinning on accept(), reaps and serves meanwhile, and accepts again by
    itself once fds are free (EMFILE forced with RLIMIT_NOFILE = 96)."""
    sm = ServiceManager(watchdog_us=1000000)     # fed every 0.25 s while making progress
    d = Daemon('max-clients=1000', 'max-clients-per-user=1000', 'max-incomplete-clients=1000',
               'handshake-timeout-ms=60000', preexec=small_fd_limit, env=sm.env)
    try:
        wit = Witness(d)
        attack = time.monotonic()
        socks = []
        last = time.monotonic()
        while len(socks) < 300 and time.monotonic() - last < 1.0:   # until the backlog stays full
            s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            s.setblocking(False)
            try:
                s.connect(d.sock)
            except BlockingIOError:
                s.close()
                time.sleep(0.01)
                continue
            socks.append(s)
            last = time.monotonic()
        check(len(socks) > 96, f'{len(socks)} connections: more than the daemon has fds for')
        time.sleep(0.5)
        cpu0 = daemon_cpu_s(d)
        time.sleep(2.0)
        cpu = (daemon_cpu_s(d) - cpu0) / 2.0
        log = d.logtext()
        check('not accepting clients' in log, 'the pause is logged')
        check(log.count('accept:') <= 10, f'logged {log.count("accept:")} times: no flood')
        check(cpu < 0.5, f'daemon at {cpu:.0%} of a core while out of fds: no busy loop')
        wit.c.sync()                        # served meanwhile
        for s in socks:
            s.close()
        end = time.monotonic() + 5
        while True:                         # it recovers by itself
            try:
                c = Conn(d.sock)
                c.hello(timeout=1.0)
                c.sync()
                c.close()
                break
            except (OSError, Closed, TimeoutError, AssertionError):
                check(time.monotonic() < end, 'accepting again within 5 s of the fds coming free')
                time.sleep(0.1)
        wit.check()
        fed = sm.feeds(attack, time.monotonic())
        took = time.monotonic() - attack
        check(fed >= took / 0.25 / 2, f'the watchdog was fed {fed} times in {took:.1f} s: the daemon made progress')
        check('watchdog not fed' not in d.logtext(), 'never withheld')
        print(f'  daemon CPU {cpu:.1%} of a core while out of fds; watchdog fed {fed} times in {took:.1f} s')
        d.proc.send_signal(signal.SIGTERM)
        d.proc.wait(timeout=20)
        check('accepting paused' in d.logtext(), 'the pauses are counted in the log at exit')
        check(sm.said('STOPPING=1'), 'STOPPING=1 at exit')
    finally:
        d.stop()
        sm.close()


@with_daemon('max-client-fds=8')
def client_fd_cap(d):
    """max-client-fds = 8: two syncs with 4 memfds each are held ahead
    of their messages; a third is one too many (bad_fd, disconnected); the
    others are served throughout and the fds go back to baseline."""
    wit = Witness(d)
    before = d.nfds()
    ok, over = d.conn(), d.conn()
    for c, n in ((ok, 2), (over, 3)):
        for _ in range(n):
            fds = [w.memfd(bytes(12)) for _ in range(4)]
            cb = c.new_id()
            c.objects[cb] = 'callback'
            w.send_ignoring_close(c, c.encode(1, 'display.sync', cb)[0], fds)
            for fd in fds:
                os.close(fd)
    ok.sync()
    check(not ok.errors() and not ok.eof, f'8 fds ahead: {ok.errors()}')
    over.expect_fatal((ERR['bad_fd'],), (0, 1))
    over.close()
    ok.close()
    wit.check()
    settle_fds(d, before)
    svc = service(d.conn())
    check(svc['max_client_fds'] == 8 and svc['refused_fds'] == 1, f'counted (spindlectl status): {svc}')


@case
def watchdog():
    """WATCHDOG=1 goes out at a quarter of WatchdogSec while the daemon
    makes progress, and is withheld while it does not: a daemon stopped
    (SIGSTOP) for twice its patience finds its state timer late when it
    resumes, says so, and is fed again at the next check."""
    sm = ServiceManager(watchdog_us=400000)
    d = Daemon(env=sm.env)
    try:
        wit = Witness(d)
        t0 = time.monotonic()
        time.sleep(1.0)
        fed = sm.feeds(t0, time.monotonic())
        check(sm.said('READY=1'), 'READY=1')
        check(fed >= 4, f'fed {fed} times in 1 s (every 0.1 s expected)')
        d.proc.send_signal(signal.SIGSTOP)
        time.sleep(0.5)
        d.proc.send_signal(signal.SIGCONT)
        t1 = time.monotonic()
        time.sleep(1.0)
        log = d.logtext()
        check('watchdog not fed: the event loop is not serving' in log, f'withheld after the stop: {log[-2000:]}')
        check('making progress again' in log, 'fed again')
        fed = sm.feeds(t1, time.monotonic())
        check(fed >= 4, f'fed {fed} times in the second after')
        svc = service(d.conn())
        check(svc['watchdog_ms'] == 400 and svc['watchdog_withheld'] >= 1 and svc['watchdog_fed'] >= 8,
              f'counted (spindlectl status): {svc}')
        wit.check()
        print(f'  watchdog: 400 ms, fed {fed} times in the second after a 0.5 s stop')
    finally:
        d.stop()
        sm.close()


def limits(c):
    """display.limits, which comes just before status (version 3)."""
    c.req(1, 'display.get_status')
    lim = c.wait('display.limits')
    c.wait('display.status')
    return lim


def service(c):
    """display.service, which comes before status (version 4)."""
    c.req(1, 'display.get_status')
    svc = c.wait('display.service')
    c.wait('display.status')
    return svc


def memfd_buffer(c, size):
    fd = w.memfd(size=size)
    try:
        return c.create('create_buffer', size, fd)
    finally:
        os.close(fd)


@with_daemon('memory-budget=8388608')
def memory_budget(d):
    """The daemon-wide memory budget refuses the client that would go over
    it (quota, fatal), not the daemon; room comes back when others go."""
    wit = Witness(d)
    base = d.rss_kb()
    with Abuse(d, wit) as a:
        big = a.conn()
        memfd_buffer(big, 6 << 20)
        big.sync()
        over = a.conn()
        memfd_buffer(over, 4 << 20)
        ev = over.expect_fatal(ERR['quota'], obj=1)
        check('memory budget' in ev['message'], f'says why: {ev}')
        grew = (d.rss_kb() - base) / 1024
        check(grew <= 8 + 48, f'RSS grew {grew:.1f} MiB under an 8 MiB budget (sanitizers take some)')
        lim = limits(a.conn())
        check(lim['refused_memory'] == 1 and lim['memory_budget'] == 8 << 20 and lim['memory_used'] >= 6 << 20,
              f'limits: {lim}')
        big.close()
        end = time.monotonic() + 3
        while limits(a.conn())['memory_used'] >= 6 << 20:
            check(time.monotonic() < end, 'the budget is given back when the client goes')
            time.sleep(0.05)
        again = a.conn()
        memfd_buffer(again, 4 << 20)
        again.sync()


@with_daemon('max-mappings=4')
def mapping_budget(d):
    wit = Witness(d)                      # one mapped buffer
    with Abuse(d, wit) as a:
        c = a.conn()
        for _ in range(3):
            memfd_buffer(c, 4096)
        c.sync()
        memfd_buffer(c, 4096)
        ev = c.expect_fatal(ERR['quota'], obj=1)
        check('maps as many buffers' in ev['message'], f'says why: {ev}')
        lim = limits(a.conn())
        check(lim['refused_mappings'] == 1 and lim['mapping_budget'] == 4, f'limits: {lim}')
        inline = a.conn()                 # inline buffers are not mappings
        inline.create('create_buffer_inline', b'\0' * 64)
        inline.sync()


@with_daemon('max-clients=8', 'handshake-timeout-ms=60000')
def limits_reported(d):
    """What the limits did is in the limits event (spindlectl status)."""
    if not privileged():
        return
    # The admin's connection first, and no other: Daemon's readiness probe
    # is a connection too, counted until the daemon has seen it close (on a
    # loaded machine, after the 9 below arrived: 3 refused, not 2).
    admin = d.conn()
    end = time.monotonic() + 5
    while limits(admin)['clients_in_handshake'] != 0:
        check(time.monotonic() < end, 'the readiness probe is never reaped')
        time.sleep(0.02)
    idle = connect_as(NOBODY, d.sock, 9)
    for c in idle:
        refused(c, 0.3)
    # max-clients 8, one kept for admins: 7 for the others, the admin's
    # connection among them.
    lim = limits(admin)
    check(lim['refused_clients'] == 3 and lim['clients_in_handshake'] == 6, f'limits: {lim}')
    check(0 < lim['fds'] <= lim['fd_limit'], f'fds: {lim}')
    for c in idle:
        c.close()
    admin.close()


def proc_status(pid):
    with open(f'/proc/{pid}/status') as f:
        return dict(line.rstrip('\n').split(':\t', 1) for line in f if ':\t' in line)


@case
def privilege_drop():
    """Started as root with user = nobody: once serving, every uid and gid
    is nobody's, no capability is left, no_new_privs is set; clients are
    served as before. A user that does not exist: it does not start."""
    if not privileged():
        return
    saved = os.environ.get('ASAN_OPTIONS')
    # LeakSanitizer cannot stop the world of a process that gave up root.
    os.environ['ASAN_OPTIONS'] = (saved + ':' if saved else '') + 'detect_leaks=0'
    try:
        d = Daemon('user=nobody')
        try:
            # The socket listens before the drop (the kernel queues
            # connections): a roundtrip is served only once the loop runs,
            # after the drop.
            c = d.conn()
            c.sync()
            c.close()
            st = proc_status(d.pid)
            check(st['Uid'].split() == [str(NOBODY)] * 4, f'Uid: {st["Uid"]}')
            check(st['Gid'].split()[:3] == [str(NOBODY)] * 3, f'Gid: {st["Gid"]}')
            for cap in ('CapEff', 'CapPrm', 'CapAmb'):
                check(int(st[cap], 16) == 0, f'{cap}: {st[cap]}')
            check(st['NoNewPrivs'].strip() == '1', f'NoNewPrivs: {st["NoNewPrivs"]}')
            wit = Witness(d)                # root is still an admin: capture works
            wit.check()
        finally:
            d.stop()
        # It binds its socket before giving up root, so wait for its exit.
        tmp = tempfile.mkdtemp(prefix='spindle-conf-')
        try:
            p = subprocess.run([harness.SPINDLED, '-c', '/dev/null', '--device', 'sim', '--profile', 'small',
                                '--renderer', 'cpu', '-s', os.path.join(tmp, 's.sock'),
                                '--set', 'user=no-such-user-spindle'], capture_output=True, text=True, timeout=30)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        check(p.returncode != 0 and "no user 'no-such-user-spindle'" in p.stderr,
              f'fails closed: exit {p.returncode}: {p.stderr[-500:]}')
    finally:
        if saved is None:
            del os.environ['ASAN_OPTIONS']
        else:
            os.environ['ASAN_OPTIONS'] = saved


@with_daemon()
def sighup_ignored(d):
    d.proc.send_signal(signal.SIGHUP)
    time.sleep(0.3)
    check(d.alive(), 'alive after SIGHUP')
    c = d.conn()
    c.sync()
    c.close()
    check('SIGHUP: ignored' in d.logtext(), 'SIGHUP is logged')


@case
def signals():
    """Each signal whose default would kill the daemon takes the shutdown
    path: exit 0, the socket removed, the reason logged."""
    for sig in (signal.SIGQUIT, signal.SIGUSR1, signal.SIGUSR2, signal.SIGALRM, signal.SIGVTALRM):
        d = Daemon()
        c = d.conn()
        c.sync()
        d.proc.send_signal(sig)
        rc = d.proc.wait(timeout=20)
        check(rc == 0, f'{sig.name}: exit status {rc}')
        check(not os.path.exists(d.sock), f'{sig.name}: the socket is removed')
        check('shutting down' in d.logtext(), f'{sig.name}: logged')
        c.close()
        d.stop()   # checks the log for sanitizer reports, cleans up


if __name__ == '__main__':
    run()
