"""The Python binding (python/spindle) against spindled on the simulated
device: connection and device info, drawing checked in captures (a
triangle, a point cloud, colours per vertex and per primitive, an indexed
mesh, transforms), frame callbacks, typed errors (a fatal protocol error, a
quota, a refused commit, a lost connection) and argument validation."""
import errno
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import spindle
from spindle import transform

SMALL = dict(width=128, height=128, images_per_rev=128, mirrored=True)


def row_of(y, cap):
    return math.floor((cap.half_height - y) / (2 * cap.half_height) * cap.height)


def test_library_is_the_builds():
    assert spindle.load_library() == os.environ['SPINDLE_LIBRARY']
    assert spindle.library_version().count('.') == 2
    with pytest.raises(spindle.LibraryError):
        spindle.load_library('/nonexistent/libspindle.so.0')


def test_loads_by_soname(daemon):
    """As installed: no SPINDLE_LIBRARY, libspindle.so.0 found by the dynamic linker."""
    env = dict(os.environ)
    lib = env.pop('SPINDLE_LIBRARY')
    env['LD_LIBRARY_PATH'] = os.path.dirname(lib)
    code = ('import sys, spindle\n'
            'with spindle.connect(sys.argv[1]) as sp:\n'
            '    print(spindle.load_library(), sp.commit_and_wait().volume_seq)')
    p = subprocess.run([sys.executable, '-c', code, daemon.sock], env=env, capture_output=True, text=True, timeout=60)
    assert p.returncode == 0 and p.stdout.startswith(spindle._lib.SONAME + ' '), p.stdout + p.stderr


def test_connect_and_device_info(sp, daemon):
    d = sp.device
    assert isinstance(d, spindle.DeviceInfo)
    for k, v in SMALL.items():
        assert getattr(d, k) == v
    assert d.images_per_volume == 64
    assert 0 < d.half_height <= 2 and d.rpm == 1800 and d.name
    assert sp.version >= 2 and sp.socket == daemon.sock and not sp.closed
    assert sp.error is None and sp.error_code == 0
    assert isinstance(sp.fileno(), int)
    st = sp.status()
    assert isinstance(st, spindle.Status) and st.clients == 1
    assert st.limits is not None and st.limits.memory_budget > 0
    assert isinstance(sp.state, spindle.State)


def test_connect_with_environment_and_version(daemon, monkeypatch):
    monkeypatch.setenv('SPINDLE_SOCKET', daemon.sock)
    with spindle.connect() as a, spindle.connect(daemon.sock, version=1) as b:
        assert a.version >= 2 and b.version == 1
        assert b.status().clients == 2
        with pytest.raises(spindle.NotSupported):
            b.create_list().set_point_size(2)
        with pytest.raises(spindle.NotSupported):
            b.state


def test_connect_fails_with_no_daemon(tmp_path):
    with pytest.raises(spindle.NotConnected) as e:
        spindle.connect(str(tmp_path / 'none.sock'))
    assert e.value.errno == errno.ENOENT and 'none.sock' in str(e.value)


