"""Volumes (protocol version 6, docs/volumes.md) through the binding:
Connection.volume() from numpy arrays, List.draw_volume() and
List.set_volume_lut(), checked in captures: a uint8 ball against the
analytic ball, the axes ([z, y, x] arrays, y up), a lookup table on a ramp,
RGBA8 and float32 samples, an int16 CT-like volume with negative values (in
either byte order), a destroyed volume dark from the next volume on, a
volume a list draws kept alive by the list, arguments checked before
sending, and NotSupported at version 5."""
import errno
import gc
import math

import numpy as np
import pytest

import spindle
from spindle import Sampling, VolumeType, transform

N = 24


def ball(n=N, inside=255, outside=0, dtype=np.uint8):
    """An n^3 volume [z, y, x]: inside within radius 0.4 of the unit cube's centre, else outside."""
    c = (np.arange(n) + 0.5) / n - 0.5
    z, y, x = np.meshgrid(c, c, c, indexing='ij')
    v = np.full((n, n, n), outside, dtype=dtype)
    v[x**2 + y**2 + z**2 <= 0.16] = inside
    return v


def centred(volume, s):
    """The list transform showing volume's box scaled by s / its largest extent, centred at the origin."""
    ext = np.asarray(volume.extent)
    k = s / ext.max()
    return transform.scale(k) @ transform.translate(*(-ext / 2))


def show(sp, volume, s=1.4, color=(255, 255, 255), **draw):
    """A layer drawing volume centred, scaled to s; committed and shown; the list and layer."""
    lst = sp.create_list().set_transform(centred(volume, s)).set_color(*color)
    lst.draw_volume(volume, **draw)
    layer = sp.create_layer(lst)
    sp.commit_and_wait()
    return lst, layer


def pixel(cap, k, u, v, channel=None):
    """Whether image k's pixel (column u, row v) is lit, in any channel or in the one given."""
    vox = cap.voxels()[k, :, v, u]
    return bool(vox.any() if channel is None else vox[channel])


def col(s, cap):
    return math.floor((s + 1) / 2 * cap.width)


def row(y, cap):
    return math.floor((cap.half_height - y) / (2 * cap.half_height) * cap.height)


