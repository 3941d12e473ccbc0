// tsm in the browser: a small API over the C API (libcodec/include/tsm/tsm.h)
// compiled to WebAssembly by web/build.sh.
//
//   import { loadTsm } from './tsm.js';
//   const tsm = await loadTsm();
//   const mesh = tsm.decode(new Uint8Array(await (await fetch('bunny.tsm')).arrayBuffer()));
//   mesh.positions  // Float32Array, 3 per vertex
//   mesh.indices    // Uint32Array, the corners of every face
//   mesh.faceOffsets // Uint32Array (faceCount + 1), only when some face is not a triangle
//   mesh.attributes  // [{ name, kind, domain, type, components, values, indices, ... }] (below)
//   mesh.metadata    // [{ key, value: Uint8Array }]
//
//   // streaming: each segment as soon as its bytes are in
//   for await (const seg of tsm.decodeStream((await fetch('dragon.tsm')).body)) draw(seg);
//
//   // the same in a Web Worker (the page's thread stays free); a worker made
//   // with createTsmWorker() can be passed as { worker } and reused
//   for await (const seg of decodeStreamInWorker((await fetch('dragon.tsm')).body)) draw(seg);
//
// Results are plain typed arrays that own their memory: each is one bulk
// copy (TypedArray.prototype.slice) of a view on the WebAssembly heap, made
// once per decode or per segment; nothing is copied element by element.
//
// A segment is { index, vertexStart, vertexCount, faceStart, faceCount,
// cornerStart, positions, indices, faceOffsets?, segmentCount, segmentsDone,
// bytesIn, decodeMs }: positions are the segment's new vertices (3 floats each, global
// numbers vertexStart..), indices are global vertex numbers (they may refer to
// vertices of earlier segments), faceOffsets (only when the segment has a
// face that is not a triangle) are faceCount + 1 offsets into the whole
// mesh's corner array: subtract cornerStart to index this segment's indices.
// bytesIn is the input fed so far, decodeMs the time spent in the decoder so
// far (feed and finish calls, copies out included).
//
// Attributes (normals, colours, texture coordinates, other values; a decoded
// mesh and every segment have the list, [] when the file has none): { name,
// kind ('generic' | 'normal' | 'color' | 'texcoord'), domain ('vertex' |
// 'face' | 'corner'), type ('f32' | 'u8' | 'u16' | 'i32': how the values were
// stored; they are floats here), components (1..4), values (Float32Array,
// components per value), valueStart, valueCount, indices (corner domain: a
// Uint32Array, one entry per face corner in the order of `indices`, naming a
// value; else null) }. In a decoded mesh valueStart is 0 and values is all of
// them. In a segment the lists are pieces to append: vertex-domain values are
// those of the segment's new vertices (valueStart = vertexStart), face-domain
// ones those of its faces (valueStart = faceStart), and a corner attribute
// gives the values the segment added to its value list (numbers valueStart..
// valueStart + valueCount - 1) and the indices of the segment's corners (global
// value numbers, possibly naming values of earlier segments). Appending each
// piece's values and indices gives the whole mesh's lists.
//
// Progressive files (`tsm encode --progressive`: a base mesh, then batches of
// vertex splits): once the base mesh is whole, each piece is a level of
// detail of the whole shape, { level: true, batchesDone, levelError,
// vertexStart: 0, faceStart: 0, positions, indices, ... }: the whole mesh
// (batches change faces in place), to draw instead of what came before.
// One piece per level (the base, then each batch), even when a chunk holds
// several; levelError is the encoder's error of the level (the largest
// distance of a full-mesh vertex from it, model units), -1 while unknown.
//
// Metadata (entries the codec passes through, e.g. key 'gltf'): [{ key (a
// string, UTF-8), value (Uint8Array) }] on a decoded mesh; in a stream, the
// whole list on the piece where it first appears (that piece may have no
// vertices or faces), else absent.
//
// Two modules: tsm_decoder.wasm, the core that loadTsm() loads, decodes what
// the encoder writes by default; tsm_decoder_full.wasm adds the paths files
// rarely need (progressive batches, keep-order, zstd-coded sections) and is
// loaded only when a file needs one of them: decodeAsync, decodeStream and
// the worker functions load it by themselves; decode() (synchronous) throws
// a TsmError with needsFull set unless loadFull() has been awaited before
// (or loadTsm({ full: true }) was called).
import createTsmModule from './tsm_decoder.js';

