// Decode times under Node (V8, the engine of Chromium): tsm's wasm decoder
// (build/web) beside draco3d's, in one process, taking turns; the same calls
// as web/demo/bench.js and gltf-bench.js (web/demo/draco-decode.js: the decode
// and the copies of the output arrays out of the heap), medians and the fastest sample (steadier
// on a loaded machine). Files: build/web/data/NAME.tsm and
// .drc (web/prepare-data.sh) and the glTF bench's .glb files
// (build/web/data/gltf-bench/, web/test/gltf-bench.mjs).
//   node web/tools/node-bench.mjs [--reps N] [--meshes a,b] [--dist DIR]
import fs from 'node:fs';
import path from 'node:path';
import zlib from 'node:zlib';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { createRequire } from 'node:module';
import { dracoDecode } from '../demo/draco-decode.js';

const here = path.dirname(fileURLToPath(import.meta.url));
const root = path.resolve(here, '../..');
const arg = (name, d) => { const i = process.argv.indexOf(name); return i > 0 ? process.argv[i + 1] : d; };
const REPS = Number(arg('--reps', '21'));
const dist = path.resolve(arg('--dist', path.join(root, 'build/web')));
const data = path.join(root, 'build/web/data');
const only = arg('--meshes', null)?.split(',');

const { loadTsm } = await import(pathToFileURL(path.join(dist, 'tsm.js')).href);
const require = createRequire(path.join(root, 'web/node_modules/draco3d/package.json'));
const dracoDir = path.join(root, 'web/node_modules/draco3d');
const DracoDecoderModule = require(path.join(dracoDir, 'draco_decoder_nodejs.js'));
const tsm = await loadTsm({ wasmBinary: fs.readFileSync(path.join(dist, 'tsm_decoder.wasm')) });
const draco = await DracoDecoderModule({ wasmBinary: fs.readFileSync(path.join(dracoDir, 'draco_decoder.wasm')) });

const median = (a) => { const s = [...a].sort((x, y) => x - y); const n = s.length; return n % 2 ? s[n >> 1] : (s[n / 2 - 1] + s[n / 2]) / 2; };

function readGlb(file) {
  const bytes = new Uint8Array(fs.readFileSync(file));
  const dv = new DataView(bytes.buffer, bytes.byteOffset);
  const jl = dv.getUint32(12, true);
  const json = JSON.parse(new TextDecoder().decode(bytes.subarray(20, 20 + jl)));
  const bin = bytes.subarray(28 + jl, 28 + jl + dv.getUint32(20 + jl, true));
  const view = (i) => { const v = json.bufferViews[i]; return bin.subarray(v.byteOffset || 0, (v.byteOffset || 0) + v.byteLength).slice(); };
  const prims = (json.meshes || []).flatMap((m) => m.primitives);
  return { json, view, prims };
}

const cases = [];
// bunny_pos: the bunny without its confidence and intensity, which Draco's PLY reader drops.
for (const [name, drc] of [['bunny', 'bunny'], ['bunny_pos', 'bunny'], ['dragon_res2', 'dragon_res2']]) {
  if (fs.existsSync(path.join(data, `${name}.tsm`)) && fs.existsSync(path.join(data, `${drc}.drc`)))
    cases.push({ name, tsm: [new Uint8Array(fs.readFileSync(path.join(data, `${name}.tsm`)))],
      draco: [{ bytes: new Int8Array(fs.readFileSync(path.join(data, `${drc}.drc`))) }] });
}
const gb = path.join(data, 'gltf-bench');
for (const name of ['Fox', 'CesiumMilkTruck', '2CylinderEngine', 'MultiUVTest', 'VertexColorTest']) {
  const t = path.join(gb, `${name}.tsm.glb`), d = path.join(gb, `${name}.draco.glb`);
  if (!fs.existsSync(t) || !fs.existsSync(d)) continue;
  const g = readGlb(t), h = readGlb(d);
  cases.push({ name,
    tsm: g.prims.filter((p) => p.extensions?.TSM_mesh_compression).map((p) => g.view(p.extensions.TSM_mesh_compression.bufferView)),
    draco: h.prims.filter((p) => p.extensions?.KHR_draco_mesh_compression).map((p) => ({
      bytes: h.view(p.extensions.KHR_draco_mesh_compression.bufferView),
      ids: Object.values(p.extensions.KHR_draco_mesh_compression.attributes) })) });
}

