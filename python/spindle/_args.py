"""Arguments checked and converted for libspindle, before anything is sent."""
import numpy as np

from .types import Mode, VertexFormat, VolumeType


#: The most bytes a buffer sent inline may hold (SPINDLE_INLINE_MAX).
INLINE_MAX = 65516

#: The most samples along each axis of a volume, and in all (docs/volumes.md).
VOLUME_MAX_SIZE = 4096
VOLUME_MAX_SAMPLES = 2**31
#: The most entries of a volume's lookup table (at least 2).
VOLUME_MAX_LUT = 4096



# ---- argument conversion ----


def _vertices(vertices, what='vertices'):
    """An N x 3 contiguous float32 array of vertices given as anything numpy
    reads: (N, 3), (..., 3) (flattened to (N, 3)) or one point of 3."""
    try:
        a = np.asarray(vertices)
    except (TypeError, ValueError) as e:
        raise TypeError(f'{what}: not an array of numbers: {e}') from None
    if a.dtype == object or not (np.issubdtype(a.dtype, np.number) or a.dtype == np.bool_):
        raise TypeError(f'{what}: expected numbers, not an array of {a.dtype}')
    if np.issubdtype(a.dtype, np.complexfloating):
        raise TypeError(f'{what}: complex numbers')
    if a.ndim == 1 and a.shape[0] == 3:
        a = a.reshape(1, 3)
    if a.ndim < 2 or a.shape[-1] != 3:
        raise ValueError(f'{what}: expected an N x 3 array of x, y, z, not shape {a.shape}')
    return np.ascontiguousarray(a.reshape(-1, 3), dtype=np.float32)


def _color_array(colors, what='colors'):
    """(array of K x 4, format) of colours given as K x 3 or K x 4 (or one
    colour of 3 or 4): floats in 0..1 (XYZ_RGBA_FLOAT) or integers in 0..255
    (XYZ_RGBA8). Alpha defaults to opaque."""
    try:
        a = np.asarray(colors)
    except (TypeError, ValueError) as e:
        raise TypeError(f'{what}: not an array of numbers: {e}') from None
    if a.ndim == 1:
        a = a.reshape(1, -1)
    if a.ndim != 2 or a.shape[1] not in (3, 4):
        raise ValueError(f'{what}: expected a K x 3 (RGB) or K x 4 (RGBA) array, not shape {a.shape}')
    if np.issubdtype(a.dtype, np.floating):
        c = np.ones((a.shape[0], 4), dtype=np.float32)
        c[:, :a.shape[1]] = a
        return c, VertexFormat.XYZ_RGBA_FLOAT
    if np.issubdtype(a.dtype, np.integer) or a.dtype == np.bool_:
        if a.size and (a.min() < 0 or a.max() > 255):
            raise ValueError(f'{what}: integer colours are 0 to 255 (floats 0 to 1), not {a.min()} .. {a.max()}')
        c = np.full((a.shape[0], 4), 255, dtype=np.uint8)
        c[:, :a.shape[1]] = a
        return c, VertexFormat.XYZ_RGBA8
    raise TypeError(f'{what}: expected numbers, not an array of {a.dtype}')


def _interleave(xyz, colors, fmt):
    """The vertices of format fmt, as a structured array."""
    if fmt == VertexFormat.XYZ:
        return xyz
    ctype = np.uint8 if fmt == VertexFormat.XYZ_RGBA8 else np.float32
    out = np.empty(len(xyz), dtype=[('xyz', np.float32, 3), ('rgba', ctype, 4)])
    assert out.dtype.itemsize == fmt.size
    out['xyz'] = xyz
    out['rgba'] = colors
    return out