const ERR_SIZE = 512;
const utf8 = new TextDecoder(); // one for all names and keys: a TextDecoder per string costs more than the string
const OPTIONS_SIZE = 64; // room for tsm_decode_options (three uint64 and an int: 32 bytes today)

export const ErrorCode = Object.freeze({
  OK: 0, INVALID_ARGUMENT: 1, IO_ERROR: 2, PARSE_ERROR: 3, CORRUPT_DATA: 4,
  UNSUPPORTED: 5, LIMIT_EXCEEDED: 6, INTERNAL: 7,
});
const CODE_NAMES = Object.fromEntries(Object.entries(ErrorCode).map(([k, v]) => [v, k.toLowerCase()]));
// The C API's TSM_KIND_*, TSM_DOMAIN_*, TSM_TYPE_* values, by index.
export const AttributeKinds = Object.freeze(['generic', 'normal', 'color', 'texcoord']);
export const AttributeDomains = Object.freeze(['vertex', 'face', 'corner']);
export const AttributeTypes = Object.freeze(['f32', 'u8', 'u16', 'i32']);

export class TsmError extends Error {
  constructor(code, message) {
    super(message || CODE_NAMES[code] || `error ${code}`);
    this.name = 'TsmError';
    this.code = code;
    this.codeName = CODE_NAMES[code] || 'unknown';
  }
}

const DEFAULT_WASM = new URL('./tsm_decoder.wasm', import.meta.url).href;
const DEFAULT_FULL_WASM = new URL('./tsm_decoder_full.wasm', import.meta.url).href;

function moduleArgs(wasmBinary, wasmUrl) {
  if (wasmBinary) return { wasmBinary };
  return { locateFile: (name) => (name.endsWith('.wasm') ? wasmUrl : name) };
}

/** Loads the WebAssembly decoder. options: { wasmUrl, wasmBinary, fullWasmUrl,
 *  fullWasmBinary, full } (wasmBinary, an ArrayBuffer or Uint8Array, skips the
 *  fetch: needed under Node; the full* ones are the full module's, fetched or
 *  used when a file first needs it; full: true loads the full module now). */
export async function loadTsm(options = {}) {
  const mod = await createTsmModule(moduleArgs(options.wasmBinary, options.wasmUrl || DEFAULT_WASM));
  const loadFull = async () => {
    const { default: createFull } = await import('./tsm_decoder_full.js');
    return new TsmDecoder(await createFull(moduleArgs(options.fullWasmBinary, options.fullWasmUrl || DEFAULT_FULL_WASM)));
  };
  const dec = new TsmDecoder(mod, loadFull);
  if (options.full) await dec.loadFull();
  return dec;
}

// What a core module's call hands back when it reached a path only the full module has.
const NEEDS_FULL = Symbol('needs the full module');

// What decode(), feed() and finish() throw while a file needs the full module and it is not loaded.
function needsFullError() {
  const e = new TsmError(ErrorCode.UNSUPPORTED,
    'this file needs the full decoder module (tsm_decoder_full.wasm): await loadFull() first, or use decodeAsync');
  e.needsFull = true;
  return e;
}

// run(); when it throws needsFull: the full module loaded (once), then retry().
async function withFull(dec, run, retry) {
  try {
    return run();
  } catch (e) {
    if (!e.needsFull) throw e;
    await dec.loadFull();
    return retry();
  }
}

