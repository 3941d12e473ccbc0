// Reads a binary little-endian PLY as `tsm decode` writes it (float x y z
// first, list uchar uint vertex_indices first; further properties, the
// mesh's attributes, are skipped) and prints the reference figures the
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
// Properties of an element: [{name, type} | {name, list: [countType, itemType]}].
const SIZE = { char: 1, uchar: 1, int8: 1, uint8: 1, short: 2, ushort: 2, int16: 2, uint16: 2,
  int: 4, uint: 4, int32: 4, uint32: 4, float: 4, float32: 4, double: 8, float64: 8 };
const props = (element) => {
  const out = [];
  for (let i = header.findIndex((l) => l.startsWith(`element ${element} `)) + 1; i < header.length; ++i) {
    const w = header[i].split(' ');
    if (w[0] !== 'property') break;
    out.push(w[1] === 'list' ? { name: w[4], list: [w[2], w[3]] } : { name: w[2], type: w[1] });
  }
  return out;
};
// Attributes (tsm decode writes them as extra properties) are skipped: the
// browser decoder's API gives positions and indices.
const readCount = (type, at) => (SIZE[type] === 1 ? buf[at] : SIZE[type] === 2 ? buf.readUInt16LE(at) : buf.readUInt32LE(at));
const vprops = props('vertex');
if (vprops.slice(0, 3).map((p) => `${p.type} ${p.name}`).join('|') !== 'float x|float y|float z' || vprops.some((p) => p.list))
  throw new Error('unexpected vertex properties: ' + JSON.stringify(vprops));
const vstride = vprops.reduce((n, p) => n + SIZE[p.type], 0);
const fprops = props('face');
if (!fprops.length || fprops[0].name !== 'vertex_indices' || fprops[0].list.join(' ') !== 'uchar uint')
  throw new Error('unexpected face properties: ' + JSON.stringify(fprops));
let at = end + 'end_header\n'.length;
const positions = new Float32Array(3 * vertexCount);
for (let v = 0; v < vertexCount; ++v, at += vstride)
  for (let k = 0; k < 3; ++k) positions[3 * v + k] = buf.readFloatLE(at + 4 * k);
const sizes = [];
const corners = [];
let triangles = true;
for (let f = 0; f < faceCount; ++f) {
  const n = buf[at++];
  if (n !== 3) triangles = false;
  sizes.push(n);
  for (let k = 0; k < n; ++k, at += 4) corners.push(buf.readUInt32LE(at));
  for (const p of fprops.slice(1)) {
    if (p.list) {
      const c = readCount(p.list[0], at);
      at += SIZE[p.list[0]] + c * SIZE[p.list[1]];
    } else {
      at += SIZE[p.type];
    }
  }
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
