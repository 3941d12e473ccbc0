// A three.js GLTFLoader plugin for TSM_mesh_compression: mesh primitives
// whose vertex attributes and indices are one .tsm stream in a bufferView
// (format-spec/gltf/TSM_mesh_compression.md): POSITION is the stream's
// positions, each semantic of the extension's `attributes` the decoded
// attribute of that number, each of its `targets` a morph target's
// displacements (grid units times `targetSteps`); vertex i of the stream is
// vertex i of the primitive.
//
//   import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
//   import { GLTFTsmExtension } from '@tsm-codec/decoder/three';
//   const loader = new GLTFLoader();
//   loader.register((parser) => new GLTFTsmExtension(parser, { workerThreshold: 256 * 1024 }));
//
// How it hooks in: GLTFLoader has no primitive hook for plugins (its Draco
// support is built in), but it asks plugins for each mesh (loadMesh). For a
// mesh with compressed primitives, the plugin decodes their streams, puts the
// decoded arrays into the parser's accessor cache as BufferAttributes (under
// the accessor numbers the primitives name), and lets the parser build the
// mesh as usual: materials, skinning, morph targets, bounds from the
// accessors' min/max and the attribute names (position, normal, uv, uv1..,
// color, skinIndex, skinWeight, tangent) all come from three.js itself.
import { BufferAttribute } from 'three';
import { loadTsm, decodeInWorker, createTsmWorker } from './tsm.js';

export const EXTENSION_NAME = 'TSM_mesh_compression';

const COMPONENT_TYPES = {
  5120: Int8Array, 5121: Uint8Array, 5122: Int16Array, 5123: Uint16Array, 5125: Uint32Array, 5126: Float32Array,
};
const TYPE_SIZES = { SCALAR: 1, VEC2: 2, VEC3: 3, VEC4: 4 };
// The largest value of a normalized integer type: normalized floats become integers by this factor.
const NORMALIZED_SCALE = { 5120: 127, 5121: 255, 5122: 32767, 5123: 65535, 5125: 4294967295 };

export class GLTFTsmExtension {
  /** options: { workerThreshold (bytes; streams at least this large are decoded
   *  in a Web Worker, default 256 KiB; Infinity: never, 0: always), wasmUrl,
   *  workerUrl, decodeOptions ({ maxVertices, maxFaces, maxCorners }), decoder
   *  (a TsmDecoder from loadTsm), worker (from createTsmWorker) }. Without
   *  decoder / worker, one of each per page is made when first needed and
   *  shared by all loaders. */
  constructor(parser, options = {}) {
    this.name = EXTENSION_NAME;
    this.parser = parser;
    this.options = options;
    this.workerThreshold = options.workerThreshold ?? 256 * 1024;
    this.decoder = options.decoder ? Promise.resolve(options.decoder) : null;
    this.worker = options.worker || null;
    this.streams = new Map(); // buffer view -> decoded mesh (a promise)
    this.sources = new Map(); // accessor -> the buffer view its values come from
  }

  loadMesh(meshIndex) {
    const json = this.parser.json;
    const meshDef = json.meshes[meshIndex];
    const compressed = meshDef.primitives.filter((p) => p.extensions && p.extensions[EXTENSION_NAME]);
    if (!compressed.length) return null;
    return Promise.all(compressed.map((p) => this.primePrimitive(p)))
      .then(() => this.parser.loadMesh(meshIndex));
  }

