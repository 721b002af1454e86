#!/usr/bin/env python3
"""Clients: one that stops reading is disconnected (no error event) while
the others are served; the client limit (too_many_clients, before hello);
1,000 connect/hang-up cycles mid-message without fd or memory leaks."""
import errno
import os
import select
import socket
import time

from harness import Abuse, ERR, Witness, check, run, settle_fds, w, with_daemon


def flood(d, wit, name):
    """Sends name requests without reading until the daemon hangs up."""
    with Abuse(d, wit) as a:
        c = a.conn(1)
        msg = c.encode(1, name, 0x100)[0] if name == 'display.sync' else c.encode(1, name)[0]
        c.sock.setblocking(False)
        batch = msg * 256
        end = time.monotonic() + 15
        closed = False
        sent = 0
        while time.monotonic() < end and not closed:
            try:
                sent += c.sock.send(batch)
            except BlockingIOError:
                select.select([], [c.sock], [], 0.05)
                # the witness is still served while the flood goes on
                if sent and sent % 64 == 0:
                    pass
            except OSError as e:
                check(e.errno in (errno.EPIPE, errno.ECONNRESET), f'send: {e}')
                closed = True
        check(closed, f'{name} flood: still connected after {sent} bytes')
        wit.c.sync()
        # What was sent before the hang-up may be read: events, no error
        # among them (read raw: the syncs all reuse one callback id), then EOF.
        c.sock.setblocking(True)
        c.sock.settimeout(10)
        raw = c.buf
        while True:
            try:
                b = c.sock.recv(1 << 16)
            except ConnectionResetError:   # it closed with our requests unread
                break
            if not b:
                break
            raw += b
        errop = w.P.events['display.error'].opcode
        off, n = 0, 0
        while off + 12 <= len(raw):
            obj, op, nfds, size = w.HEADER.unpack_from(raw, off)
            check(size >= 12, f'event size {size}')
            check(not (obj == 1 and op == errop), 'disconnected without an error event')
            off += size
            n += 1
        print(f'  {name}: disconnected after {sent} bytes sent, {n} events read')


@with_daemon()
def slow_reader_status(d):
    flood(d, Witness(d), 'display.get_status')


@with_daemon()
def slow_reader_sync(d):
    flood(d, Witness(d), 'display.sync')


@with_daemon('max-clients=3')
def client_limit(d):
    wit = Witness(d)   # 1
    b = d.conn(2)      # 2
    c = d.conn(1)      # 3
    before = d.nfds()
    for _ in range(3):
        over = w.Conn(d.sock)
        err = over.expect_fatal(ERR['too_many_clients'])
        check(err['object'] in (0, 1), f'{err}')
        check(over.log[0].name == 'display.error', f'error first, before any hello: {over.log}')
        over.close()
    settle_fds(d, before)
    b.sync()
    c.sync()
    wit.check()
    st = c.status()
    check(st['clients'] == 3, f'status clients {st["clients"]}')
    b.close()
    time.sleep(0.1)
    e = d.conn(1)      # a place is free again
    e.sync()
    st = e.status()
    check(st['clients'] == 3, f'status clients {st["clients"]}')
    for x in (c, e):
        x.close()


@with_daemon('max-clients=64')
def connect_kill_cycles(d):
    """1,000 connections hung up mid-message (half a header, half a message,
    a message with fds and half of the next, nothing at all)."""
    wit = Witness(d)
    data = w.vertices([(0.1, 0.1, 0.1)] * 4)
    fd = w.memfd(data)
    hello = w.Conn.encode(None, 1, 'display.hello', 1)[0]
    cb_msg = w.HEADER.pack(1, w.P.request('display.create_buffer').opcode, 1, 24)
    before_fds = d.nfds()
    before_rss = d.rss_kb()
    t0 = time.monotonic()
    connected = 0
    for batch in range(50):
        socks = []
        for i in range(20):
            s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM | socket.SOCK_NONBLOCK)
            for _ in range(200):
                try:
                    s.connect(d.sock)
                    connected += 1
                    break
                except BlockingIOError:   # backlog full: let the daemon catch up
                    time.sleep(0.005)
            k = (batch * 20 + i) % 5
            try:
                if k == 0:
                    s.send(hello[:6])
                elif k == 1:
                    s.send(hello + cb_msg[:14])
                elif k == 2:
                    s.sendmsg([hello + cb_msg + bytes(6)], [(socket.SOL_SOCKET, socket.SCM_RIGHTS,
                                                              bytes(memoryview(__import__('array').array('i', [fd]))))])
                elif k == 3:
                    s.sendmsg([hello[:3]], [(socket.SOL_SOCKET, socket.SCM_RIGHTS,
                                             bytes(memoryview(__import__('array').array('i', [fd, fd]))))])
            except OSError:
                pass   # the daemon may refuse it over max-clients: fine
            socks.append(s)
        for s in socks:
            s.close()
        if batch % 10 == 9:
            wit.c.sync()
    os.close(fd)
    elapsed = time.monotonic() - t0
    wit.check()
    settle_fds(d, before_fds, timeout=5)
    after_rss = d.rss_kb()
    check(connected == 1000, f'{connected} of 1000 connected')
    print(f'  1000 cycles in {elapsed:.1f} s; RSS {before_rss} -> {after_rss} kB')
    check(after_rss - before_rss < 64 * 1024, f'RSS grew by {after_rss - before_rss} kB')
    st = wit.c.status()
    check(st['clients'] == 1, f'status clients {st["clients"]} after the cycles')


if __name__ == '__main__':
    run()
