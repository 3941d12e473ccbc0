// Reads a binary little-endian PLY as `tsm decode` writes it (float x y z,
// list uchar uint vertex_indices) and prints the reference figures the
// browser test checks: counts and FNV-1a of the index and position arrays.
//   node web/tools/ply-ref.mjs mesh.ply > mesh.ref.json
import fs from 'node:fs';
import { fnv1a, hex } from '../demo/hash.js';

const buf = fs.readFileSync(process.argv[2]);
const end = buf.indexOf('end_header\n');
if (end < 0) throw new Error('not a PLY file');
const header = buf.subarray(0, end).toString('latin1').split('\n');
if (!header.includes('format binary_little_endian 1.0')) throw new Error('expected a binary little-endian PLY');
let vertexCount = 0, faceCount = 0;
for (const line of header) {
  const m = line.match(/^element (vertex|face) (\d+)$/);
  if (m) (m[1] === 'vertex' ? (vertexCount = +m[2]) : (faceCount = +m[2]));
}
const vprops = header.slice(header.findIndex((l) => l.startsWith('element vertex')) + 1)
  .filter((l, i, a) => a.slice(0, i + 1).every((x) => x.startsWith('property')));
if (vprops.join('|') !== 'property float x|property float y|property float z')
  throw new Error('unexpected vertex properties: ' + vprops.join(', '));
if (!header.includes('property list uchar uint vertex_indices')) throw new Error('unexpected face property');
let at = end + 'end_header\n'.length;
const positions = new Float32Array(3 * vertexCount);
for (let i = 0; i < 3 * vertexCount; ++i, at += 4) positions[i] = buf.readFloatLE(at);
const sizes = [];
const corners = [];
let triangles = true;
for (let f = 0; f < faceCount; ++f) {
  const n = buf[at++];
  if (n !== 3) triangles = false;
  sizes.push(n);
  for (let k = 0; k < n; ++k, at += 4) corners.push(buf.readUInt32LE(at));
}
if (at !== buf.length) throw new Error(`${buf.length - at} bytes after the faces`);
const indices = Uint32Array.from(corners);
const out = {
  vertexCount, faceCount, cornerCount: indices.length, triangles,
  indexHash: hex(fnv1a(indices)), positionHash: hex(fnv1a(positions)),
};
if (!triangles) {
  const offsets = new Uint32Array(faceCount + 1);
  for (let f = 0; f < faceCount; ++f) offsets[f + 1] = offsets[f] + sizes[f];
  out.faceOffsetHash = hex(fnv1a(offsets));
}
console.log(JSON.stringify(out));