  // Decodes a primitive's stream and caches its accessors as decoded.
  async primePrimitive(primitive) {
    const parser = this.parser;
    const ext = primitive.extensions[EXTENSION_NAME];
    const view = checkIndex(ext.bufferView, parser.json.bufferViews, 'bufferView');
    // one decode per stream, however many primitives or meshes name it
    if (!this.streams.has(view)) {
      this.streams.set(view, parser.getDependency('bufferView', view).then((bytes) => this.decode(new Uint8Array(bytes))));
    }
    const mesh = await this.streams.get(view);
    const vertexCount = mesh.positions.length / 3;
    if (mesh.faceOffsets) throw new Error(`${EXTENSION_NAME}: the stream has faces that are not triangles`);
    const cache = parser.cache;
    // POSITION is always the stream's positions (the extension does not list it).
    const listed = { ...(ext.attributes || {}), POSITION: -1 };
    for (const [semantic, id] of Object.entries(listed)) {
      const accessorIndex = primitive.attributes[semantic];
      if (accessorIndex === undefined) {
        throw new Error(`${EXTENSION_NAME}: ${semantic} is compressed but the primitive has no ${semantic} accessor`);
      }
      const accessor = parser.json.accessors[checkIndex(accessorIndex, parser.json.accessors, 'accessor')];
      this.claim(accessorIndex, view);
      let values, components, type = 'f32';
      if (semantic === 'POSITION') {
        values = mesh.positions; components = 3;
      } else {
        const a = mesh.attributes[checkIndex(id, mesh.attributes, `stream attribute (${semantic})`)];
        values = perVertex(a, mesh.indices, vertexCount, semantic);
        components = a.components; type = a.type;
      }
      const attribute = toAttribute(values, components, type, vertexCount, accessor, semantic);
      cache.add(`accessor:${accessorIndex}`, Promise.resolve(attribute));
    }
    this.primeTargets(primitive, ext, mesh, view);
    if (primitive.indices !== undefined) {
      const accessor = parser.json.accessors[checkIndex(primitive.indices, parser.json.accessors, 'accessor')];
      this.claim(primitive.indices, view);
      if (accessor.count !== mesh.indices.length) {
        throw new Error(`${EXTENSION_NAME}: the indices accessor has ${accessor.count} entries, the stream ${mesh.indices.length}`);
      }
      const Type = accessor.componentType === 5123 && vertexCount <= 65536 ? Uint16Array
        : accessor.componentType === 5121 && vertexCount <= 256 ? Uint8Array : Uint32Array;
      cache.add(`accessor:${primitive.indices}`, Promise.resolve(new BufferAttribute(
        Type === Uint32Array ? mesh.indices : Type.from(mesh.indices), 1)));
    }
  }

  // Morph targets in the stream (the extension's `targets`): each listed
  // semantic's i32 grid units times its step in `targetSteps`, as floats.
  primeTargets(primitive, ext, mesh, view) {
    const parser = this.parser;
    const vertexCount = mesh.positions.length / 3;
    (ext.targets || []).forEach((map, t) => {
      for (const [semantic, id] of Object.entries(map)) {
        const name = `target ${t} ${semantic}`;
        const accessorIndex = primitive.targets && primitive.targets[t] ? primitive.targets[t][semantic] : undefined;
        if (accessorIndex === undefined) throw new Error(`${EXTENSION_NAME}: ${name} is compressed but the primitive has no such accessor`);
        const step = ext.targetSteps ? ext.targetSteps[semantic] : undefined;
        if (!(step > 0) || !Number.isFinite(step)) throw new Error(`${EXTENSION_NAME}: targetSteps.${semantic} is not a positive number`);
        const accessor = parser.json.accessors[checkIndex(accessorIndex, parser.json.accessors, 'accessor')];
        this.claim(accessorIndex, view);
        const a = mesh.attributes[checkIndex(id, mesh.attributes, `stream attribute (${name})`)];
        const units = perVertex(a, mesh.indices, vertexCount, name);
        const values = new Float32Array(units.length);
        for (let i = 0; i < units.length; ++i) values[i] = units[i] * step;
        parser.cache.add(`accessor:${accessorIndex}`,
          Promise.resolve(toAttribute(values, a.components, 'f32', vertexCount, accessor, name)));
      }
    });
  }

  // An accessor takes its values from one stream only.
  claim(accessorIndex, view) {
    const other = this.sources.get(accessorIndex);
    if (other !== undefined && other !== view) {
      throw new Error(`${EXTENSION_NAME}: accessor ${accessorIndex} is decoded from two streams (buffer views ${other} and ${view})`);
    }
    this.sources.set(accessorIndex, view);
  }