def test_triangle_shown_and_captured(sp):
    y = 0.25
    tri = np.array([[-0.6, y, -0.4], [0.6, y, -0.4], [0, y, 0.6]])  # float64: converted
    lst = sp.create_list().set_color(255, 255, 255).triangles(tri)
    layer = sp.create_layer(lst)
    assert layer.list is lst and layer.visible
    frame = sp.commit_and_wait()
    assert isinstance(frame, spindle.Frame) and frame.volume_seq > 0
    cap = sp.capture()
    assert (cap.width, cap.height, cap.images, cap.mirrored) == (128, 128, 64, True)
    assert cap.volume_seq >= frame.volume_seq
    # Inside the triangle (barycentric mixes of its corners): lit.
    for w in [(1 / 3, 1 / 3, 1 / 3), (0.6, 0.2, 0.2), (0.2, 0.6, 0.2), (0.2, 0.2, 0.6), (0.45, 0.45, 0.1)]:
        p = np.asarray(w) @ tri
        assert cap.lit_at(p), f'{p} inside the triangle is dark'
    # Outside it, and away from its plane: dark.
    for p in [(0, y, -0.8), (0.7, y, 0.5), (-0.7, y, 0.5), (0, -0.5, 0), (0.3, 0.8, 0.1)]:
        assert not cap.lit_at(p, radius=0, images=0), f'{p} outside the triangle is lit'
    rows = np.nonzero(cap.lit().any(axis=(0, 2)))[0]
    assert len(rows) and abs(rows.min() - row_of(y, cap)) <= 1 and abs(rows.max() - row_of(y, cap)) <= 1
    # White: every channel.
    assert cap.lit_count(0) == cap.lit_count(1) == cap.lit_count(2) > 100
    # Hidden, nothing shows.
    layer.visible = False
    sp.commit_and_wait()
    assert sp.capture().lit_count() == 0


def test_point_cloud_from_numpy(sp):
    rng = np.random.default_rng(7)
    r = np.sqrt(rng.uniform(0.04, 0.8, 300))
    a = rng.uniform(0, 2 * math.pi, 300)
    cloud = np.stack([r * np.cos(a), rng.uniform(-0.8, 0.8, 300), r * np.sin(a)], axis=1)
    red = np.tile(np.array([[255, 0, 0]], dtype=np.uint8), (300, 1))
    with sp.create_buffer(cloud, red) as buf:
        assert buf.format == spindle.VertexFormat.XYZ_RGBA8 and buf.count == 300 and buf.size == 300 * 16
        lst = sp.create_list().set_point_size(2).points(buf)
    sp.create_layer(lst)
    sp.commit_and_wait()
    cap = sp.capture()
    dark = [p for p in cloud if not cap.lit_at(p, channel=0)]
    assert not dark, f'{len(dark)} of 300 points dark, the first {dark[0]}'
    assert cap.lit_count(1) == 0 and cap.lit_count(2) == 0
    # Float colours (0..1), and a float32 Fortran-ordered array: converted.
    lst.clear().points(np.asfortranarray(cloud[:50].astype(np.float32)), np.array([0.0, 0.0, 1.0]))
    sp.commit_and_wait()
    cap = sp.capture()
    assert cap.lit_count(0) == 0 and cap.lit_count(1) == 0
    assert all(cap.lit_at(p, channel=2) for p in cloud[:50])


def test_colours_per_primitive_and_indexed_mesh(sp):
    lower = [[-0.5, -0.4, -0.3], [0.5, -0.4, -0.3], [0, -0.4, 0.5]]
    upper = [[-0.5, 0.4, -0.3], [0.5, 0.4, -0.3], [0, 0.4, 0.5]]
    lst = sp.create_list().triangles(np.array([lower, upper]), np.array([[255, 0, 0], [0, 0, 255]]))
    sp.create_layer(lst)
    sp.commit_and_wait()
    cap = sp.capture()
    centre_lo, centre_hi = np.mean(lower, axis=0), np.mean(upper, axis=0)
    assert cap.lit_at(centre_lo, channel=0) and not cap.lit_at(centre_lo, channel=2)
    assert cap.lit_at(centre_hi, channel=2) and not cap.lit_at(centre_hi, channel=0)
    assert cap.lit_count(1) == 0
    # The same as an indexed mesh: a square of two triangles, green.
    square = np.array([[-0.4, 0.1, -0.4], [0.4, 0.1, -0.4], [0.4, 0.1, 0.4], [-0.4, 0.1, 0.4]])
    lst.clear().mesh(square, [[0, 1, 2], [0, 2, 3]], np.array([[0, 255, 0]] * 4))
    sp.commit_and_wait()
    cap = sp.capture()
    assert cap.lit_count(0) == 0 and cap.lit_count(2) == 0
    for p in [(0.3, 0.1, 0.3), (-0.3, 0.1, -0.3), (-0.3, 0.1, 0.3), (0.3, 0.1, -0.3)]:
        assert cap.lit_at(p, channel=1), f'{p} of the square is dark'
    # Index buffers: 16 bits when they fit, 32 on request.
    assert sp.create_index_buffer([0, 1, 2]).index_type == spindle.IndexType.U16
    big = sp.create_index_buffer(np.array([0, 1, 2]), type=spindle.IndexType.U32)
    assert big.index_type == spindle.IndexType.U32 and big.size == 12
    lst.clear().set_color('#ffffff').draw_indexed(spindle.Mode.TRIANGLES, sp.create_buffer(square), big)
    sp.commit_and_wait()
    assert sp.capture().lit_at((0.3, 0.1, -0.3), channel=0)


