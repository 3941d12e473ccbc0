// Geometry decode time of compressed glTF: tsm (TSM_mesh_compression) beside
// draco3d (KHR_draco_mesh_compression) and meshoptimizer's decoder
// (EXT_meshopt_compression), on the files of /data/gltf-bench/index.json
// (made by web/test/gltf-bench.mjs). Only the decoding of the compressed
// buffer views into typed arrays is timed: no three.js, no textures.
// window.benchResult holds the figures for web/test/gltf-bench.mjs.
import { loadTsm } from '/dist/tsm.js';
import { MeshoptDecoder } from '/meshopt/meshopt_decoder.mjs';
import { loadDraco } from './draco.js';
import { dracoDecode } from './draco-decode.js';

const params = new URLSearchParams(location.search);
const REPS = Number(params.get('reps') || 15);
// Untimed decodes before the timed ones, for at least WARMUP_MS of each decoder's time and at least
// twice: V8 runs WebAssembly from its baseline compiler first and swaps in optimized code of each hot
// function when its background compile is done (a large function, on a loaded machine, takes a while):
// with 2 decodes the first asset was timed on baseline code (Fox, tsm 13.5 ms; after 40, 4.9 ms).
const WARMUP_MS = Number(params.get('warmup') || 500);
const warm = (f) => { const t0 = performance.now(); for (let i = 0; i < 2 || performance.now() - t0 < WARMUP_MS; ++i) f(); };
const result = (window.benchResult = { state: 'running', reps: REPS, rows: [] });
const log = (s) => { document.getElementById('log').textContent += '\n' + s; };
const median = (a) => { const s = [...a].sort((x, y) => x - y); const n = s.length; return n % 2 ? s[n >> 1] : (s[n / 2 - 1] + s[n / 2]) / 2; };

// A .glb's JSON and the bytes of each buffer view (buffer 0 is the binary chunk).
async function readGlb(url) {
  const bytes = new Uint8Array(await (await fetch(url)).arrayBuffer());
  const dv = new DataView(bytes.buffer);
  if (dv.getUint32(0, true) !== 0x46546c67) throw new Error(`${url}: not a .glb`);
  const jl = dv.getUint32(12, true);
  const json = JSON.parse(new TextDecoder().decode(bytes.subarray(20, 20 + jl)));
  const bin = bytes.subarray(28 + jl, 28 + jl + dv.getUint32(20 + jl, true));
  const view = (i) => { const v = json.bufferViews[i]; return bin.subarray(v.byteOffset || 0, (v.byteOffset || 0) + v.byteLength); };
  return { json, bytes, bin, view };
}

const primitives = (json) => (json.meshes || []).flatMap((m) => m.primitives);

// Each codec: the work list of a file (what to decode) and the decoding of it.
function tsmJobs(g) {
  return primitives(g.json).filter((p) => p.extensions && p.extensions.TSM_mesh_compression)
    .map((p) => g.view(p.extensions.TSM_mesh_compression.bufferView));
}
function dracoJobs(g) {
  return primitives(g.json).filter((p) => p.extensions && p.extensions.KHR_draco_mesh_compression)
    .map((p) => ({ bytes: g.view(p.extensions.KHR_draco_mesh_compression.bufferView),
      ids: Object.values(p.extensions.KHR_draco_mesh_compression.attributes) }));
}
// The meshopt-compressed buffer views of mesh geometry (gltfpack also compresses animations: not counted).
function meshoptJobs(g) {
  const geometry = new Set();
  const use = (a) => { const acc = g.json.accessors[a]; if (acc && acc.bufferView !== undefined) geometry.add(acc.bufferView); };
  for (const p of primitives(g.json)) {
    Object.values(p.attributes).forEach(use);
    if (p.indices !== undefined) use(p.indices);
    for (const t of p.targets || []) Object.values(t).forEach(use);
  }
  return g.json.bufferViews.filter((v, i) => geometry.has(i) && v.extensions && v.extensions.EXT_meshopt_compression).map((v) => {
    const e = v.extensions.EXT_meshopt_compression;
    const b = g.json.buffers[e.buffer];
    if (!b || b.uri !== undefined || e.buffer !== 0) throw new Error('meshopt data outside the .glb binary chunk');
    return { e, src: g.bin.subarray(e.byteOffset || 0, (e.byteOffset || 0) + e.byteLength) };
  });
}