export class TsmDecoder {
  constructor(mod, loadFull) {
    this.mod = mod;
    // A core module (tsm_web_core_refused exported) and how to load the full one.
    this.core = typeof mod._tsm_web_core_refused === 'function';
    this.loadFullModule = loadFull;
    this.full = null;
    this.fullReady = null;
    this.errPtr = mod._malloc(ERR_SIZE);
    this.optPtr = mod._malloc(OPTIONS_SIZE);
    this.outPtr = mod._malloc(4); // tsm_mesh* out-parameter
    this.sizePtr = mod._malloc(4); // size_t out-parameter (metadata sizes)
    this.inPtr = 0;
    this.inCap = 0;
    this.hasStreaming = typeof mod._tsm_stream_new === 'function';
    this.hasAttributes = typeof mod._tsm_mesh_attribute_count === 'function';
    this.hasMetadata = typeof mod._tsm_mesh_metadata_count === 'function';
    this.hasLevels = typeof mod._tsm_stream_stop_at_levels === 'function';
  }

  /** The library's version string. */
  get version() { return this.cstring(this.mod._tsm_version()); }

  /** Decodes a whole .tsm file (Uint8Array or ArrayBuffer). options: { maxVertices,
   *  maxFaces, maxCorners } refuse larger files before anything is allocated.
   *  Returns { positions, indices, faceOffsets?, vertexCount, faceCount, attributes,
   *  metadata } (see the top of this file). */
  decode(bytes, options) {
    // Once loaded, the full module decodes everything (the core would only repeat its work on files it lacks a path for).
    if (this.full) return this.full.decode(bytes, options);
    const r = this.guard(() => this.decodeNow(bytes, options));
    if (r === NEEDS_FULL) throw needsFullError();
    return r;
  }

  /** decode(), loading the full module first when the file needs it. */
  decodeAsync(bytes, options) {
    return withFull(this, () => this.decode(bytes, options), () => this.full.decode(bytes, options));
  }

  /** Loads the full module (once); decode() then handles every file. */
  loadFull() {
    if (!this.core) return Promise.resolve(this);
    this.fullReady = this.fullReady || this.loadFullModule().then((d) => (this.full = d));
    return this.fullReady.catch((err) => { this.fullReady = null; throw err; });
  }

  // The full module's decoder; throws (needsFull) while it is not loaded.
  fullDecoder() {
    if (this.full) return this.full;
    throw needsFullError();
  }

  // Whether the last call into a core module reached a path it lacks (clears the flag).
  refused() { return this.core && this.mod._tsm_web_core_refused() !== 0; }

  decodeNow(bytes, options) {
    const m = this.mod;
    const data = toBytes(bytes);
    const inPtr = this.input(data);
    const opt = this.options(options);
    const rc = m._tsm_decode(inPtr, data.length, opt, this.outPtr, this.errPtr, ERR_SIZE);
    if (this.refused()) {
      if (rc === 0) m._tsm_mesh_free(m.HEAPU32[this.outPtr >> 2]);
      return NEEDS_FULL;
    }
    if (rc !== 0) throw new TsmError(rc, this.cstring(this.errPtr));
    const mesh = m.HEAPU32[this.outPtr >> 2];
    try {
      const r = this.extract(mesh, 0, 0, m._tsm_mesh_vertex_count(mesh), m._tsm_mesh_face_count(mesh), true);
      r.metadata = this.metadata(mesh);
      return r;
    } finally {
      m._tsm_mesh_free(mesh);
    }
  }

  /** A streaming decoder: feed(chunk) and finish() return the segments that chunk
   *  completed (often none, sometimes several). */
  createStream(options) { return new TsmStream(this.full || this, options); }

  /** Decodes a ReadableStream (a fetch body) or any (async) iterable of byte
   *  chunks, yielding each segment as soon as it is decoded. Leaving the loop
   *  early (or an error) cancels a ReadableStream source. */
  async *decodeStream(source, options) {
    const stream = this.createStream(options);
    try {
      for await (const chunk of chunks(source)) {
        for (const seg of await stream.feedAsync(chunk)) yield seg;
      }
      for (const seg of await stream.finishAsync()) yield seg;
    } finally {
      stream.free();
    }
  }

  // ---- internals ----------------------------------------------------------

