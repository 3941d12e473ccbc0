// The glTF bench: the corpus's glTF assets compressed three ways, then their
// geometry decoded in headless Chromium by each codec's own decoder
// (web/demo/gltf-bench.html): tsm (`tsm encode`, TSM_mesh_compression,
// defaults: positions 14 bits, normals 10, texture coordinates 12, colours
// 10; at the default level 6 and at level 0, the fastest to decode), Draco (KHR_draco_mesh_compression, written by glTF-Transform with
// draco3d's encoder, edgebreaker, the same quantization bits) and meshopt
// (gltfpack -cc -vp 14 -vt 12 -vn 10 -vc 10, EXT_meshopt_compression).
// Writes build/web/gltf-bench.md and .json.
//   node web/test/gltf-bench.mjs [--reps N]
//   node web/test/gltf-bench.mjs --index FILE [--reps N]
// With --index (how `tsm bench --browser` calls it), the files are given:
// FILE is [{"name": ..., "files": {"tsm": path, "draco": path, "meshopt":
// path}}, ...] (any of the three), nothing is compressed here, and the
// result is printed as JSON on stdout, nothing else.
// Env: TSM (the native CLI), CORPUS (../shared/corpus).
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { NodeIO } from '@gltf-transform/core';
import { ALL_EXTENSIONS, KHRDracoMeshCompression } from '@gltf-transform/extensions';
import draco3d from 'draco3d';
import { runBenchPage } from './chromium.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
const web = path.resolve(here, '..');
const root = path.resolve(web, '..');
const TSM = process.env.TSM || path.join(root, 'build/release/cli/tsm');
const CORPUS = path.resolve(process.env.CORPUS || path.join(root, '../shared/corpus'));
const out = path.join(root, 'build/web/data/gltf-bench');
const arg = (name, d) => { const i = process.argv.indexOf(name); return i > 0 ? process.argv[i + 1] : d; };
fs.mkdirSync(out, { recursive: true });

// The corpus's assets compressed by tsm (levels 6 and 0), glTF-Transform +
// draco3d and gltfpack, into `out`, listed in `index`.
async function prepare() {
  const io = new NodeIO().registerExtensions(ALL_EXTENSIONS).registerDependencies({
    'draco3d.decoder': await draco3d.createDecoderModule(), 'draco3d.encoder': await draco3d.createEncoderModule() });

  for (const rel of ['assets/Fox/Fox.gltf', 'assets/CesiumMilkTruck/CesiumMilkTruck.gltf', 'assets/2CylinderEngine.glb']) {
    const src = path.join(CORPUS, rel);
    if (!fs.existsSync(src)) { console.log(`note: ${src} missing, left out`); continue; }
    const name = path.basename(rel).replace(/\.gl(b|tf)$/, '');
    const files = { tsm: `${name}.tsm.glb`, tsm_l0: `${name}.tsm-l0.glb`, draco: `${name}.draco.glb`, meshopt: `${name}.meshopt.glb` };
    const dest = (k) => path.join(out, files[k]);
    execFileSync(TSM, ['encode', src, '-o', dest('tsm'), '-f', '--quiet']);
    execFileSync(TSM, ['encode', src, '-o', dest('tsm_l0'), '-f', '--quiet', '-l', '0']);
    const doc = await io.read(src);
    // glTF-Transform's Draco writer skips primitives without indices (Fox's): give them 0, 1, 2, ...
    for (const mesh of doc.getRoot().listMeshes()) {
      for (const prim of mesh.listPrimitives()) {
        if (prim.getIndices()) continue;
        const count = prim.getAttribute('POSITION').getCount();
        prim.setIndices(doc.createAccessor().setType('SCALAR').setBuffer(doc.getRoot().listBuffers()[0])
          .setArray(count < 65536 ? Uint16Array.from({ length: count }, (_, i) => i) : Uint32Array.from({ length: count }, (_, i) => i)));
      }
    }
    doc.createExtension(KHRDracoMeshCompression).setRequired(true).setEncoderOptions({
      method: KHRDracoMeshCompression.EncoderMethod.EDGEBREAKER, encodeSpeed: 0, decodeSpeed: 5,
      quantizationBits: { POSITION: 14, NORMAL: 10, TEX_COORD: 12, COLOR: 10, GENERIC: 16 } });
    await io.write(dest('draco'), doc);
    execFileSync(process.execPath, [path.join(web, 'node_modules/gltfpack/cli.js'), '-i', src, '-o', dest('meshopt'),
      '-cc', '-vp', '14', '-vt', '12', '-vn', '10', '-vc', '10'], { stdio: ['ignore', 'ignore', 'pipe'] });
    index.push({ name, files: Object.fromEntries(Object.entries(files).map(([k, f]) => [k, `/data/gltf-bench/${f}`])) });
    console.log(`gltf-bench: ${name}: ` + Object.keys(files).map((k) => `${k} ${fs.statSync(dest(k)).size} bytes`).join(', '));
  }
}

