// Test helper standing in for a glTF writer: wraps a .tsm stream of a
// one-primitive glTF mesh into a .glb with the TSM_mesh_compression extension,
// given the stream's decoded mesh (vertex i of the stream is glTF vertex i).
// fallback: false -> accessors without bufferView, the extension required;
// true -> an uncompressed copy of the decoded values beside the stream.
import { BinWriter, writeGlb } from './glb.mjs';

const GLTF_SEMANTIC = { normal: 'NORMAL', texcoord: 'TEXCOORD_0', color: 'COLOR_0' };
const TYPE = { 1: 'SCALAR', 2: 'VEC2', 3: 'VEC3', 4: 'VEC4' };
const INTEGER = { u8: [5121, Uint8Array], u16: [5123, Uint16Array], i32: [5125, Uint32Array] };

export function fixtureGlb(tsmBytes, mesh, { fallback = false } = {}) {
  const n = mesh.positions.length / 3;
  const json = {
    asset: { version: '2.0', generator: 'tsm web test fixture' }, scene: 0, scenes: [{ nodes: [0] }],
    nodes: [{ mesh: 0, name: 'fixture' }], materials: [{ name: 'm', pbrMetallicRoughness: { metallicFactor: 0 } }],
    extensionsUsed: ['TSM_mesh_compression'], accessors: [],
  };
  if (!fallback) json.extensionsRequired = ['TSM_mesh_compression'];
  const w = new BinWriter(json);
  const stream = w.view(tsmBytes);
  const accessor = (array, type, extra) => {
    const a = { componentType: 5126, count: array.length / ({ SCALAR: 1, VEC2: 2, VEC3: 3, VEC4: 4 })[type], type, ...extra };
    if (fallback) a.bufferView = w.view(array);
    json.accessors.push(a);
    return json.accessors.length - 1;
  };
  const min = [0, 1, 2].map((k) => mesh.positions.filter((_, i) => i % 3 === k).reduce((x, y) => Math.min(x, y)));
  const max = [0, 1, 2].map((k) => mesh.positions.filter((_, i) => i % 3 === k).reduce((x, y) => Math.max(x, y)));
  const attributes = { POSITION: accessor(mesh.positions, 'VEC3', { min, max }) };
  const map = {};
  mesh.attributes.forEach((a, id) => {
    const semantic = GLTF_SEMANTIC[a.kind];
    if (!semantic || a.domain !== 'vertex' || semantic in attributes) return;
    const int = INTEGER[a.type];
    const values = int ? int[1].from(a.values) : a.values;
    attributes[semantic] = accessor(values, TYPE[a.components],
      int ? { componentType: int[0], ...(semantic === 'COLOR_0' ? { normalized: true } : {}) } : {});
    map[semantic] = id;
  });
  const indices = accessor(n <= 65536 ? Uint16Array.from(mesh.indices) : mesh.indices, 'SCALAR',
    { componentType: n <= 65536 ? 5123 : 5125 });
  json.meshes = [{ primitives: [{ attributes, indices, material: 0,
    extensions: { TSM_mesh_compression: { bufferView: stream, attributes: map } } }] }];
  return writeGlb(json, w.finish());
}