  // Runs f; an abort inside the WebAssembly module (out of memory: the build
  // has C++ exception catching off, so std::bad_alloc aborts) leaves the
  // module unusable: every later call fails at once with this error.
  guard(f) {
    if (this.dead) throw this.dead;
    try {
      return f();
    } catch (e) {
      if (e instanceof TsmError) throw e;
      this.dead = new TsmError(ErrorCode.INTERNAL, `the decoder aborted (${e && e.message || e}); load a new one`);
      throw this.dead;
    }
  }

  input(data) { // copies the input into the heap (one set), reusing one buffer
    const m = this.mod;
    if (data.length > this.inCap) {
      if (this.inPtr) m._free(this.inPtr);
      this.inCap = Math.max(data.length, this.inCap * 2, 1 << 16);
      this.inPtr = m._malloc(this.inCap);
      if (!this.inPtr) { this.inCap = 0; throw new TsmError(ErrorCode.LIMIT_EXCEEDED, 'out of memory'); }
    }
    m.HEAPU8.set(data, this.inPtr);
    return this.inPtr;
  }

  options(o) {
    if (!o) return 0;
    const m = this.mod;
    m.HEAPU8.fill(0, this.optPtr, this.optPtr + OPTIONS_SIZE);
    const put = (i, v) => {
      const n = Number(v || 0);
      m.HEAPU32[(this.optPtr >> 2) + 2 * i] = n % 4294967296;
      m.HEAPU32[(this.optPtr >> 2) + 2 * i + 1] = Math.floor(n / 4294967296);
    };
    put(0, o.maxVertices); put(1, o.maxFaces); put(2, o.maxCorners);
    m.HEAP32[(this.optPtr >> 2) + 6] = 1; // threads: the WebAssembly build decodes on one
    return this.optPtr;
  }

  cstring(ptr) {
    const h = this.mod.HEAPU8;
    ptr >>>= 0;
    let end = ptr;
    while (h[end]) ++end;
    return utf8.decode(h.subarray(ptr, end));
  }

  // Copies vertices [v0, v1) and faces [f0, f1) of a tsm_mesh out of the heap:
  // one slice per array. The heap views are read after the decode, since a
  // grown memory replaces them. valueStarts[i]: where corner attribute i's
  // new values start (a stream's values reported so far; 0 when absent).
  // Pointers come back from WebAssembly as signed 32-bit numbers: >>> makes
  // them unsigned (a heap above 2 GB).
  extract(mesh, v0, f0, v1, f1, whole, valueStarts) {
    const m = this.mod;
    const pos = m._tsm_mesh_positions(mesh) >>> 2;
    const idx = m._tsm_mesh_indices(mesh) >>> 2;
    const cornerCount = m._tsm_mesh_index_count(mesh);
    let c0, c1, faceOffsets;
    const allTriangles = cornerCount === 3 * m._tsm_mesh_face_count(mesh);
    if (allTriangles) {
      c0 = 3 * f0; c1 = 3 * f1;
    } else {
      const off = m._tsm_mesh_face_offsets(mesh) >>> 2;
      const U = m.HEAPU32;
      c0 = U[off + f0]; c1 = U[off + f1];
      if (c1 - c0 !== 3 * (f1 - f0) || whole) faceOffsets = U.subarray(off + f0, off + f1 + 1).slice();
    }
    const r = {
      vertexStart: v0, vertexCount: v1 - v0, faceStart: f0, faceCount: f1 - f0, cornerStart: c0,
      positions: m.HEAPF32.subarray(pos + 3 * v0, pos + 3 * v1).slice(),
      indices: m.HEAPU32.subarray(idx + c0, idx + c1).slice(),
    };
    if (faceOffsets) r.faceOffsets = faceOffsets;
    r.attributes = this.attributes(mesh, v0, f0, v1, f1, c0, c1, valueStarts);
    return r;
  }

