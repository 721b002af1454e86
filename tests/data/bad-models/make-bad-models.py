#!/usr/bin/env python3
"""Writes the model files no loader may crash on (tests/data/bad-models/
README.md), generated so that none is committed: the truncated bunny, a
face index far out of range, NaN and infinite vertices, copies of the bunny
with a few bytes changed, absurd counts, a node tree deep enough to
overflow assimp's stack, and bytes that are no model at all.

    make-bad-models.py DATA_DIR OUT_DIR

DATA_DIR is tests/data (the bunny and the glTF triangle come from it).
Python 3 standard library only; the output is the same on every run.
"""
import json
import os
import random
import struct
import sys

# Seeds of random.Random whose byte changes made the bunny crash Spindle
# before assimp's validation was on (SIGSEGV in assimp's post-processing).
FLIP_SEEDS = (0, 1, 8, 17, 18)
FLIPS = 4


def ply_header(vertices, faces, binary=True):
    fmt = 'binary_little_endian' if binary else 'ascii'
    return (f'ply\nformat {fmt} 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\n'
            f'property float z\nelement face {faces}\nproperty list uchar int vertex_indices\n'
            'end_header\n').encode()


def triangle_ply(last_index):
    return (ply_header(3, 1) + struct.pack('<9f', 0, 0, 0, 1, 0, 0, 0, 1, 0)
            + struct.pack('<Biii', 3, 0, 1, last_index))


def flipped(bunny, seed):
    r = random.Random(seed)
    b = bytearray(bunny)
    for _ in range(FLIPS):
        b[r.randrange(len(b))] = r.randrange(256)
    return bytes(b)


def deep_gltf(data_dir, depth):
    with open(os.path.join(data_dir, 'transformed.gltf')) as f:
        g = json.load(f)
    g['nodes'] = [{'children': [i + 1]} for i in range(depth)] + [{'mesh': 0}]
    g['scenes'] = [{'nodes': [0]}]
    return json.dumps(g, separators=(',', ':')).encode()


def files(data_dir):
    with open(os.path.join(data_dir, 'bunny.ply'), 'rb') as f:
        bunny = f.read()
    out = {
        'truncated-bunny.ply': bunny[:300],
        'huge-index.ply': triangle_ply(99999999),
        'negative-index.ply': triangle_ply(-1),
        'nan.obj': b'v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n',
        'inf.obj': b'v 0 0 0\nv 1 0 0\nv 0 1 -inf\nf 1 2 3\n',
        'overflow.stl': b'solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1e39 0 0\n'
                        b'vertex 0 1 0\nendloop\nendfacet\nendsolid s\n',
        'huge-count.ply': ply_header(2147483647, 1) + struct.pack('<9f', 0, 0, 0, 1, 0, 0, 0, 1, 0),
        'no-faces-huge-count.ply': ply_header(4000000000, 0, binary=False) + b'0 0 0\n',
        'deep-nodes.gltf': deep_gltf(data_dir, 20000),
        'garbage.stl': bytes(range(256)) * 4,
        'empty.obj': b'',
    }
    for seed in FLIP_SEEDS:
        out[f'flipped-bunny-{seed:02d}.ply'] = flipped(bunny, seed)
    return out


def main():
    data_dir, out_dir = sys.argv[1:3]
    os.makedirs(out_dir, exist_ok=True)
    for name, data in sorted(files(data_dir).items()):
        with open(os.path.join(out_dir, name), 'wb') as f:
            f.write(data)


if __name__ == '__main__':
    main()
