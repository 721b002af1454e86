#!/usr/bin/env python3
"""Writes the seeds of the fuzz target "model" (fuzz/fuzz_model.c): the test
models of tests/data, small files of every format the target names, models
that used to crash the loader, and a few loader results.

    fuzz/gen_model_corpus.py [OUTDIR]    (default: fuzz/corpus/model)

Each seed is one file, named after what it holds, in the target's input
format: a selector byte (the file's extension; bit 7: a result), then the
file. Only the model target's directory is rewritten (fuzz/gen_corpus.py
writes the others). Python 3 standard library only; the output is
reproducible.
"""
import base64
import json
import os
import shutil
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, '..', 'tests', 'data')
EXT = {e: i for i, e in enumerate(('ply', 'obj', 'stl', 'gltf', 'glb', 'off', 'dae', 'fbx'))}
RESULT = 0x80


def data_file(name):
    with open(os.path.join(DATA, name), 'rb') as f:
        return f.read()


def seed(ext, body):
    return bytes([EXT[ext]]) + body


def ply_binary(verts, faces, colors=None):
    head = f'ply\nformat binary_little_endian 1.0\nelement vertex {len(verts)}\n'
    head += 'property float x\nproperty float y\nproperty float z\n'
    if colors:
        head += 'property uchar red\nproperty uchar green\nproperty uchar blue\n'
    head += f'element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n'
    body = b''
    for i, v in enumerate(verts):
        body += struct.pack('<3f', *v) + (bytes(colors[i]) if colors else b'')
    for f in faces:
        body += struct.pack(f'<B{len(f)}i', len(f), *f)
    return head.encode() + body


def small_bunny():
    """The bunny's first 120 faces, with the vertices they use."""
    raw = data_file('bunny.ply')
    end = raw.index(b'end_header\n') + len(b'end_header\n')
    nv = 1839
    verts = [struct.unpack_from('<3f', raw, end + 12 * i) for i in range(nv)]
    faces, off = [], end + 12 * nv
    for _ in range(120):
        faces.append(struct.unpack_from('<3i', raw, off + 1))
        off += 13
    used = sorted({i for f in faces for i in f})
    index = {v: i for i, v in enumerate(used)}
    return ply_binary([verts[v] for v in used], [[index[i] for i in f] for f in faces])


TETRA = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
TETRA_FACES = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def binary_stl():
    tris = [[TETRA[i] for i in f] for f in TETRA_FACES]
    body = b'\0' * 80 + struct.pack('<I', len(tris))
    for t in tris:
        body += struct.pack('<3f', 0, 0, 0) + b''.join(struct.pack('<3f', *v) for v in t) + b'\0\0'
    return body


def glb():
    g = json.loads(data_file('transformed.gltf'))
    buf = base64.b64decode(g['buffers'][0]['uri'].split(',', 1)[1])
    del g['buffers'][0]['uri']
    g['materials'] = [{'pbrMetallicRoughness': {'baseColorFactor': [1, 0.5, 0, 1]}}]
    g['meshes'][0]['primitives'][0]['material'] = 0
    js = json.dumps(g, separators=(',', ':')).encode()
    js += b' ' * (-len(js) % 4)
    buf += b'\0' * (-len(buf) % 4)
    chunks = struct.pack('<I4s', len(js), b'JSON') + js + struct.pack('<I4s', len(buf), b'BIN\0') + buf
    return b'glTF' + struct.pack('<II', 2, 12 + len(chunks)) + chunks


DAE = b'''<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
<library_geometries><geometry id="g"><mesh>
<source id="p"><float_array id="pa" count="9">0 0 0 1 0 0 0 1 0</float_array>
<technique_common><accessor source="#pa" count="3" stride="3"><param name="X" type="float"/>
<param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common></source>
<vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
<triangles count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2</p></triangles>
</mesh></geometry></library_geometries>
<library_visual_scenes><visual_scene id="s"><node><instance_geometry url="#g"/></node></visual_scene>
</library_visual_scenes><scene><instance_visual_scene url="#s"/></scene></COLLADA>
'''


def result(flags, counts, payload):
    def num(v):
        return bytes([v]) if v < 0x80 else b'\x80' + struct.pack('<Q', v)
    return bytes([RESULT, flags]) + b''.join(num(c) for c in counts) + payload


def seeds():
    bunny = data_file('bunny.ply')
    tri = struct.pack('<9f', 0, 0, 0, 1, 0, 0, 0, 1, 0)
    return {
        'cube.stl': seed('stl', data_file('cube.stl')),
        'lines.obj': seed('obj', data_file('lines.obj')),
        'points.ply': seed('ply', data_file('points.ply')),
        'transformed.gltf': seed('gltf', data_file('transformed.gltf')),
        'bunny-120-faces.ply': seed('ply', small_bunny()),
        'colored-tetra.ply': seed('ply', ply_binary(TETRA, TETRA_FACES, [(255, 0, 0), (0, 255, 0), (0, 0, 255),
                                                                           (9, 9, 9)])),
        'polygons.obj': seed('obj', b'o a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nf 1 2 3 4\n'
                                    b'f 1/1 2/1 5/1\nl 1 2 3 4 5\np 1 3\nusemtl m\nf -1 -2 -3\n'),
        'tetra-binary.stl': seed('stl', binary_stl()),
        'tetra.off': seed('off', b'OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n'),
        'material.glb': seed('glb', glb()),
        'triangle.dae': seed('dae', DAE),
        'truncated-bunny.ply': seed('ply', bunny[:300]),
        'huge-index.ply': seed('ply', ply_binary([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [(0, 1, 99999999)])),
        'nan.obj': seed('obj', b'v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n'),
        'result-triangle': result(0, (3, 1, 0, 0), tri + struct.pack('<3I', 0, 1, 2)),
        'result-colored-points': result(1, (3, 0, 0, 3), tri + b'\xff\0\0\xff' * 3 + struct.pack('<3I', 0, 1, 2)),
        'result-bad-index': result(0, (3, 0, 1, 0), tri + struct.pack('<2I', 0, 7)),
    }


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, 'corpus', 'model')
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    for name, data in sorted(seeds().items()):
        with open(os.path.join(out, name), 'wb') as f:
            f.write(data)


if __name__ == '__main__':
    main()
