#!/usr/bin/env python3
"""spindled as a service: sd_notify readiness and stopping, systemd socket
activation (through systemd-socket-activate when installed), the config file
and its errors. Usage: test-service.py SPINDLED SPINDLECTL"""
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

spindled, ctl = sys.argv[1:3]
tmp = tempfile.mkdtemp(prefix='spindle-service-')
checks = 0


def check(cond, what):
    global checks
    if not cond:
        print('FAIL:', what)
        sys.exit(1)
    checks += 1


def wait_for(path):
    for _ in range(500):
        if os.path.exists(path):
            return
        time.sleep(0.01)
    check(False, f'{path} never appeared')


def status(sock):
    p = subprocess.run([ctl, '--socket', sock, 'status'], capture_output=True, text=True, timeout=30)
    check(p.returncode == 0, f'spindlectl status: {p.stderr}')
    return dict(l.split(': ', 1) for l in p.stdout.splitlines() if ': ' in l)


def test_notify():
    """READY=1 once serving, STOPPING=1 on SIGTERM, exit 0."""
    path = os.path.join(tmp, 'notify')
    sock = os.path.join(tmp, 'n.sock')
    notify = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    notify.bind(path)
    notify.settimeout(10)
    env = dict(os.environ, NOTIFY_SOCKET=path)
    d = subprocess.Popen([spindled, '-p', 'small', '-s', sock, '-c', '/dev/null'], env=env,
                         stderr=subprocess.DEVNULL)
    msg = notify.recv(4096).decode()
    check('READY=1' in msg, f'first notification {msg!r}')
    check(status(sock)['width'] == '128', 'serving once ready')
    d.send_signal(signal.SIGTERM)
    msgs = ''
    while 'STOPPING=1' not in msgs:
        msgs += notify.recv(4096).decode()
    check(d.wait(timeout=10) == 0, 'exit status 0 on SIGTERM')
    check(not os.path.exists(sock), 'socket removed')
    notify.close()


def test_socket_activation():
    """systemd passes the listening socket; spindled serves on it."""
    activate = shutil.which('systemd-socket-activate')
    if not activate:
        print('systemd-socket-activate not installed: socket activation not tested')
        return
    sock = os.path.join(tmp, 'a.sock')
    log = os.path.join(tmp, 'a.log')
    with open(log, 'w') as f:
        # (systemd-socket-activate passes no environment, SPINDLE_USER neither)
        d = subprocess.Popen([activate, '-l', sock, spindled, '-p', 'small', '-c', '/dev/null', '--user', 'root'],
                             stderr=f)
    wait_for(sock)
    check(status(sock)['images per revolution'] == '128', 'status over the activated socket')
    d.send_signal(signal.SIGTERM)
    check(d.wait(timeout=10) == 0, 'activated daemon exits 0')
    with open(log) as f:
        check('socket from systemd' in f.read(), 'took the socket from systemd')