def test_transform_update(sp):
    blob = sp.create_list().set_point_size(3).points([0.6, 0.0, 0.0])
    layer = sp.create_layer(blob)
    sp.commit_and_wait()
    cap = sp.capture()
    assert cap.lit_at((0.6, 0, 0)) and not cap.lit_at((0, 0, -0.6))
    # A quarter turn about the axis: x goes to -z.
    layer.transform = transform.rotate_y(math.pi / 2)
    np.testing.assert_allclose(layer.transform, transform.rotate_y(math.pi / 2))
    sp.commit_and_wait()
    cap = sp.capture()
    assert cap.lit_at((0, 0, -0.6)) and not cap.lit_at((0.6, 0, 0), radius=0, images=0)
    # 16 numbers in column-major order, the C API's layout: a move up.
    layer.set_transform([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0.5, 0, 1])
    np.testing.assert_allclose(layer.transform, transform.translate(0, 0.5, 0))
    sp.commit_and_wait()
    cap = sp.capture()
    assert cap.lit_at((0.6, 0.5, 0)) and not cap.lit_at((0.6, 0, 0), radius=0, images=0)
    # The list's own transforms compose with the layer's.
    layer.transform = transform.identity()
    blob.clear().set_point_size(3).set_transform(transform.translate(-0.6, 0, 0))
    with blob.pushed():
        blob.multiply_transform(transform.translate(0.6, -0.5, 0)).points([0.3, 0, 0])  # (0.3, -0.5, 0)
    blob.points([0, 0.5, 0.3])  # (-0.6, 0.5, 0.3)
    sp.commit_and_wait()
    cap = sp.capture()
    assert cap.lit_at((0.3, -0.5, 0)) and cap.lit_at((-0.6, 0.5, 0.3))


def test_frames_paced_by_callbacks(sp):
    lst = sp.create_list().points([0, 0, 0])
    layer = sp.create_layer(lst)
    seen = []
    frames = []
    for i in range(5):
        layer.transform = transform.translate(0.1 * i, 0, 0)
        req = sp.request_frame(seen.append)
        sp.commit()
        frames.append(req.wait(timeout=10))
        assert req.done and req.frame == frames[-1]
    assert seen == frames
    assert all(b.volume_seq > a.volume_seq and b.time_ns > a.time_ns for a, b in zip(frames, frames[1:]))
    # The batch helper: committed at the end of the block, and waited for.
    with sp.batch() as b:
        layer.priority = 5
        layer.transform = transform.scale(0.5)
    assert b.frame.volume_seq > frames[-1].volume_seq and layer.priority == 5
    # dispatch() handles a frame callback in an event loop of one's own.
    req = sp.request_frame()
    sp.commit()
    while not req.done:
        sp.dispatch(timeout=1)
    # An exception in a callback comes out of the call that ran it.
    sp.request_frame(lambda f: 1 / 0)
    layer.visible = False
    sp.commit()
    with pytest.raises(ZeroDivisionError):
        for _ in range(100):
            sp.dispatch(timeout=0.1)
    with pytest.raises(spindle.Timeout):
        sp.request_frame().wait(timeout=0.2)  # nothing committed