  // The attributes' pieces for vertices [v0, v1), faces [f0, f1), corners
  // [c0, c1): one slice of values (and of indices) each.
  attributes(mesh, v0, f0, v1, f1, c0, c1, valueStarts) {
    const m = this.mod;
    const out = [];
    const n = this.hasAttributes ? m._tsm_mesh_attribute_count(mesh) : 0;
    for (let i = 0; i < n; ++i) {
      const components = m._tsm_mesh_attribute_components(mesh, i);
      const domain = m._tsm_mesh_attribute_domain(mesh, i);
      let s0, s1;
      if (domain === 0) { s0 = v0; s1 = v1; }
      else if (domain === 1) { s0 = f0; s1 = f1; }
      else { s0 = (valueStarts && valueStarts[i]) || 0; s1 = m._tsm_mesh_attribute_value_count(mesh, i) >>> 0; }
      const vals = m._tsm_mesh_attribute_values(mesh, i) >>> 2;
      const a = {
        name: this.cstring(m._tsm_mesh_attribute_name(mesh, i)),
        kind: AttributeKinds[m._tsm_mesh_attribute_kind(mesh, i)] || 'generic',
        domain: AttributeDomains[domain],
        type: AttributeTypes[m._tsm_mesh_attribute_type(mesh, i)] || 'f32',
        components, valueStart: s0, valueCount: s1 - s0,
        values: m.HEAPF32.subarray(vals + components * s0, vals + components * s1).slice(),
        indices: null,
      };
      if (domain === 2) {
        const ix = m._tsm_mesh_attribute_indices(mesh, i) >>> 2;
        a.indices = m.HEAPU32.subarray(ix + c0, ix + c1).slice();
      }
      out.push(a);
    }
    return out;
  }

  // The mesh's metadata entries, keys as strings, values copied out.
  metadata(mesh) {
    const m = this.mod;
    const out = [];
    const n = this.hasMetadata ? m._tsm_mesh_metadata_count(mesh) : 0;
    for (let i = 0; i < n; ++i) {
      const k = m._tsm_mesh_metadata_key(mesh, i, this.sizePtr) >>> 0;
      const kn = m.HEAPU32[this.sizePtr >> 2];
      const v = m._tsm_mesh_metadata_value(mesh, i, this.sizePtr) >>> 0;
      const vn = m.HEAPU32[this.sizePtr >> 2];
      out.push({ key: utf8.decode(m.HEAPU8.subarray(k, k + kn)), value: m.HEAPU8.slice(v, v + vn) });
    }
    return out;
  }
}

export class TsmStream {
  constructor(dec, options) {
    this.dec = dec;
    this.m = dec.mod;
    this.v = 0; this.f = 0; this.segIndex = 0; this.bytesIn = 0;
    this.valueCounts = []; // per corner attribute: its values handed out so far
    this.metaCount = 0;    // metadata entries handed out (all of them once any)
    this.decodeMs = 0; // time spent decoding (in feed/finish, copies out included)
    this.failed = null;
    this.levelBatches = -1; // progressive files: the batches of the last level handed out
    if (dec.hasStreaming) {
      this.s = this.m._tsm_stream_new(dec.options(options));
      if (!this.s) throw new TsmError(ErrorCode.LIMIT_EXCEEDED, 'out of memory');
      if (dec.hasLevels) this.m._tsm_stream_stop_at_levels(this.s, 1);
      // On a core module: the chunks so far, for the full module's stream
      // that takes over when the file needs it (toFull); pieces handed out.
      this.opts = options;
      this.fed = dec.core ? [] : null;
      this.delivered = 0;
      this.inner = null;   // the full module's stream, once it took over
      this.switching = 0;  // 1: a feed, 2: finish reached a path the core lacks; the full module is awaited
    } else {
      // The library has no streaming API yet: gather the chunks, decode at finish.
      this.s = 0; this.parts = []; this.opts = options;
    }
  }

  get segmentCount() {
    if (this.inner) return this.inner.segmentCount;
    return this.s ? this.m._tsm_stream_segment_count(this.s) : (this.done ? 1 : 0);
  }
  get segmentsDone() {
    if (this.inner) return this.inner.segmentsDone;
    return this.s ? this.m._tsm_stream_segments_done(this.s) : (this.done ? 1 : 0);
  }