def test_config():
    """Keys from the file, overridden by options; bad files refused."""
    sock = os.path.join(tmp, 'c.sock')
    conf = os.path.join(tmp, 'spindled.conf')
    with open(conf, 'w') as f:
        f.write('# test\nprofile = small\n  max-clients = 8  # trailing comment\nrenderer=cpu\n'
                'render-threads = 1\nprojector-buffers = 2\n')
    d = subprocess.Popen([spindled, '-c', conf, '-s', sock], stderr=subprocess.DEVNULL)
    wait_for(sock)
    check(status(sock)['width'] == '128', 'profile from the config file')
    d.send_signal(signal.SIGTERM)
    check(d.wait(timeout=10) == 0, 'exit 0')

    for text, needle in (('profile small\n', 'expected key = value'),
                         ('colour = blue\n', "unknown key 'colour'"),
                         ('max-clients = -3\n', "bad value for 'max-clients'"),
                         ('projector-buffers = 7\n', "bad value for 'projector-buffers'"),
                         ('renderer = vulkan\n', "bad value for 'renderer'")):
        with open(conf, 'w') as f:
            f.write(text)
        p = subprocess.run([spindled, '-c', conf, '-s', sock], capture_output=True, text=True, timeout=10)
        check(p.returncode == 2 and needle in p.stderr, f'{text!r}: exit 2 with {needle!r}: {p.stderr!r}')
    # Every renderer name is accepted, from the file or the command line;
    # one that can't run here falls back to the CPU renderer with a warning.
    for name in ('auto', 'cpu', 'egl', 'osmesa'):
        with open(conf, 'w') as f:
            f.write(f'profile = small\nrenderer = {name}\n')
        log = os.path.join(tmp, f'r-{name}.log')
        for args in (['-c', conf], ['-c', '/dev/null', '-p', 'small', '--renderer', name]):
            if os.path.exists(sock):
                os.unlink(sock)
            with open(log, 'w') as f:
                d = subprocess.Popen([spindled, '-s', sock] + args, stderr=f)
            wait_for(sock)
            check(status(sock)['width'] == '128', f'serving with renderer {name}')
            d.send_signal(signal.SIGTERM)
            check(d.wait(timeout=10) == 0, f'renderer {name}: exit 0')
            with open(log) as f:
                text = f.read()
            ran = [l.split('renderer: ', 1)[1] for l in text.splitlines() if 'info: renderer: ' in l]
            check(len(ran) == 1, f'renderer {name}: one "renderer: NAME" line in {text!r}')
            if name in ('egl', 'osmesa') and ran[0] != name:
                check(f"renderer '{name}' unavailable" in text and ran[0] == 'cpu',
                      f'renderer {name} unavailable: a warning and the CPU renderer: {text!r}')
            elif name != 'auto':
                check(ran[0] == name, f'renderer {name} runs: {text!r}')
    p = subprocess.run([spindled, '-c', os.path.join(tmp, 'missing.conf')], capture_output=True,
                       text=True, timeout=10)
    check(p.returncode == 2, 'a named config file that is missing is an error')
    p = subprocess.run([spindled, '-p', 'huge', '-s', sock, '-c', '/dev/null'], capture_output=True,
                       text=True, timeout=10)
    check(p.returncode == 2 and "bad value for 'profile' (one of: perspecta, small)" in p.stderr,
          f'unknown profile: exit 2 naming the profiles: {p.returncode} {p.stderr!r}')
    p = subprocess.run([spindled, '-r', 'vulkan', '-s', sock, '-c', '/dev/null'], capture_output=True,
                       text=True, timeout=10)
    check(p.returncode == 2 and "(one of: auto, cpu, egl, osmesa)" in p.stderr,
          f'unknown renderer: exit 2 naming the renderers: {p.returncode} {p.stderr!r}')



def test_hardware_config():
    """device = hw: a sync line that cannot be opened is an error at start,
    naming it; --blank with no projector attached (none is, here) is fine,
    with device hw and with device sim; bad hw keys are refused."""
    sock = os.path.join(tmp, 'hw.sock')
    p = subprocess.run([spindled, '-s', sock, '-c', '/dev/null', '-p', 'small', '--device', 'hw',
                        '--set', 'sync-chip=spindle-no-such-chip', '--set', 'sync-line=5'],
                       capture_output=True, text=True, timeout=10)
    check(p.returncode != 0 and 'spindle-no-such-chip' in p.stderr, f'hw without a sync line: {p.stderr!r}')
    check(not os.path.exists(sock), 'hw without a sync line: no socket left')
    for device in ('hw', 'sim'):
        p = subprocess.run([spindled, '-c', '/dev/null', '-p', 'small', '--device', device, '--blank'],
                           capture_output=True, text=True, timeout=10)
        check(p.returncode == 0 and 'nothing to blank' in p.stderr, f'--blank, device {device}: {p.stderr!r}')
    for key in ('projector-vid=12345', 'projector-pid=-1', 'sync-active-low=maybe', 'device=usb'):
        p = subprocess.run([spindled, '-c', '/dev/null', '--set', key, '--blank'], capture_output=True,
                           text=True, timeout=10)
        check(p.returncode == 2, f'bad value {key} refused')


test_notify()
test_socket_activation()
test_config()
test_hardware_config()
shutil.rmtree(tmp, ignore_errors=True)
print(f'{checks} passed, 0 failed')