def test_callbacks_neither_block_nor_close_at_once(sp):
    layer = sp.create_layer(sp.create_list().points([0, 0, 0]))
    req = sp.request_frame(lambda f: sp.roundtrip())
    sp.commit()
    with pytest.raises(RuntimeError, match='callback'):
        req.wait(timeout=10)
    # close() from a callback: once the call that ran it returns.
    closed_in_callback = []
    req = sp.request_frame(lambda f: (sp.close(), closed_in_callback.append(sp.closed)))
    layer.visible = False
    sp.commit()
    assert req.wait(timeout=10).volume_seq > 0
    assert closed_in_callback == [False] and sp.closed and layer.destroyed


def test_protocol_error_is_typed(sp):
    lst = sp.create_list()
    lst.set_point_size(17)  # the daemon takes 1 to 16
    with pytest.raises(spindle.InvalidValueError) as e:
        sp.roundtrip()
    err = e.value
    assert isinstance(err, spindle.ProtocolError) and isinstance(err, spindle.ConnectionLost)
    assert err.code == 4 and err.name == 'invalid_value' and 'point size 17' in err.message
    assert sp.error_code == 4 and 'point size 17' in sp.error
    # The connection stays broken, with the same error.
    with pytest.raises(spindle.InvalidValueError):
        sp.create_list()
    with pytest.raises(spindle.InvalidValueError):
        lst.set_color(1, 2, 3)


def test_pop_without_push_is_typed(sp):
    sp.create_list().pop()
    with pytest.raises(spindle.InvalidValueError, match='nothing pushed'):
        sp.roundtrip()


def test_quota_error(start_daemon):
    d = start_daemon('--set', 'max-vertices=100')
    with spindle.connect(d.sock) as conn:
        conn.create_list().points(np.zeros((1000, 3)))
        with pytest.raises(spindle.QuotaError) as e:
            conn.roundtrip()
        assert e.value.code == 6 and 'more than 100 vertices' in e.value.message


def test_commit_refused_goes_on(start_daemon):
    d = start_daemon('--set', 'max-primitives=10')
    refusals = []
    with spindle.connect(d.sock) as conn:
        conn.on_refused = lambda code, obj, message: refusals.append((code, obj, message))
        lst = conn.create_list().points(np.zeros((50, 3)))
        conn.create_layer(lst)
        with pytest.raises(spindle.RefusedQuota) as e:
            conn.commit_and_wait()
        assert isinstance(e.value, spindle.CommitRefused) and e.value.code == 1 and e.value.errno == errno.EDQUOT
        assert refusals and refusals[0][0] == spindle.Refusal.QUOTA
        # Not fatal: fewer primitives are shown.
        lst.clear().points(np.zeros((5, 3)))
        assert conn.commit_and_wait().volume_seq > 0
        assert conn.error is None


def test_connection_lost_when_daemon_killed(daemon):
    sp = spindle.connect(daemon.sock)
    lst = sp.create_list().points([0, 0, 0])
    sp.create_layer(lst)
    sp.commit_and_wait()
    daemon.kill()
    with pytest.raises(spindle.ConnectionLost) as e:
        sp.roundtrip()
    assert not isinstance(e.value, spindle.ProtocolError)
    assert e.value.errno == errno.EPIPE and e.value.message == sp.error and sp.error_code == 0
    with pytest.raises(spindle.ConnectionLost):
        sp.create_list()
    with pytest.raises(spindle.ConnectionLost):
        lst.points([0, 0, 0])
    sp.close()
    assert sp.closed and lst.destroyed
    with pytest.raises(spindle.NotConnected):
        sp.commit()
    with pytest.raises(spindle.NotConnected):
        lst.clear()
    lst.destroy()  # nothing to do
    sp.close()


