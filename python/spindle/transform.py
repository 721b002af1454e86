"""4x4 affine transforms as numpy arrays, for :meth:`spindle.List.set_transform`,
:meth:`spindle.List.multiply_transform` and :attr:`spindle.Layer.transform`.

A transform is the matrix as written in mathematics: ``m @ (x, y, z, 1)``
maps a point, the translation is ``m[:3, 3]`` and the bottom row is
``0 0 0 1``. Every function here returns a new 4x4 float32 array; compose
with ``@`` (``a @ b`` applies ``b`` first). Angles are in radians, and
rotations are right-handed (counter-clockwise looking down the axis towards
the origin). Volume space: y up along the rotation axis, unit the display's
radius (docs/design.md, section 3).

Anything taking a transform also takes 16 numbers in column-major order
(the C API's ``float m[16]``) or a 3x4 affine matrix.
"""
import math

import numpy as np

__all__ = ['identity', 'translate', 'scale', 'rotate', 'rotate_x', 'rotate_y', 'rotate_z', 'to_column_major',
           'from_column_major']


def identity():
    """The identity transform."""
    return np.eye(4, dtype=np.float32)


def _vec3(x, y, z, what):
    if y is None and z is None:
        v = np.asarray(x, dtype=np.float64).reshape(-1)
        if v.shape == (1, ):
            return float(v[0]), float(v[0]), float(v[0])
        if v.shape != (3, ):
            raise ValueError(f'{what}: expected x, y, z (or one vector of 3), not shape {v.shape}')
        return tuple(float(c) for c in v)
    if y is None or z is None:
        raise TypeError(f'{what}: give x, y and z, or one vector')
    return float(x), float(y), float(z)


def translate(x, y=None, z=None):
    """A translation by (x, y, z); ``translate(v)`` takes a vector of 3."""
    m = identity()
    m[:3, 3] = _vec3(x, y, z, 'translate')
    return m


def scale(x, y=None, z=None):
    """A scaling: ``scale(s)`` uniform, ``scale(sx, sy, sz)`` or ``scale(v)`` per axis."""
    if y is None and z is None and np.ndim(x) == 0:
        x = [x, x, x]
    m = identity()
    m[0, 0], m[1, 1], m[2, 2] = _vec3(x, y, z, 'scale')
    return m


def rotate(angle, axis):
    """A rotation by angle (radians) about the axis (a vector of 3 through
    the origin; normalised here), right-handed."""
    a = np.asarray(axis, dtype=np.float64).reshape(-1)
    if a.shape != (3, ):
        raise ValueError(f'rotate: the axis is a vector of 3, not shape {a.shape}')
    n = np.linalg.norm(a)
    if not n > 0 or not math.isfinite(n):
        raise ValueError('rotate: the axis has no direction')
    x, y, z = a / n
    c, s = math.cos(angle), math.sin(angle)
    t = 1 - c
    m = identity()
    m[:3, :3] = [[t * x * x + c, t * x * y - s * z, t * x * z + s * y],
                 [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
                 [t * x * z - s * y, t * y * z + s * x, t * z * z + c]]
    return m


def rotate_x(angle):
    """A rotation by angle (radians) about the x axis: y towards z."""
    return rotate(angle, (1, 0, 0))


def rotate_y(angle):
    """A rotation by angle (radians) about the y axis (the display's rotation axis): z towards x."""
    return rotate(angle, (0, 1, 0))


def rotate_z(angle):
    """A rotation by angle (radians) about the z axis: x towards y."""
    return rotate(angle, (0, 0, 1))


def to_column_major(m):
    """The 16 float32 values the C API takes (column-major, contiguous) of a
    transform given as a 4x4 or 3x4 matrix (mathematical layout, see the
    module's description) or as 16 numbers already in column-major order.
    Raises ValueError for any other shape, TypeError for non-numbers."""
    try:
        a = np.asarray(m, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f'a transform is a 4x4 matrix or 16 numbers, not {type(m).__name__}') from None
    if a.shape == (3, 4):
        a = np.vstack([a, [0, 0, 0, 1]])
    if a.shape == (4, 4):
        a = a.T
    elif a.shape != (16, ):
        raise ValueError(f'a transform is a 4x4 (or 3x4) matrix or 16 numbers in column-major order, '
                         f'not shape {a.shape}')
    return np.ascontiguousarray(a.reshape(16), dtype=np.float32)


def from_column_major(values):
    """The 4x4 matrix (mathematical layout) of 16 column-major numbers."""
    return np.asarray(values, dtype=np.float32).reshape(4, 4).T.copy()