@pytest.mark.parametrize('sampling', ['nearest', Sampling.TRILINEAR])
def test_ball_shown_where_it_is(sp, sampling):
    vol = sp.volume(ball(), spacing=(1 / N, 1 / N, 1 / N))
    assert isinstance(vol, spindle.Volume) and vol.type is VolumeType.U8
    assert vol.size == (N, N, N) and vol.nbytes == N**3 and np.allclose(vol.extent, 1)
    assert 'Volume 24x24x24 U8' in repr(vol)
    s = 1.4
    show(sp, vol, s, sampling=sampling, threshold=128, window=(64, 128))
    cap = sp.capture()
    w, h = cap.width, cap.height
    # The centre of image 0 lit white (the window saturates: 255 is at full colour), far outside dark.
    assert all(pixel(cap, 0, w // 2, h // 2, c) for c in range(3))
    assert not pixel(cap, 0, 2, h // 2) and not pixel(cap, 0, w // 2, 2) and not pixel(cap, 0, w - 3, h - 3)
    # Every image against the analytic ball: a pixel whose centre lies inside it by more than a sample's
    # half diagonal (nearest; a whole diagonal trilinear) is lit, one outside by more is dark.
    su = (np.arange(w) + 0.5) / w * 2 - 1
    yv = cap.half_height - (np.arange(h) + 0.5) / h * 2 * cap.half_height
    dist = np.hypot(su[None, :], yv[:, None]) - 0.4 * s
    margin = s / N * math.sqrt(3) * (0.5 if sampling == 'nearest' else 1)
    lit = cap.lit()
    inside, outside = dist < -margin, dist > margin
    assert inside.sum() > 1000
    assert lit[:, inside].all(), 'inside the ball, dark'
    assert not lit[:, outside].any(), 'outside the ball, lit'


def test_axes_are_z_y_x_and_y_is_up(sp):
    """An array [z, y, x] of different sizes along each axis, lit in its +x +y +z octant only."""
    nz, ny, nx = 10, 16, 12
    a = np.zeros((nz, ny, nx), dtype=np.uint8)
    a[nz // 2:, ny // 2:, nx // 2:] = 255
    vol = sp.volume(a, spacing=(1 / nx, 1 / ny, 1 / nz))  # a unit cube
    assert vol.size == (nx, ny, nz) and np.allclose(vol.extent, 1)
    show(sp, vol, 1.2, sampling='nearest', threshold=128, window=(64, 128))
    cap = sp.capture()
    assert cap.lit_at((0.3, 0.3, 0.3))
    for p in [(-0.3, 0.3, 0.3), (0.3, -0.3, 0.3), (0.3, 0.3, -0.3), (-0.3, -0.3, -0.3), (0.3, -0.3, -0.3)]:
        assert not cap.lit_at(p, radius=0, images=0), f'{p} is lit: the axes are not [z, y, x] with y up'


def ramp(n=N):
    """An n^3 uint8 volume rising along y (up): 0 at the bottom to 255 at the top."""
    a = np.empty((n, n, n), dtype=np.uint8)
    a[:] = (np.arange(n) * 255 // (n - 1)).astype(np.uint8)[None, :, None]
    return a


@pytest.mark.parametrize('table', [
    np.array([[255, 0, 0, 255], [0, 255, 0, 255]], dtype=np.uint8),
    [[1.0, 0, 0], [0, 1.0, 0]],  # RGB floats 0..1
])
def test_lookup_table_colours_a_ramp(sp, table):
    vol = sp.volume(ramp(), spacing=1 / N)
    lst = sp.create_list().set_transform(centred(vol, 1.0))
    lst.set_volume_lut(table).draw_volume(vol, 'nearest', threshold=0, window=(128, 256))
    layer = sp.create_layer(lst)
    sp.commit_and_wait()
    cap = sp.capture()
    u, low, high = col(0.1, cap), row(-0.3, cap), row(0.3, cap)
    assert pixel(cap, 0, u, low, 0) and not pixel(cap, 0, u, low, 1)  # the low half red
    assert pixel(cap, 0, u, high, 1) and not pixel(cap, 0, u, high, 0)  # the high half green
    assert cap.lit_count(2) == 0
    # None: the list's colour again (blue), scaled by the window.
    lst.clear().set_transform(centred(vol, 1.0)).set_color(0, 0, 255)
    lst.set_volume_lut(table).set_volume_lut(None).draw_volume(vol, 'nearest', threshold=0, window=(128, 256))
    layer.list = lst
    sp.commit_and_wait()
    cap = sp.capture()
    assert pixel(cap, 0, u, high, 2) and cap.lit_count(0) == cap.lit_count(1) == 0


def test_rgba8_samples_are_their_own_colour(sp):
    a = np.zeros((N, N, N, 4), dtype=np.uint8)
    inside = ball() > 0
    a[inside] = (255, 0, 0, 255)  # red,
    a[inside & (np.arange(N) >= N // 2)[None, :, None]] = (0, 0, 255, 255)  # its upper half blue,
    a[:, :, :N // 4] = (0, 255, 0, 0)  # and an invisible (alpha 0) green slab at low x
    vol = sp.volume(a, spacing=1 / N)
    assert vol.type is VolumeType.RGBA8 and vol.nbytes == 4 * N**3
    show(sp, vol, 1.4, color=(0, 0, 0), sampling='nearest', threshold=1)  # the list's colour does not apply
    cap = sp.capture()
    assert cap.lit_at((0, -0.25, 0), channel=0) and not cap.lit_at((0, -0.25, 0), channel=2)
    assert cap.lit_at((0, 0.25, 0), channel=2) and not cap.lit_at((0, 0.25, 0), channel=0)
    assert cap.lit_count(1) == 0


def test_float32_default_window_and_nan(sp):
    a = ball(inside=1.0, dtype=np.float32)
    a[:, N // 2:, :] = np.where(a[:, N // 2:, :] > 0, np.nan, 0)  # the upper half NaN: dark
    vol = sp.volume(a, spacing=1 / N)
    assert vol.type is VolumeType.F32
    show(sp, vol, 1.4, sampling='nearest')  # window 0..1, threshold 0: 1.0 at full colour, 0 dark
    cap = sp.capture()
    assert cap.lit_at((0, -0.25, 0)) and not cap.lit_at((0, 0.25, 0), radius=0, images=0)


@pytest.mark.parametrize('byteorder', ['<', '>'])
def test_int16_ct_with_negative_values(sp, byteorder):
    """Hounsfield units: air -1000 around a ball of soft tissue (40) with a
    bone core (1000); the soft tissue window (40/400), air below -500 dark."""
    nz, ny, nx = 20, 24, 28
    z, y, x = np.meshgrid(*[(np.arange(n) + 0.5) / n - 0.5 for n in (nz, ny, nx)], indexing='ij')
    r2 = x**2 + y**2 + z**2
    ct = np.full((nz, ny, nx), -1000, dtype=np.int16)
    ct[r2 <= 0.16] = 40
    ct[r2 <= 0.01] = 1000
    ct = ct.astype(np.dtype(np.int16).newbyteorder(byteorder))
    vol = sp.volume(ct, spacing=(0.9 / nx, 0.9 / ny, 0.9 / nz))  # mm, say: a 0.9 cube
    assert vol.type is VolumeType.I16 and vol.size == (nx, ny, nz)
    show(sp, vol, 1.4, sampling=Sampling.NEAREST, threshold=-500, window=(40, 400))
    cap = sp.capture()
    assert cap.lit_at((0.3, 0, 0)) and cap.lit_at((0, 0, 0))  # soft tissue (g = 0.5) and bone (g = 1)
    assert not cap.lit_at((0.65, 0, 0), radius=0, images=0) and not cap.lit_at((0, 0.65, 0), radius=0, images=0)
    # Without the threshold (its default: the window's low end, -160) air stays dark too.
    layer_list = sp.create_list().set_transform(centred(vol, 1.4)).draw_volume(vol, 'nearest', window=(40, 400))
    sp.create_layer(layer_list)
    sp.commit_and_wait()
    assert not sp.capture().lit_at((0.65, 0, 0), radius=0, images=0)


def memory_used(sp):
    return sp.status().limits.memory_used


def test_destroyed_volume_is_dark_from_the_next_volume(sp):
    before = memory_used(sp)
    vol = sp.volume(ball(), spacing=1 / N)
    assert memory_used(sp) >= before + N**3
    lst, _ = show(sp, vol, 1.4, sampling='nearest', threshold=128, window=(64, 128))
    assert sp.capture().lit_count() > 1000
    vol.destroy()
    assert vol.destroyed
    vol.destroy()  # twice: nothing
    sp.commit_and_wait()  # a volume after the destroy
    assert sp.capture().lit_count() == 0
    assert memory_used(sp) < before + N**3
    with pytest.raises(spindle.NotConnected):
        lst.draw_volume(vol)
    # A with block destroys it too.
    with sp.volume(ball(), spacing=1 / N) as v:
        assert not v.destroyed
    assert v.destroyed


def test_a_list_keeps_the_volumes_it_draws(sp):
    before = memory_used(sp)
    lst = sp.create_list().set_transform(transform.scale(1.4) @ transform.translate(-0.5, -0.5, -0.5))
    lst.draw_volume(sp.volume(ball(), spacing=1 / N), 'nearest', threshold=128, window=(64, 128))
    gc.collect()  # only the list references the volume
    sp.create_layer(lst)
    sp.commit_and_wait()
    assert sp.capture().lit_count() > 1000
    lst.clear()
    gc.collect()  # no longer: destroyed at the connection's next call
    assert memory_used(sp) < before + N**3


def test_arguments_are_checked_before_sending(sp, daemon):
    before = memory_used(sp)
    for bad in [
            np.zeros((4, 4, 4)),  # float64
            np.zeros((4, 4, 4), dtype=np.int32),
            np.zeros((4, 4, 4), dtype=np.int8),
            np.zeros((4, 4, 4), dtype=np.float16),
            np.zeros((4, 4, 4), dtype=bool),
            np.zeros((4, 4, 4), dtype=np.complex64),
            np.zeros((4, 4, 4, 4), dtype=np.int64),
            [[[1, 2], [3, 4]]],  # a list: int64
            'abc',
    ]:
        with pytest.raises(TypeError):
            sp.volume(bad)
    for bad in [
            np.zeros((4, 4), dtype=np.uint8),
            np.zeros(4, dtype=np.uint8),
            np.zeros((4, 4, 4, 4), dtype=np.uint16),  # 4-D is uint8 RGBA
            np.zeros((4, 4, 4, 3), dtype=np.uint8),  # RGB: not RGBA
            np.zeros((2, 2, 2, 2, 4), dtype=np.uint8),
            np.zeros((4, 0, 4), dtype=np.uint8),
            np.zeros((1, 1, 4097), dtype=np.uint8),
    ]:
        with pytest.raises(ValueError):
            sp.volume(bad)
    good = np.zeros((2, 2, 2), dtype=np.uint8)
    for spacing in [0, -1, (1, 1, 0), (1, 1, float('nan')), (1, 1, float('inf')), (1, 1), 1e-50, 1e39]:
        with pytest.raises(ValueError):
            sp.volume(good, spacing=spacing)
    with pytest.raises(TypeError):
        sp.volume(good, spacing='xyz')
    vol = sp.volume(good)
    assert vol.spacing == (1.0, 1.0, 1.0)
    lst = sp.create_list()
    with pytest.raises(ValueError, match='sampling'):
        lst.draw_volume(vol, 'cubic')
    with pytest.raises(ValueError, match='sampling'):
        lst.draw_volume(vol, 2)
    for window in [(10, 0), (10, -1), (0, float('nan')), (1e8, 1e-3), (float('inf'), 1)]:
        with pytest.raises(ValueError):
            lst.draw_volume(vol, window=window)
    for window in [10, 'ab', (1, 2, 3)]:
        with pytest.raises((TypeError, ValueError)):
            lst.draw_volume(vol, window=window)
    with pytest.raises(ValueError):
        lst.draw_volume(vol, threshold=float('nan'))
    with pytest.raises(TypeError):
        lst.draw_volume(vol, threshold='128')
    with pytest.raises(TypeError):
        lst.draw_volume(np.zeros((2, 2, 2), dtype=np.uint8))
    with spindle.connect(daemon.sock) as other:
        with pytest.raises(ValueError, match='another connection'):
            other.create_list().draw_volume(vol)
    for table in [[[255, 0, 0, 255]], np.zeros((4097, 4), dtype=np.uint8), np.zeros((4, 5), dtype=np.uint8),
                  [[300, 0, 0, 255], [0, 0, 0, 255]], [[1.5, 0, 0], [0, 0, 0]], np.zeros((2, 2, 4), np.uint8)]:
        with pytest.raises(ValueError):
            lst.set_volume_lut(table)
    # Nothing bad reached the daemon (each would have been a fatal error).
    sp.roundtrip()
    assert sp.error is None
    assert memory_used(sp) < before + 1000
    lst.set_volume_lut([]).set_volume_lut(np.zeros((0, 4), np.uint8)).draw_volume(vol)
    sp.roundtrip()
    assert sp.error is None


def test_not_supported_before_version_6(daemon):
    with spindle.connect(daemon.sock, version=5) as old:
        assert old.version == 5
        with pytest.raises(spindle.NotSupported) as e:
            old.volume(ball())
        assert e.value.errno == errno.EPROTONOSUPPORT
        with pytest.raises(spindle.NotSupported):
            old.create_list().set_volume_lut([[0, 0, 0, 255], [255, 255, 255, 255]])
        old.roundtrip()
        assert old.error is None
