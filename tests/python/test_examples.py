"""The Python examples (python/examples) answer --help, run for about a
second against spindled and exit 0, and what they show is on the display."""
import os
import subprocess
import sys

import pytest

import spindle

EXAMPLES = os.environ.get('SPINDLE_PY_EXAMPLES') or os.path.join(os.path.dirname(__file__), '..', '..', 'python',
                                                                  'examples')


def run(name, *args, timeout=60):
    return subprocess.run([sys.executable, os.path.join(EXAMPLES, name), *args], capture_output=True, text=True,
                          timeout=timeout)


@pytest.mark.parametrize('name', ['rotating_cloud.py', 'surface.py', 'breathing.py'])
def test_help(name):
    p = run(name, '--help')
    assert p.returncode == 0 and 'usage:' in p.stdout and '--socket' in p.stdout and '--seconds' in p.stdout


@pytest.mark.parametrize('name', ['rotating_cloud.py', 'surface.py', 'breathing.py'])
def test_no_daemon(name, tmp_path):
    p = run(name, '--socket', str(tmp_path / 'none.sock'), '--seconds', '1')
    assert p.returncode == 1 and 'cannot connect' in p.stderr


def test_rotating_cloud(daemon):
    p = run('rotating_cloud.py', '--socket', daemon.sock, '--seconds', '1', '--points', '2000')
    assert p.returncode == 0, p.stdout + p.stderr
    frames = int(p.stdout.split('rotating_cloud: ')[-1].split()[0])
    assert frames >= 3, p.stdout  # about 60 a second here; a loaded (or ASan) machine does fewer


def test_breathing(daemon):
    """Ten phases sent once, then cycled: each shown volume is a phase."""
    p = run('breathing.py', '--socket', daemon.sock, '--seconds', '1', '--size', '24')
    assert p.returncode == 0, p.stdout + p.stderr
    assert 'breathing: 10 phases of 24^3 int16 sent' in p.stdout, p.stdout
    shown = int(p.stdout.split('breathing: ')[-1].split()[0])
    assert shown >= 3, p.stdout  # about 60 a second at the small profile; a loaded (or ASan) machine does fewer


def test_surface(daemon):
    proc = subprocess.Popen([sys.executable, os.path.join(EXAMPLES, 'surface.py'), '--socket', daemon.sock,
                             '--seconds', '1.5', '--function', 'saddle', '--grid', '24'],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    line = proc.stdout.readline()
    assert line.startswith('surface: 1058 triangles shown in volume'), line + proc.stderr.read()
    with spindle.connect(daemon.sock) as sp:
        cap = sp.capture()
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, out + err
    # The saddle x^2 - y^2 fitted (the function's x along x, its y along z,
    # its value up): the centre in the middle, the top at x = +-1, the bottom
    # at y = +-1.
    h = cap.half_height
    assert cap.lit_at((0, 0, 0))
    side = 0.97 / 2**0.5
    assert cap.lit_at((side, 0.9 * h, 0), radius=2) and cap.lit_at((0, -0.9 * h, side), radius=2)
    # Coloured by height: red at the top, blue at the bottom.
    assert cap.lit_at((side, 0.9 * h, 0), radius=2, channel=0)
    assert cap.lit_at((0, -0.9 * h, side), radius=2, channel=2)


def test_surface_expression(daemon):
    p = run('surface.py', '--socket', daemon.sock, '--seconds', '0.5', '--expr', 'np.sin(3 * x) * y', '--grid', '8')
    assert p.returncode == 0 and '98 triangles' in p.stdout, p.stdout + p.stderr
    p = run('surface.py', '--socket', daemon.sock, '--seconds', '0.5', '--expr', '1 / (x - x)')
    assert p.returncode == 1 and 'not finite' in p.stderr
