"""Captured volumes: the ``.svol`` format (docs/formats.md) that
:meth:`spindle.Connection.capture` returns and ``spindlectl capture`` writes,
read into numpy arrays, with the mapping from volume space to voxels
(docs/design.md, section 3)."""
import math
import os
import struct

import numpy as np

__all__ = ['Capture']

_HEADER = struct.Struct('<4sHHIIIIBBHfQQ16x')


class Capture:
    """One captured volume (an ``.svol`` file's contents).

    Attributes: ``width`` (W, pixels per image row), ``height`` (H, rows),
    ``images`` (images in the file: N, or N/2 when mirrored),
    ``images_per_rev`` (N), ``mirrored``, ``half_height`` (h),
    ``volume_seq``, ``time_ns`` (CLOCK_MONOTONIC time first shown, 0 if
    never), ``data`` (the whole file, bytes).

    Image k stands at angle ``2 pi k / N`` from +x towards +z; its pixel
    (u, v) lights the points whose in-plane coordinate s falls in column
    ``u = floor((s + 1) / 2 * W)`` and whose height y falls in row
    ``v = floor((h - y) / (2 h) * H)``, on both sides of the axis.
    """

    def __init__(self, data):
        data = bytes(data)
        if len(data) < _HEADER.size:
            raise ValueError(f'not an .svol volume: {len(data)} bytes, shorter than its 64-byte header')
        (magic, version, header_size, self.width, self.height, self.images, self.images_per_rev, planes, flags, _,
         self.half_height, self.volume_seq, self.time_ns) = _HEADER.unpack_from(data)
        if magic != b'SVOL' or version != 1 or header_size != 64 or planes != 3:
            raise ValueError(f'not an .svol version 1 volume (magic {magic!r}, version {version}, '
                             f'header {header_size}, planes {planes})')
        self.mirrored = bool(flags & 1)
        self.row_bytes = (self.width + 7) // 8
        want = 64 + self.images * 3 * self.height * self.row_bytes
        if len(data) != want:
            raise ValueError(f'.svol volume of {len(data)} bytes: its header says {want}')
        self.data = data

    @classmethod
    def load(cls, path):
        """Reads an ``.svol`` file."""
        with open(path, 'rb') as f:
            return cls(f.read())

    def save(self, path):
        """Writes the volume as an ``.svol`` file (``spindlectl preview`` reads it)."""
        with open(os.fspath(path), 'wb') as f:
            f.write(self.data)

    def __repr__(self):
        return (f'<spindle.Capture volume {self.volume_seq}: {self.images} images of {self.width}x{self.height}, '
                f'{self.lit_count()} voxels lit>')

    @property
    def planes(self):
        """The packed bit planes, a read-only uint8 array of shape
        (images, 3, H, ceil(W / 8)): channel R, G, B; the most significant
        bit is the leftmost pixel."""
        return np.frombuffer(self.data, dtype=np.uint8, offset=64).reshape(self.images, 3, self.height,
                                                                             self.row_bytes)

    def voxels(self):
        """Every voxel, a bool array of shape (images, 3, H, W): [k, c, v, u]
        is channel c of image k's pixel in column u, row v."""
        return np.unpackbits(self.planes, axis=-1)[..., :self.width].astype(bool)

    def lit(self):
        """The voxels lit in any channel, a bool array of shape (images, H, W)."""
        return self.voxels().any(axis=1)

    def lit_count(self, channel=None):
        """How many voxels are lit: in any channel (None), or in channel 0, 1 or 2 (R, G, B)."""
        if channel is None:
            return int(self.lit().sum())
        return int(np.unpackbits(self.planes[:, channel], axis=-1)[..., :self.width].sum())

    def voxels_at(self, point):
        """The voxels (k, u, v) of this file where the volume-space point
        (x, y, z) is shown: one image per lobe of the bow tie it falls in
        (one image in all for a mirrored volume)."""
        x, y, z = (float(c) for c in point)
        n_rev = self.images_per_rev
        step = 2 * math.pi / n_rev
        phi = math.atan2(z, x)
        h = self.half_height
        v = min(max(math.floor((h - y) / (2 * h) * self.height), 0), self.height - 1)
        out = []
        for lobe in (0.0, math.pi):
            k = round((phi - lobe) / step) % n_rev % self.images
            theta = k * step
            s = x * math.cos(theta) + z * math.sin(theta)
            u = min(max(math.floor((s + 1) / 2 * self.width), 0), self.width - 1)
            if (k, u, v) not in out:
                out.append((k, u, v))
        return out

    def lit_at(self, point, radius=1, images=1, channel=None):
        """Whether a voxel within ``radius`` pixels (columns and rows) and
        ``images`` images of where the point (x, y, z) is shown is lit, in
        any channel (None) or in the channel given (0, 1, 2: R, G, B)."""
        planes = self.planes
        for k0, u0, v0 in self.voxels_at(point):
            for dk in range(-images, images + 1):
                k = (k0 + dk) % self.images
                for v in range(max(v0 - radius, 0), min(v0 + radius, self.height - 1) + 1):
                    for u in range(max(u0 - radius, 0), min(u0 + radius, self.width - 1) + 1):
                        bit = 0x80 >> (u % 8)
                        channels = range(3) if channel is None else (channel, )
                        if any(planes[k, c, v, u // 8] & bit for c in channels):
                            return True
        return False