  decode(bytes) {
    const o = this.options;
    if (bytes.length >= this.workerThreshold && typeof Worker !== 'undefined') {
      const worker = this.worker || shared(workers, String(o.workerUrl || ''), () => createTsmWorker(o.workerUrl));
      return decodeInWorker(bytes, { worker, wasmUrl: o.wasmUrl, decodeOptions: o.decodeOptions });
    }
    const key = String(o.wasmUrl || '');
    const decoder = this.decoder || shared(decoders, key, () => loadTsm(o.wasmUrl ? { wasmUrl: o.wasmUrl } : {}));
    return decoder.then((d) => d.decodeAsync(bytes, o.decodeOptions).catch((e) => {
      if (d.dead && decoders.get(key) === decoder) decoders.delete(key); // aborted (out of memory): a new one next time
      throw e;
    }));
  }
}

// One main-thread decoder and one worker per page (per wasm / worker URL),
// shared by every loader and kept: each load then skips compiling the module.
const decoders = new Map();
const workers = new Map();
function shared(map, key, make) {
  if (!map.has(key)) {
    const made = make();
    map.set(key, made);
    if (made && typeof made.catch === 'function') made.catch(() => map.delete(key)); // a failed load is retried next time
  }
  return map.get(key);
}

function checkIndex(i, list, what) {
  if (!Number.isInteger(i) || i < 0 || !list || i >= list.length) {
    throw new Error(`${EXTENSION_NAME}: ${what} ${i} does not exist (${list ? list.length : 0} of them)`);
  }
  return i;
}

// A stream attribute as one value per vertex: vertex-domain values as they
// are; face- and corner-domain ones spread to the vertices of their corners.
function perVertex(a, indices, vertexCount, semantic) {
  const k = a.components;
  if (a.domain === 'vertex' && !a.indices) {
    if (a.values.length !== k * vertexCount) {
      throw new Error(`${EXTENSION_NAME}: ${semantic} has ${a.values.length / k} values for ${vertexCount} vertices`);
    }
    return a.values;
  }
  const out = new Float32Array(k * vertexCount);
  const valueCount = a.values.length / k;
  for (let c = 0; c < indices.length; ++c) {
    const v = indices[c];
    const value = a.domain === 'face' ? Math.floor(c / 3) : a.indices ? a.indices[c] : v;
    if (value >= valueCount) throw new Error(`${EXTENSION_NAME}: ${semantic} names value ${value} of ${valueCount}`);
    for (let j = 0; j < k; ++j) out[k * v + j] = a.values[k * value + j];
  }
  return out;
}

// The decoded floats in the accessor's component type: a stream attribute of
// an integer type ('u8', 'u16', 'i32') holds the accessor's integers; a float
// one ('f32') in a normalized integer accessor holds the normalized values
// ([0, 1] or [-1, 1]), scaled back to integers here.
function toAttribute(values, components, streamType, vertexCount, accessor, semantic) {
  const size = TYPE_SIZES[accessor.type];
  if (size !== components || accessor.count !== vertexCount) {
    throw new Error(`${EXTENSION_NAME}: ${semantic}: the accessor is ${accessor.count} × ${accessor.type}, ` +
      `the stream has ${vertexCount} × ${components} components`);
  }
  const Type = COMPONENT_TYPES[accessor.componentType];
  if (!Type) throw new Error(`${EXTENSION_NAME}: ${semantic}: unknown componentType ${accessor.componentType}`);
  const normalized = accessor.normalized === true;
  if (Type === Float32Array) return new BufferAttribute(values, size, normalized);
  const scale = normalized && streamType === 'f32' ? NORMALIZED_SCALE[accessor.componentType] : 1;
  const out = new Type(values.length);
  for (let i = 0; i < values.length; ++i) out[i] = Math.round(values[i] * scale);
  return new BufferAttribute(out, size, normalized);
}