def _rgba(args, what='color'):
    """(r, g, b, a) bytes of a colour: set_color(r, g, b[, a]), a sequence
    of 3 or 4, or '#rrggbb[aa]'. Any float among them: all are 0..1."""
    if len(args) == 1:
        c = args[0]
        if isinstance(c, str):
            s = c[1:] if c.startswith('#') else c
            if len(s) not in (6, 8) or any(ch not in '0123456789abcdefABCDEF' for ch in s):
                raise ValueError(f'{what}: {c!r} is not #rrggbb or #rrggbbaa')
            v = [int(s[i:i + 2], 16) for i in range(0, len(s), 2)]
            return tuple(v) + (255, ) * (4 - len(v))
        args = tuple(np.asarray(c).reshape(-1).tolist()) if not isinstance(c, (int, float)) else (c, )
    if len(args) not in (3, 4):
        raise TypeError(f'{what}: expected r, g, b[, a], a sequence of 3 or 4, or "#rrggbb", not {len(args)} values')
    if any(isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) for v in args):
        raise TypeError(f'{what}: the channels are numbers: {args!r}')
    if any(isinstance(v, (float, np.floating)) for v in args):
        if any(not 0 <= v <= 1 for v in args):
            raise ValueError(f'{what}: float channels are 0 to 1 (integers 0 to 255): {args!r}')
        v = [int(round(float(x) * 255)) for x in args]
    else:
        v = [int(x) for x in args]
        if any(not 0 <= x <= 255 for x in v):
            raise ValueError(f'{what}: integer channels are 0 to 255 (floats 0 to 1): {args!r}')
    return tuple(v) + (255, ) * (4 - len(v))


def _uint(value, what, top=0xffffffff):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f'{what}: an integer, not {type(value).__name__}')
    if not 0 <= value <= top:
        raise ValueError(f'{what}: {value} is not 0 to {top}')
    return int(value)


_PER_PRIMITIVE = {Mode.POINTS: 1, Mode.LINES: 2, Mode.TRIANGLES: 3}

# (dtype kind, itemsize): the volume type of samples of that dtype (either byte order).
_VOLUME_TYPES = {
    ('u', 1): VolumeType.U8,
    ('u', 2): VolumeType.U16,
    ('i', 2): VolumeType.I16,
    ('f', 4): VolumeType.F32
}


def _volume_samples(samples):
    """(VolumeType, (nx, ny, nz), the samples as a C-contiguous
    little-endian array) of a volume given as a 3-D array [z, y, x] of
    uint8, uint16, int16 or float32, or a 4-D uint8 array [z, y, x, 4]
    (RGBA8)."""
    try:
        a = np.asarray(samples)
    except (TypeError, ValueError) as e:
        raise TypeError(f'volume: not an array of samples: {e}') from None
    vtype = _VOLUME_TYPES.get((a.dtype.kind, a.dtype.itemsize))
    if vtype is None or a.dtype.fields is not None:
        raise TypeError(f'volume: samples of uint8, uint16, int16 or float32 (or uint8 RGBA), not {a.dtype}: convert '
                        'them with astype()')
    if a.ndim == 4:
        if vtype != VolumeType.U8 or a.shape[3] != 4:
            raise ValueError(f'volume: a 4-D array is RGBA, uint8 [z, y, x, 4], not {a.dtype} of shape {a.shape}')
        vtype = VolumeType.RGBA8
    elif a.ndim != 3:
        raise ValueError(f'volume: expected a 3-D array [z, y, x] (or uint8 [z, y, x, 4] for RGBA), '
                         f'not shape {a.shape}')
    nz, ny, nx = (int(n) for n in a.shape[:3])
    for n, axis in ((nx, 'x'), (ny, 'y'), (nz, 'z')):
        if not 1 <= n <= VOLUME_MAX_SIZE:
            raise ValueError(f'volume: {n} samples along {axis} (1 to {VOLUME_MAX_SIZE}), shape {a.shape}')
    if nx * ny * nz > VOLUME_MAX_SAMPLES:
        raise ValueError(f'volume: {nx * ny * nz} samples (at most 2^31), shape {a.shape}')
    return vtype, (nx, ny, nz), np.ascontiguousarray(a, dtype=a.dtype.newbyteorder('<'))