function table(head, rows) {
  const t = document.createElement('table');
  t.innerHTML = '<tr>' + head.map((x) => `<th>${x}</th>`).join('') + '</tr>' +
    rows.map((r) => '<tr>' + r.map((x) => `<td>${x}</td>`).join('') + '</tr>').join('');
  document.getElementById('out').append(t);
}

async function main() {
  const index = await (await fetch('/data/gltf-bench/index.json')).json();
  const tsm = await loadTsm();
  // Files given by `tsm bench --browser` may need the full module: loaded
  // first, it decodes them all (the same code as the core's for the others).
  await tsm.loadFull();
  const draco = await loadDraco();
  await MeshoptDecoder.ready;
  const codecs = {
    tsm: { jobs: tsmJobs, run: (j) => { const m = tsm.decode(j); return { vertices: m.vertexCount, triangles: m.faceCount }; } },
    draco: { jobs: dracoJobs, run: (j) => { const m = dracoDecode(draco, j.bytes, j.ids); return { vertices: m.vertexCount, triangles: m.faceCount }; } },
    meshopt: {
      jobs: meshoptJobs,
      run: (j) => {
        const target = new Uint8Array(j.e.count * j.e.byteStride);
        MeshoptDecoder.decodeGltfBuffer(target, j.e.count, j.e.byteStride, j.src, j.e.mode, j.e.filter);
        return { bytes: target.length };
      },
    },
  };
  codecs.tsm_l0 = codecs.tsm; // the same decoder, files written at level 0
  const rows = [];
  for (const asset of index) {
    const files = {};
    for (const [codec, url] of Object.entries(asset.files)) {
      const g = await readGlb(url);
      files[codec] = { url, fileBytes: g.bytes.length, jobs: codecs[codec].jobs(g) };
      const f = files[codec];
      f.geometryBytes = f.jobs.reduce((s, j) => s + (j.src || j.bytes || j).byteLength, 0);
      if (!f.jobs.length) { log(`${url}: nothing compressed with ${codec}, left out`); delete files[codec]; }
    }
    const times = Object.fromEntries(Object.keys(files).map((c) => [c, []]));
    // One sample decodes the file's streams `inner` times (about 20 ms of the slowest codec's
    // work): the page's clock ticks in 0.1 ms steps, coarser than a small file's decode.
    const runAll = (c, inner = 1) => {
      const t0 = performance.now();
      for (let k = 0; k < inner; ++k) for (const j of files[c].jobs) codecs[c].run(j);
      return (performance.now() - t0) / inner;
    };
    for (const c of Object.keys(files)) warm(() => runAll(c));
    const slowest = Math.max(...Object.keys(files).map((c) => Math.min(runAll(c), runAll(c), runAll(c))));
    const inner = Math.max(1, Math.ceil(20 / Math.max(0.1, slowest)));
    for (let i = 0; i < REPS; ++i) for (const c of Object.keys(files)) times[c].push(runAll(c, inner));
    const row = { name: asset.name };
    for (const c of Object.keys(files)) row[c] = { fileBytes: files[c].fileBytes, geometryBytes: files[c].geometryBytes,
      streams: files[c].jobs.length, ms: median(times[c]), minMs: Math.min(...times[c]) };
    result.rows.push(row);
    log(`${asset.name}: ` + Object.keys(files).map((c) => `${c} ${row[c].ms.toFixed(2)} ms`).join(', '));
    rows.push([asset.name, ...['tsm', 'tsm_l0', 'draco', 'meshopt'].map((c) => (row[c] ? `${row[c].ms.toFixed(2)} ms (${row[c].geometryBytes.toLocaleString()} B)` : '-'))]);
    await new Promise((r) => setTimeout(r, 0));
  }
  table(['asset', 'tsm', 'tsm -l 0', 'Draco (draco3d)', 'meshopt'], rows);
  result.state = 'done';
  log('done');
}

main().catch((e) => { result.state = 'error'; result.error = String(e && e.stack || e); log('error: ' + (e.stack || e)); });