const given = arg('--index', null);
const index = [];
// The page loads the wasm decoder from build/web: without it, it would wait for its timeout.
for (const f of ['tsm_decoder.wasm', 'tsm_decoder.js', 'tsm.js']) {
  if (!fs.existsSync(path.join(root, 'build/web', f))) {
    console.error(`gltf-bench: error: build/web/${f} is missing: build the web decoder first (bash web/build.sh)`);
    process.exit(1);
  }
}
if (given) {
  // Copied under web/'s server root, where the page fetches them.
  for (const [i, asset] of JSON.parse(fs.readFileSync(given, 'utf8')).entries()) {
    const files = {};
    for (const [codec, file] of Object.entries(asset.files)) {
      const name = `given-${i}-${codec}.glb`;
      fs.copyFileSync(file, path.join(out, name));
      files[codec] = `/data/gltf-bench/${name}`;
    }
    index.push({ name: asset.name, files });
  }
} else {
  await prepare();
}
fs.writeFileSync(path.join(out, 'index.json'), JSON.stringify(index, null, 1));

const r = await runBenchPage(`gltf-bench.html?reps=${arg('--reps', '15')}`, given ? 180000 : 600000);
if (r.state !== 'done') { console.error('gltf bench failed:', r.error); process.exit(1); }
if (given) {
  console.log(JSON.stringify(r));
  process.exit(0);
}
const n = (x) => x.toLocaleString('en-US');
const lines = [`Chromium ${r.chromium}, headless, this machine; geometry of each file decoded into typed arrays, ` +
  `median of ${r.reps} samples (each the mean of enough decodes to take about 20 ms) after 0.5 s of warm-up decodes each, the decoders taking turns.`, '',
  '| asset | tsm ms | tsm -l 0 ms | Draco ms | meshopt ms | tsm .glb bytes | tsm -l 0 .glb bytes | Draco .glb bytes | meshopt .glb bytes | ' +
  'tsm geometry bytes | tsm -l 0 geometry bytes | Draco geometry bytes | meshopt geometry bytes |',
  '|---|---|---|---|---|---|---|---|---|---|---|---|---|'];
for (const x of r.rows) {
  const c = ['tsm', 'tsm_l0', 'draco', 'meshopt'];
  lines.push(`| ${x.name} | ${c.map((k) => (x[k] ? x[k].ms.toFixed(2) : '-')).join(' | ')} | ` +
    `${c.map((k) => (x[k] ? n(x[k].fileBytes) : '-')).join(' | ')} | ${c.map((k) => (x[k] ? n(x[k].geometryBytes) : '-')).join(' | ')} |`);
}
const md = lines.join('\n');
console.log(md);
fs.writeFileSync(path.join(root, 'build/web/gltf-bench.md'), md + '\n');
fs.writeFileSync(path.join(root, 'build/web/gltf-bench.json'), JSON.stringify(r, null, 1) + '\n');