const rows = [];
for (const c of cases) {
  if (only && !only.includes(c.name)) continue;
  // Each sample repeats the decode `inner` times (about 20 ms of tsm decoding) so small files time well.
  const time = (f, inner) => { const t0 = performance.now(); for (let i = 0; i < inner; ++i) f(); return (performance.now() - t0) / inner; };
  const decT = () => { for (const b of c.tsm) tsm.decode(b); };
  const decD = () => { for (const j of c.draco) dracoDecode(draco, j.bytes, j.ids); };
  for (let i = 0; i < 3; ++i) { decT(); decD(); }
  const inner = Math.max(1, Math.ceil(20 / Math.max(0.01, time(decT, 1))));
  const ts = [], ds = [];
  for (let i = 0; i < REPS; ++i) { ts.push(time(decT, inner)); ds.push(time(decD, inner)); }
  rows.push({ name: c.name, streams: c.tsm.length, tsmMs: median(ts), dracoMs: median(ds),
    tsmMinMs: Math.min(...ts), dracoMinMs: Math.min(...ds) });
}
const gz = (f) => zlib.gzipSync(fs.readFileSync(f), { level: 9 }).length;
const br = (f) => zlib.brotliCompressSync(fs.readFileSync(f)).length;
// Download sizes (raw, gzip -9, brotli) of a module: wasm + glue. The core
// (tsm_decoder) is what a page loads; the full module only when a file needs it.
const sizes = (wasm, glue) => Object.fromEntries(Object.entries({ raw: (f) => fs.statSync(f).size, gzip: gz, brotli: br })
  .map(([k, f]) => [k, f(wasm) + f(glue)]));
const core = sizes(path.join(dist, 'tsm_decoder.wasm'), path.join(dist, 'tsm_decoder.js'));
const fullWasm = path.join(dist, 'tsm_decoder_full.wasm');
const full = fs.existsSync(fullWasm) ? sizes(fullWasm, path.join(dist, 'tsm_decoder_full.js')) : null;
const dracoSizes = sizes(path.join(dracoDir, 'draco_decoder.wasm'), path.join(dracoDir, 'draco_decoder_nodejs.js'));
const wasmGz = gz(path.join(dist, 'tsm_decoder.wasm')), glueGz = gz(path.join(dist, 'tsm_decoder.js'));
const dracoGz = dracoSizes.gzip;
const res = { wasmGz, glueGz, dracoGz, core, full, draco: dracoSizes, rows };
if (process.argv.includes('--json')) { console.log(JSON.stringify(res)); process.exit(0); }
console.log(`node ${process.version}; tsm wasm gzip ${wasmGz}, glue gzip ${glueGz}, total ${wasmGz + glueGz} = ` +
  `${((wasmGz + glueGz) / dracoGz).toFixed(3)}x draco3d's ${dracoGz} (wasm + glue); median and fastest of ${REPS}`);
const line = (name, s) => `| ${name} | ${s.raw} | ${s.gzip} | ${s.brotli} | ${(s.gzip / dracoGz).toFixed(3)} |`;
console.log('| wasm + glue | raw | gzip | brotli | gzip / draco3d |\n|---|---:|---:|---:|---:|');
console.log(line('tsm core (tsm_decoder)', core));
if (full) console.log(line('tsm full (tsm_decoder_full, on demand)', full));
console.log(line('draco3d decoder', dracoSizes) + '\n');
console.log('| mesh | streams | tsm ms | draco3d ms | tsm/draco | tsm fastest ms | draco3d fastest ms | tsm/draco (fastest) |');
console.log('|---|---:|---:|---:|---:|---:|---:|---:|');
const f = (x) => x.toFixed(3);
for (const r of rows)
  console.log(`| ${r.name} | ${r.streams} | ${f(r.tsmMs)} | ${f(r.dracoMs)} | ${(r.tsmMs / r.dracoMs).toFixed(2)} | ` +
    `${f(r.tsmMinMs)} | ${f(r.dracoMinMs)} | ${(r.tsmMinMs / r.dracoMinMs).toFixed(2)} |`);