  feed(chunk) {
    if (this.inner) return this.inner.feed(chunk);
    const data = toBytes(chunk);
    this.bytesIn += data.length;
    if (this.failed) throw this.failed;
    if (this.switching) { // throws until the full module is loaded
      if (data.length) this.fed.push(data.slice());
      return this.toFull();
    }
    if (!this.s) { this.parts.push(data.slice()); return []; }
    if (data.length === 0) return [];
    if (this.fed) this.fed.push(data.slice());
    const out = this.dec.guard(() => {
      const t0 = now();
      const ptr = this.dec.input(data);
      const rc = this.m._tsm_stream_feed(this.s, ptr, data.length, this.dec.errPtr, ERR_SIZE);
      if (this.dec.refused()) return NEEDS_FULL;
      const pieces = this.collect(rc, t0);
      const levels = this.pendingLevels();
      return levels === NEEDS_FULL ? NEEDS_FULL : pieces.concat(levels);
    });
    if (out === NEEDS_FULL) { this.switching = 1; return this.toFull(); }
    this.delivered += out.length;
    return out;
  }

  /** feed(), loading the full module when the file needs it. */
  feedAsync(chunk) {
    return withFull(this.dec, () => this.feed(chunk), () => this.toFull());
  }

  /** finish(), loading the full module when the file needs it. */
  finishAsync() {
    return withFull(this.dec, () => this.finish(), () => this.toFull());
  }

  // Hands the stream to the full module: a stream of its own is fed the
  // chunks so far (the same chunks give the same pieces) and the pieces
  // already handed out are dropped; throws (needsFull) while the full
  // module is not loaded.
  toFull() {
    const full = this.dec.fullDecoder();
    const inner = new TsmStream(full, this.opts);
    let out = [];
    for (const c of this.fed) out = out.concat(inner.feed(c));
    if (this.switching === 2) out = out.concat(inner.finish());
    out = out.slice(this.delivered);
    if (this.s && !this.dec.dead) this.m._tsm_stream_free(this.s);
    this.s = 0; this.fed = null; this.inner = inner; this.switching = 0;
    return out;
  }

  // Levels of a progressive file left in the chunk after the first: one
  // piece each.
  pendingLevels() {
    const out = [];
    while (this.dec.hasLevels && this.m._tsm_stream_level_pending(this.s)) {
      const t0 = now();
      const rc = this.m._tsm_stream_feed(this.s, 0, 0, this.dec.errPtr, ERR_SIZE);
      if (this.dec.refused()) return NEEDS_FULL;
      out.push(...this.collect(rc, t0));
    }
    return out;
  }

  finish() {
    if (this.inner) return this.inner.finish();
    if (this.failed) throw this.failed;
    if (this.switching) { this.switching = 2; return this.toFull(); }
    const t0 = now();
    if (!this.s) {
      const all = concat(this.parts, this.bytesIn);
      this.parts = [];
      const mesh = this.dec.decode(all, this.opts);
      this.done = true;
      this.decodeMs += now() - t0;
      return [{ ...mesh, index: 0, segmentCount: 1, segmentsDone: 1, bytesIn: this.bytesIn, decodeMs: this.decodeMs }];
    }
    const out = this.dec.guard(() => {
      const levels = this.pendingLevels();
      if (levels === NEEDS_FULL) return NEEDS_FULL;
      const rc = this.m._tsm_stream_finish(this.s, this.dec.errPtr, ERR_SIZE);
      if (this.dec.refused()) return NEEDS_FULL;
      return levels.concat(this.collect(rc, t0));
    });
    if (out === NEEDS_FULL) { this.switching = 2; return this.toFull(); }
    this.delivered += out.length;
    return out;
  }

  collect(rc, t0) {
    try {
      return this.collectSegments(rc);
    } finally {
      this.decodeMs += now() - t0;
      if (this.last) { this.last.decodeMs = this.decodeMs; this.last = null; }
    }
  }

