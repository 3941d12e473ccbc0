// A generated test asset: a UV sphere (one primitive, u16 indices) with
// float normals, texture coordinates and u8 normalized RGBA colours, as a
// plain .glb: the mesh the glTF tests have without the corpus. Two of its
// vertices are used by no triangle (the first of the top row, the last of the
// bottom one).
import { BinWriter, writeGlb } from './glb.mjs';

export function sphereGlb(rings = 24, sectors = 40) {
  const pos = [], nrm = [], uv = [], col = [], idx = [];
  for (let r = 0; r <= rings; ++r) {
    const t = (Math.PI * r) / rings;
    for (let s = 0; s <= sectors; ++s) {
      const p = (2 * Math.PI * s) / sectors;
      const n = [Math.sin(t) * Math.cos(p), Math.cos(t), Math.sin(t) * Math.sin(p)];
      pos.push(...n); nrm.push(...n); uv.push(s / sectors, r / rings);
      col.push(Math.round(255 * (0.5 + 0.5 * n[0])), Math.round(255 * (0.5 + 0.5 * n[1])), (r * 37 + s * 11) % 256, 255);
    }
  }
  for (let r = 0; r < rings; ++r) {
    for (let s = 0; s < sectors; ++s) {
      const a = r * (sectors + 1) + s, b = a + sectors + 1;
      if (r > 0) idx.push(a, b, a + 1);
      if (r < rings - 1) idx.push(a + 1, b, b + 1);
    }
  }
  const n = pos.length / 3;
  const json = {
    asset: { version: '2.0', generator: 'tsm web test' }, scene: 0, scenes: [{ nodes: [0] }],
    nodes: [{ mesh: 0, name: 'sphere' }], materials: [{ name: 'vertex colours', pbrMetallicRoughness: { metallicFactor: 0 } }],
    meshes: [{ name: 'sphere', primitives: [{ attributes: { POSITION: 0, NORMAL: 1, TEXCOORD_0: 2, COLOR_0: 3 }, indices: 4, material: 0 }] }],
  };
  const w = new BinWriter(json);
  json.accessors = [
    { bufferView: w.view(new Float32Array(pos), 34962), componentType: 5126, count: n, type: 'VEC3', min: [-1, -1, -1], max: [1, 1, 1] },
    { bufferView: w.view(new Float32Array(nrm), 34962), componentType: 5126, count: n, type: 'VEC3' },
    { bufferView: w.view(new Float32Array(uv), 34962), componentType: 5126, count: n, type: 'VEC2' },
    { bufferView: w.view(new Uint8Array(col), 34962), componentType: 5121, normalized: true, count: n, type: 'VEC4' },
    { bufferView: w.view(new Uint16Array(idx), 34963), componentType: 5123, count: idx.length, type: 'SCALAR' },
  ];
  // min/max of POSITION as the floats stored
  const f = new Float32Array(pos);
  json.accessors[0].min = [0, 1, 2].map((k) => Math.min(...f.filter((_, i) => i % 3 === k)));
  json.accessors[0].max = [0, 1, 2].map((k) => Math.max(...f.filter((_, i) => i % 3 === k)));
  return writeGlb(json, w.finish());
}