def test_closing_frees_objects(daemon):
    with spindle.connect(daemon.sock) as conn:
        lst = conn.create_list()
        layer = conn.create_layer(lst)
        buf = conn.create_buffer(np.zeros((3, 3)))
    assert conn.closed and lst.destroyed and layer.destroyed and buf.destroyed
    with pytest.raises(spindle.NotConnected):
        layer.visible = False
    # Objects destroyed one by one.
    with spindle.connect(daemon.sock) as conn:
        lst = conn.create_list()
        lst.destroy()
        with pytest.raises(spindle.NotConnected, match='destroyed'):
            lst.clear()
        assert conn.status().clients == 1


def test_garbage_collected_buffers_are_destroyed(start_daemon):
    d = start_daemon('--set', 'max-objects=40')
    with spindle.connect(d.sock) as conn:
        lst = conn.create_list()
        for i in range(200):
            buf = conn.create_buffer(np.full((3, 3), i / 200))
            lst.clear().points(buf)
        for i in range(200):  # temporary buffers of arrays
            lst.clear().triangles(np.full((3, 3), i / 200))
        conn.roundtrip()


def test_big_buffers_go_in_memfds(sp):
    cloud = np.random.default_rng(3).uniform(-0.5, 0.5, (20000, 3))  # 240000 bytes: over the inline maximum
    lst = sp.create_list().points(cloud)
    sp.create_layer(lst)
    sp.commit_and_wait()
    assert sp.capture().lit_count() > 1000
    with pytest.raises(ValueError):
        sp.create_buffer(cloud, inline=True)
    raw = sp.create_raw_buffer(cloud[:10].astype(np.float32).tobytes())
    assert raw.size == 120 and raw.format is None
    lst.clear().points(raw)
    sp.roundtrip()


def test_arguments_are_checked_before_sending(sp):
    lst = sp.create_list()
    with pytest.raises(ValueError, match='N x 3'):
        lst.points(np.zeros((5, 2)))
    with pytest.raises(ValueError, match='whole triangles'):
        lst.triangles(np.zeros((4, 3)))
    with pytest.raises(ValueError, match='whole segments'):
        lst.lines(np.zeros((3, 3)))
    with pytest.raises(ValueError, match='colours for'):
        lst.points(np.zeros((5, 3)), np.zeros((4, 3), dtype=np.uint8))
    with pytest.raises(ValueError, match='0 to 255'):
        lst.points(np.zeros((2, 3)), np.array([[300, 0, 0], [0, 0, 0]]))
    with pytest.raises(ValueError):
        lst.set_color(256, 0, 0)
    with pytest.raises(ValueError):
        lst.set_color(1.5, 0, 0)
    with pytest.raises(ValueError):
        lst.set_color('#12345')
    with pytest.raises(TypeError):
        lst.set_color(1, 2)
    with pytest.raises(ValueError, match='4x4'):
        lst.set_transform(np.eye(3))
    with pytest.raises(TypeError):
        lst.points([['a', 'b', 'c']])
    with pytest.raises(ValueError, match='not below'):
        lst.mesh(np.zeros((3, 3)), [[0, 1, 3]])
    with pytest.raises(ValueError):
        sp.create_layer().priority = 2**40
    with pytest.raises(TypeError):
        sp.create_layer().set_list('list')
    # Nothing reached the daemon: the connection is healthy.
    sp.roundtrip()
    assert sp.error is None


def test_capture_file_round_trip(sp, tmp_path):
    sp.create_layer(sp.create_list().points([0.5, 0.5, 0.5]))
    sp.commit_and_wait()
    cap = sp.capture()
    cap.save(tmp_path / 'v.svol')
    again = spindle.Capture.load(tmp_path / 'v.svol')
    assert again.data == cap.data and again.lit_count() == cap.lit_count() > 0
    with pytest.raises(ValueError):
        spindle.Capture(b'SVOL' + bytes(60))