  collectSegments(rc) {
    const m = this.m;
    if (rc !== 0) {
      this.failed = new TsmError(rc, this.dec.cstring(this.dec.errPtr));
      throw this.failed;
    }
    const mesh = m._tsm_stream_mesh(this.s);
    const v1 = m._tsm_mesh_vertex_count(mesh);
    const f1 = m._tsm_mesh_face_count(mesh);
    const done = m._tsm_stream_segments_done(this.s);
    const metaCount = this.dec.hasMetadata ? m._tsm_mesh_metadata_count(mesh) : 0;
    if (this.dec.hasLevels && m._tsm_stream_progressive(this.s)) return this.collectLevel(mesh, v1, f1, done, metaCount);
    if (v1 === this.v && f1 === this.f && done === this.segIndex && metaCount === this.metaCount) return [];
    // Everything finished since the last call comes out as one piece (several
    // segments finished by one chunk are reported together).
    const seg = this.dec.extract(mesh, this.v, this.f, v1, f1, false, this.valueCounts);
    for (let i = 0; i < seg.attributes.length; ++i) {
      const a = seg.attributes[i];
      if (a.domain === 'corner') this.valueCounts[i] = a.valueStart + a.valueCount;
    }
    if (metaCount !== this.metaCount) { seg.metadata = this.dec.metadata(mesh); this.metaCount = metaCount; }
    seg.index = this.segIndex;
    seg.segmentsDone = done;
    seg.segmentCount = m._tsm_stream_segment_count(this.s);
    seg.bytesIn = this.bytesIn;
    this.v = v1; this.f = f1; this.segIndex = done;
    this.last = seg; // gets decodeMs: time spent in feed/finish so far, this call included
    return [seg];
  }

  // A progressive file's level: the whole mesh, when it changed.
  collectLevel(mesh, v1, f1, done, metaCount) {
    const m = this.m;
    const batches = m._tsm_stream_batches_done(this.s);
    if (batches === this.levelBatches && v1 === this.v && f1 === this.f) return [];
    const level = this.dec.extract(mesh, 0, 0, v1, f1, true);
    if (metaCount !== this.metaCount) { level.metadata = this.dec.metadata(mesh); this.metaCount = metaCount; }
    Object.assign(level, { level: true, batchesDone: batches, levelError: m._tsm_stream_level_error(this.s),
      index: done, segmentsDone: done, segmentCount: m._tsm_stream_segment_count(this.s), bytesIn: this.bytesIn });
    this.levelBatches = batches; this.v = v1; this.f = f1; this.segIndex = done;
    this.last = level;
    return [level];
  }

  free() {
    if (this.inner) this.inner.free();
    if (this.s && !this.dec.dead) this.m._tsm_stream_free(this.s);
    this.s = 0; this.parts = [];
    if (!this.failed) this.failed = new TsmError(ErrorCode.INVALID_ARGUMENT, 'stream already freed');
  }
}

let runCounter = 0;

/** A Web Worker running tsm-worker.js (beside this file), to pass as
 *  options.worker to decodeStreamInWorker and reuse for several files: the
 *  module is then loaded and compiled once. */
export function createTsmWorker(workerUrl) {
  return new Worker(workerUrl || new URL('./tsm-worker.js', import.meta.url), { type: 'module' });
}

/** Streams source (fetch body, iterable of chunks) through a decoder in a Web
 *  Worker; yields the same segments as decodeStream, their arrays transferred
 *  from the worker. options: { worker (from createTsmWorker, kept; else a
 *  worker is made for this call and ended after it), workerUrl, wasmUrl,
 *  decodeOptions }. One stream at a time per worker. */