def _volume_spacing(spacing):
    """The spacing (sx, sy, sz) as 3 float32, finite and above 0: 3 numbers or one for all."""
    try:
        s = np.asarray(spacing, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f'spacing: 3 numbers (x, y, z), not {spacing!r}') from None
    if s.ndim == 0:
        s = np.repeat(s, 3)
    if s.shape != (3, ):
        raise ValueError(f'spacing: 3 numbers (x, y, z) or one for all, not shape {s.shape}')
    with np.errstate(over='ignore'):
        f = s.astype(np.float32)
    if not (np.all(np.isfinite(f)) and np.all(f > 0)):
        raise ValueError(f'spacing: finite and above 0, not {s.tolist()}')
    return f


def _float32(value, what):
    """value as a finite float32 (a Python float)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f'{what}: a number, not {type(value).__name__}')
    with np.errstate(over='ignore'):
        f = np.float32(value)
    if not np.isfinite(f):
        raise ValueError(f'{what}: {value} is not a finite float32')
    return float(f)


#: The window of each volume type when draw_volume is given none: its whole range (0..1 for float32).
_DEFAULT_WINDOW = {
    VolumeType.U8: (127.5, 255.0),
    VolumeType.U16: (32767.5, 65535.0),
    VolumeType.I16: (-0.5, 65535.0),
    VolumeType.F32: (0.5, 1.0),
    VolumeType.RGBA8: (127.5, 255.0),
}


def _window(window, vtype):
    """(center, width, low end) of a draw_volume window, as the daemon computes them in float32."""
    if window is None:
        window = _DEFAULT_WINDOW[vtype]
    try:
        center, width = window
    except (TypeError, ValueError):
        raise TypeError(f'window: (center, width), not {window!r}') from None
    center, width = _float32(center, 'window center'), _float32(width, 'window width')
    if not width > 0:
        raise ValueError(f'window: the width is above 0, not {width}')
    c, half = np.float32(center), np.float32(width) / np.float32(2)
    lo, hi = c - half, c + half
    if not hi > lo:
        raise ValueError(f'window: {center}/{width} is empty at float32 precision')
    return center, width, float(lo)


def _lut(colors):
    """A lookup table as an N x 4 uint8 array (N = 0: none): K x 3 or K x 4
    colours, integers 0..255 or floats 0..1."""
    if colors is None:
        return np.zeros((0, 4), dtype=np.uint8)
    try:
        a = np.asarray(colors)
    except (TypeError, ValueError) as e:
        raise TypeError(f'lookup table: not an array of colours: {e}') from None
    if a.size == 0 and a.ndim <= 2:
        return np.zeros((0, 4), dtype=np.uint8)
    if a.ndim != 2 and not (a.ndim == 1 and a.shape[0] in (3, 4)):
        raise ValueError(f'lookup table: expected an N x 4 (RGBA) or N x 3 (RGB) array, not shape {a.shape}')
    c, fmt = _color_array(a, 'lookup table')
    if fmt == VertexFormat.XYZ_RGBA_FLOAT:
        if not np.all((c >= 0) & (c <= 1)):
            raise ValueError('lookup table: float colours are 0 to 1 (integers 0 to 255)')
        c = np.round(c * 255).astype(np.uint8)
    if not 2 <= len(c) <= VOLUME_MAX_LUT:
        raise ValueError(f'lookup table: {len(c)} entries (2 to {VOLUME_MAX_LUT}; None or an empty table: the '
                         'list\'s colour again)')
    return np.ascontiguousarray(c, dtype=np.uint8)


def _check_count(mode, count):
    if mode == Mode.LINES and count % 2:
        raise ValueError(f'lines: {count} vertices do not make whole segments (2 each)')
    if mode == Mode.TRIANGLES and count % 3:
        raise ValueError(f'triangles: {count} vertices do not make whole triangles (3 each)')

