"""Fixtures of the Python binding's tests: spindled on the simulated device
(small profile, the CPU renderer, brightness exact: every voxel a primitive
touches is lit), each in its own folder.

The environment (python/meson.build sets it): SPINDLED (the daemon),
SPINDLE_LIBRARY (libspindle of the build), PYTHONPATH (the source python/
folder), SPINDLE_PROTO_XML, SPINDLE_LAYOUT (tests/python/layout.c built) and
SPINDLE_PY_EXAMPLES (python/examples).
"""
import getpass
import os
import signal
import socket
import subprocess
import time

import pytest


class Daemon:
    """A spindled: ``sock`` its socket path, ``proc`` its process, ``log`` its stderr's file."""

    def __init__(self, tmp, *extra):
        self.sock = str(tmp / 's.sock')
        self.log = str(tmp / 'spindled.log')
        env = dict(os.environ)
        # The daemon is linked with what it needs (ASan included): the
        # preloaded runtime is for python.
        env.pop('LD_PRELOAD', None)
        cmd = [
            os.environ['SPINDLED'], '--device', 'sim', '--profile', 'small', '--renderer', 'cpu', '--socket',
            self.sock, '--user',
            getpass.getuser(), '--config', '/dev/null', '--set', 'brightness=exact', *extra
        ]
        with open(self.log, 'w') as log:
            self.proc = subprocess.Popen(cmd, stdout=log, stderr=log, env=env)
        self._wait_socket()

    def _wait_socket(self):
        end = time.monotonic() + 20
        while time.monotonic() < end:
            if self.proc.poll() is not None:
                raise RuntimeError(f'spindled exited {self.proc.returncode}: {self.tail()}')
            try:
                with socket.socket(socket.AF_UNIX) as s:
                    s.connect(self.sock)
                    return
            except OSError:
                time.sleep(0.01)
        raise RuntimeError(f'spindled did not listen in 20 s: {self.tail()}')

    def tail(self):
        """The end of the daemon's log."""
        with open(self.log, errors='replace') as f:
            return f.read()[-2000:]

    def kill(self):
        """SIGKILL, and reap."""
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait(timeout=10)

    def stop(self):
        """SIGTERM; fails the test unless it exits 0."""
        if self.proc.poll() is not None:
            return self.proc.returncode
        self.proc.send_signal(signal.SIGTERM)
        try:
            return self.proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            return 'hung'


@pytest.fixture
def start_daemon(tmp_path_factory):
    """start_daemon(*extra_spindled_args) -> Daemon; every daemon started is
    stopped after the test (and must exit 0 unless killed)."""
    started = []

    def start(*extra):
        d = Daemon(tmp_path_factory.mktemp('spindled'), *extra)
        started.append(d)
        return d

    yield start
    for d in started:
        killed = d.proc.returncode is not None and d.proc.returncode < 0
        rc = d.stop()
        if not killed:
            assert rc == 0, f'spindled exited {rc}: {d.tail()}'


@pytest.fixture
def daemon(start_daemon):
    """A spindled with the default limits."""
    return start_daemon()


@pytest.fixture
def sp(daemon):
    """A connection to the daemon fixture, closed after the test."""
    import spindle
    with spindle.connect(daemon.sock) as conn:
        yield conn