export async function* decodeStreamInWorker(source, options = {}) {
  const own = !options.worker;
  const worker = options.worker || createTsmWorker(options.workerUrl);
  const queue = [];
  let wake = null, ended = false, error = null, stopped = false;
  const id = ++runCounter; // messages of an earlier, abandoned run on a reused worker are ignored
  worker.onmessage = (e) => {
    const msg = e.data;
    if (msg.id !== id) return;
    if (msg.type === 'segment') queue.push(msg.segment);
    else if (msg.type === 'done') ended = true;
    else if (msg.type === 'error') { error = new TsmError(msg.code, msg.message); ended = true; }
    if (wake) { wake(); wake = null; }
  };
  worker.onerror = (e) => { error = new Error(e.message || 'worker failed'); ended = true; if (wake) { wake(); wake = null; } };
  worker.postMessage({ type: 'start', id, wasmUrl: options.wasmUrl, decodeOptions: options.decodeOptions });
  // Chunks of a ReadableStream are ours to hand over (transferred); others are copied first.
  const transferable = !!(source && typeof source.getReader === 'function');
  // Pump the input into the worker while segments come back.
  const pump = (async () => {
    try {
      for await (const chunk of chunks(source)) {
        if (stopped) return; // the consumer left: stop reading (the reader is released)
        const c = toBytes(chunk);
        const mine = transferable && c.byteOffset === 0 && c.byteLength === c.buffer.byteLength ? c : c.slice();
        worker.postMessage({ type: 'chunk', bytes: mine }, [mine.buffer]);
      }
      worker.postMessage({ type: 'end' });
    } catch (e) {
      error = e; ended = true;
      if (wake) { wake(); wake = null; }
    }
  })();
  try {
    for (;;) {
      while (queue.length) yield queue.shift();
      if (error) throw error;
      if (ended) break;
      await new Promise((r) => { wake = r; });
    }
    await pump;
  } finally {
    stopped = true;
    worker.onmessage = null;
    worker.onerror = null;
    if (own) worker.terminate();
    else if (!ended) worker.postMessage({ type: 'cancel' });
  }
}

/** Decodes a whole .tsm file (Uint8Array or ArrayBuffer) in a Web Worker;
 *  resolves to what TsmDecoder.decode returns, its arrays transferred from the
 *  worker. The bytes are copied to the worker (the caller's stay intact).
 *  options: { worker (from createTsmWorker, kept; several decodes may share
 *  it, they run one after another), workerUrl, wasmUrl, decodeOptions }. */
export function decodeInWorker(bytes, options = {}) {
  const own = !options.worker;
  const worker = options.worker || createTsmWorker(options.workerUrl);
  const id = ++runCounter;
  const copy = toBytes(bytes).slice();
  return new Promise((resolve, reject) => {
    const done = () => {
      worker.removeEventListener('message', onMessage);
      worker.removeEventListener('error', onError);
      if (own) worker.terminate();
    };
    const onMessage = (e) => {
      const msg = e.data;
      if (msg.id !== id) return;
      done();
      if (msg.type === 'mesh') resolve(msg.mesh);
      else reject(new TsmError(msg.code, msg.message));
    };
    const onError = (e) => { done(); reject(new Error(e.message || 'the tsm worker failed')); };
    worker.addEventListener('message', onMessage);
    worker.addEventListener('error', onError);
    worker.postMessage({ type: 'decode', id, bytes: copy, wasmUrl: options.wasmUrl,
      decodeOptions: options.decodeOptions }, [copy.buffer]);
  });
}

// ---- helpers ----------------------------------------------------------------

const now = () => (typeof performance !== 'undefined' ? performance.now() : Date.now());

function toBytes(b) {
  if (b instanceof Uint8Array) return b;
  if (b instanceof ArrayBuffer) return new Uint8Array(b);
  if (ArrayBuffer.isView(b)) return new Uint8Array(b.buffer, b.byteOffset, b.byteLength);
  throw new TypeError('expected a Uint8Array or ArrayBuffer');
}

async function* chunks(source) {
  if (source && typeof source.getReader === 'function') { // ReadableStream
    const reader = source.getReader();
    let finished = false;
    try {
      for (;;) {
        const { done, value } = await reader.read();
        if (done) { finished = true; return; }
        yield value;
      }
    } finally {
      // Left early (the consumer stopped, or decoding failed): cancel the download.
      if (!finished) reader.cancel().catch(() => {});
      reader.releaseLock();
    }
  } else if (source instanceof Uint8Array || source instanceof ArrayBuffer) {
    yield source;
  } else {
    yield* source;
  }
}

function concat(parts, total) {
  if (parts.length === 1) return parts[0];
  const out = new Uint8Array(total);
  let at = 0;
  for (const p of parts) { out.set(p, at); at += p.length; }
  return out;
}
