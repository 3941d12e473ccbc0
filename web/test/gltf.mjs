// The glTF test: compressed glTF (TSM_mesh_compression) through three.js.
// Makes the assets in build/web/data/gltf/ with the native `tsm encode`: a
// generated sphere (normals, UVs, u8 colours) always, and the corpus's Fox,
// CesiumMilkTruck and 2CylinderEngine when present, and Draco- and
// meshopt-compressed inputs transcoded (the corpus's Draco engine, Fox through
// gltfpack -cc); .glb with the extension required and with --fallback (an
// uncompressed copy), and .gltf for two of them; `tsm decode` back to plain
// glTF. Every file tsm writes passes the Khronos glTF validator (npm
// gltf-validator) with no errors (none but those its input already has).
// Then in headless Chromium (web/demo/gltf.html) each compressed file is loaded by three.js's
// GLTFLoader with the tsm plugin, on the page's thread and in a worker, and
// compared with the original asset: meshes, vertex and index counts,
// attribute names, sizes and normalized flags, and the rendering with the
// same camera (mean absolute difference and share of pixels off by more than
// 32 levels, within MAX_MEAN_ABS / MAX_OVER32). A fallback file also loads
// without the plugin, and a damaged stream is refused with an error.
//   node web/test/gltf.mjs
// Env: TSM (the native CLI, default build/release/cli/tsm), CORPUS
// (../shared/corpus; in CI a missing corpus fails the test).
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import validator from 'gltf-validator';
import { startServer } from '../serve.mjs';
import { launch } from './chromium.mjs';
import { readGlb } from './glb.mjs';
import { sphereGlb } from './sphere-glb.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
const root = path.resolve(here, '../..');
const out = path.join(root, 'build/web/data/gltf');
const shots = path.join(root, 'build/web/screenshots');
const TSM = process.env.TSM || path.join(root, 'build/release/cli/tsm');
const CORPUS = path.resolve(process.env.CORPUS || path.join(root, '../shared/corpus'));
const inCI = !['', '0', 'false'].includes(String(process.env.CI || '').toLowerCase());
// The rendering of a compressed asset against the original's (0..255 levels; share of pixels).
const MAX_MEAN_ABS = 1.5;
const MAX_OVER32 = 0.01;
fs.rmSync(out, { recursive: true, force: true });
fs.mkdirSync(out, { recursive: true });
fs.mkdirSync(shots, { recursive: true });

let passed = 0, failed = 0;
const ok = (msg) => { passed++; console.log(`ok   ${msg}`); };
const fail = (msg) => { failed++; console.log(`FAIL ${msg}`); };

// ---- assets --------------------------------------------------------------------
const sphere = path.join(out, 'sphere.glb');
fs.writeFileSync(sphere, sphereGlb());
// name, original (a file; its URL on the test server)
const assets = [{ name: 'sphere', file: sphere, url: '/data/gltf/sphere.glb' }];
for (const rel of ['assets/Fox/Fox.gltf', 'assets/CesiumMilkTruck/CesiumMilkTruck.gltf', 'assets/2CylinderEngine.glb']) {
  const file = path.join(CORPUS, rel);
  if (fs.existsSync(file)) assets.push({ name: path.basename(rel).replace(/\.gl(b|tf)$/, ''), file, url: `/corpus/${rel}` });
  else if (inCI) fail(`corpus asset ${file} missing (CI)`);
  else console.log(`note: ${file} missing, left out`);
}
// Transcoding: Draco- and meshopt-compressed inputs (the corpus's Draco engine, Fox through gltfpack -cc),
// compared with the input as three.js loads it (its DRACOLoader, MeshoptDecoder). Their attributes may
// change type (KHR_mesh_quantization's integers come back as floats): names and sizes are compared.
const dracoEngine = path.join(CORPUS, 'assets/2CylinderEngine_Draco/2CylinderEngine.gltf');
if (fs.existsSync(dracoEngine)) {
  assets.push({ name: '2CylinderEngine_Draco', file: dracoEngine, url: '/corpus/assets/2CylinderEngine_Draco/2CylinderEngine.gltf', transcoded: true });
}
const fox = assets.find((a) => a.name === 'Fox');
if (fox) {
  const file = path.join(out, 'Fox_meshopt.glb');
  execFileSync(process.execPath, [path.join(here, '../node_modules/gltfpack/cli.js'), '-i', fox.file, '-o', file, '-cc'],
    { stdio: ['ignore', 'ignore', 'pipe'] });
  assets.push({ name: 'Fox_meshopt', file, url: '/data/gltf/Fox_meshopt.glb', transcoded: true });
}
const written = []; // every glTF file tsm wrote, for the validator
for (const a of assets) {
  a.variants = [];
  // .glb with and without --fallback; .gltf (JSON + .bin) for the generated sphere and the truck (textures by URI)
  const kinds = [['glb', false], ['glb', true]];
  if (a.name === 'sphere' || a.name === 'CesiumMilkTruck') kinds.push(['gltf', false]);
  for (const [format, fallback] of kinds) {
    const name = `${a.name}${fallback ? '.fallback' : ''}.tsm.${format}`;
    const file = path.join(out, name);
    try {
      execFileSync(TSM, ['encode', a.file, '-o', file, '-f', '--quiet', ...(fallback ? ['--fallback'] : [])],
        { stdio: ['ignore', 'ignore', 'pipe'] });
    } catch (e) {
      fail(`tsm encode ${a.file}${fallback ? ' --fallback' : ''}: ${String(e.stderr || e.message).trim()}`);
      continue;
    }
    let json;
    try { json = format === 'glb' ? readGlb(fs.readFileSync(file)).json : JSON.parse(fs.readFileSync(file, 'utf8')); }
    catch (e) { fail(`${name}: ${e.message}`); continue; }
    if (!(json.extensionsUsed || []).includes('TSM_mesh_compression')) { fail(`${name}: no TSM_mesh_compression in extensionsUsed`); continue; }
    const required = (json.extensionsRequired || []).includes('TSM_mesh_compression');
    if (required === fallback) fail(`${name}: the extension is ${required ? '' : 'not '}required`);
    written.push({ file, source: a.file });
    a.variants.push({ name, fallback, url: `/data/gltf/${name}`, bytes: fs.statSync(file).size });
  }
  // `tsm decode` back to plain glTF: also validated
  if (a.variants.length) {
    const plain = path.join(out, `${a.name}.plain.glb`);
    try {
      execFileSync(TSM, ['decode', path.join(out, a.variants[0].name), '-o', plain, '-f', '--quiet'], { stdio: ['ignore', 'ignore', 'pipe'] });
      written.push({ file: plain, source: a.file });
    } catch (e) { fail(`tsm decode ${a.variants[0].name}: ${String(e.stderr || e.message).trim()}`); }
  }
}
fs.writeFileSync(path.join(out, 'index.json'), JSON.stringify(assets.filter((a) => a.variants.length)
  .map((a) => ({ name: a.name, original: a.url, compressed: a.variants[0].url })), null, 1));

// ---- Khronos validator ---------------------------------------------------------
// No errors; an input that already has some (the corpus's Fox: byteStride on
// its skin and animation buffer views) may pass its own on, no others.
const validate = async (file) => {
  const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
    uri: path.basename(file), maxIssues: 10000,
    externalResourceFunction: (uri) => fs.promises.readFile(path.resolve(path.dirname(file), decodeURIComponent(uri))),
  });
  const errors = report.issues.messages.filter((m) => m.severity === 0);
  return { report, errors, codes: new Set(errors.map((m) => m.code)) };
};
const inputs = new Map();
for (const { file, source } of written) {
  if (!inputs.has(source)) inputs.set(source, await validate(source));
  const input = inputs.get(source);
  const { report, errors } = await validate(file);
  const own = errors.filter((m) => !input.codes.has(m.code));
  const { numWarnings, numInfos } = report.issues;
  const infos = [...new Set(report.issues.messages.filter((m) => m.severity > 0).map((m) => m.code))].join(', ') || 'none';
  if (own.length || errors.length > input.errors.length) {
    fail(`validator ${path.basename(file)}: ${errors.length} errors (the input ${path.basename(source)} has ${input.errors.length}): ` +
      (own.length ? own : errors).slice(0, 5).map((m) => `${m.code} ${m.pointer || ''} ${m.message}`).join('; '));
  } else {
    ok(`validator ${path.basename(file)}: ${errors.length ? `${errors.length} errors, all of kinds the input has ` +
      `(${path.basename(source)}: ${input.errors.length} errors, ${[...input.codes].join(', ')})` : 'no errors'} ` +
      `(${numWarnings} warnings, ${numInfos} infos: ${infos})`);
  }
}

// ---- three.js in Chromium ------------------------------------------------------
const server = await startServer();
const base = `http://localhost:${server.address().port}`;
const browser = await launch();
const problems = [];
async function view(page, query) {
  await page.goto(`${base}/gltf.html?${new URLSearchParams(query)}`);
  await page.waitForFunction(() => ['done', 'error'].includes(window.tsmGltf && window.tsmGltf.state), null, { timeout: 180000 });
  return page.evaluate(() => window.tsmGltf);
}
// what three.js made of an asset: per mesh, counts and attributes (name, itemSize, normalized)
// (vertices the triangles use: tsm keeps those only; triangles: tsm writes
// indices for a primitive that had none, 0 1 2 ...; normalized flags but
// skinWeight's: tsm writes float WEIGHTS_n as normalized u16)
const shape = (v, transcoded) => v.meshes.map((m) => ({ vertices: m.usedVertices, triangles: (m.indexCount ?? m.vertexCount) / 3, skinned: m.skinned,
  attributes: Object.entries(m.attributes).map(([k, a]) => `${k}:${a.itemSize}${a.normalized && !transcoded && k !== 'skinWeight' ? 'n' : ''}`)
    .sort().join(' ') }));
try {
  const page = await browser.newPage({ viewport: { width: 1000, height: 560 } });
  page.on('pageerror', (e) => problems.push(`page error: ${e.message}`));
  page.on('console', (m) => { if (m.type() === 'error') problems.push(`console: ${m.text()}`); });
  for (const a of assets) {
    for (const v of a.variants) {
      // the sphere also through the worker (threshold 0); the corpus assets with the default threshold
      for (const worker of v.fallback ? [null] : a.name === 'sphere' ? [null, 0] : [null]) {
        const label = `three.js ${v.name}${worker === 0 ? ' (worker)' : ''}`;
        const before = problems.length;
        const q = { a: v.url, b: a.url };
        if (worker !== null) q.worker = worker;
        const r = await view(page, q);
        await page.screenshot({ path: path.join(shots, `gltf-${v.name}${worker === 0 ? '-worker' : ''}.png`) });
        const diffs = [];
        if (r.state !== 'done') diffs.push(r.error);
        else {
          const [got, want] = r.views.map((x) => shape(x, a.transcoded));
          if (JSON.stringify(got) !== JSON.stringify(want))
            diffs.push(`meshes differ: tsm ${JSON.stringify(got)}, original ${JSON.stringify(want)}`);
          const unused = r.views[0].meshes.filter((m) => m.vertexCount !== m.usedVertices);
          if (unused.length) diffs.push(`vertices no triangle uses: ${unused.map((m) => `${m.name} ${m.vertexCount - m.usedVertices}`).join(', ')}`);
          if (!(r.diff.drawn > 0.05)) diffs.push(`the original covers ${(100 * r.diff.drawn).toFixed(1)}% of the picture: nothing to compare`);
          if (!(r.diff.meanAbs <= MAX_MEAN_ABS && r.diff.over32 <= MAX_OVER32))
            diffs.push(`rendering differs: mean ${r.diff.meanAbs.toFixed(3)} levels, ${(100 * r.diff.over32).toFixed(2)}% pixels off by > 32`);
        }
        diffs.push(...problems.slice(before));
        if (diffs.length) fail(`${label}: ${diffs.join('; ')}`);
        else {
          const m = r.views[0].meshes;
          const dropped = r.views[1].meshes.reduce((s, x) => s + x.vertexCount, 0) - m.reduce((s, x) => s + x.vertexCount, 0);
          ok(`${label}: ${m.length} mesh(es), ${m.reduce((s, x) => s + x.vertexCount, 0)} vertices` +
            `${dropped ? ` (the original's ${dropped} unused ones dropped)` : ''}, ` +
            `${m.reduce((s, x) => s + (x.indexCount ?? x.vertexCount), 0) / 3} triangles, attributes as the original's; rendering: mean ` +
            `${r.diff.meanAbs.toFixed(3)} levels, ${(100 * r.diff.over32).toFixed(3)}% of ${r.diff.pixels} pixels off by > 32 ` +
            `(the model covers ${(100 * r.diff.drawn).toFixed(0)}%); ` +
            `load ${r.views[0].loadMs.toFixed(0)} ms (original ${r.views[1].loadMs.toFixed(0)} ms)`);
        }
      }
    }
  }
  // A fallback file without the plugin: three.js reads the uncompressed copy.
  const fb = assets[0].variants.find((v) => v.fallback);
  if (fb) {
    const r = await view(page, { a: fb.url, b: assets[0].url, plain: 1 });
    if (r.state === 'done' && r.diff.meanAbs <= MAX_MEAN_ABS) ok(`${fb.name} without the plugin: mean ${r.diff.meanAbs.toFixed(3)} levels`);
    else fail(`${fb.name} without the plugin: ${r.error || JSON.stringify(r.diff)}`);
  }
  // Damaged streams are refused with an error (a rejected load), the page keeps working.
  if (assets[0].variants.length) {
    const r = await page.evaluate(async (url) => {
      const { GLTFLoader } = await import('three/addons/loaders/GLTFLoader.js');
      const { GLTFTsmExtension } = await import('/dist/gltf-tsm-extension.js');
      const bytes = new Uint8Array(await (await fetch(url)).arrayBuffer());
      const dv = new DataView(bytes.buffer);
      const jsonLength = dv.getUint32(12, true);
      const json = JSON.parse(new TextDecoder().decode(bytes.subarray(20, 20 + jsonLength)));
      const bv = json.bufferViews[json.meshes[0].primitives[0].extensions.TSM_mesh_compression.bufferView];
      const at = 20 + jsonLength + 8 + (bv.byteOffset || 0);
      const load = async (b, threshold) => {
        const loader = new GLTFLoader();
        loader.register((parser) => new GLTFTsmExtension(parser, { workerThreshold: threshold }));
        try { await loader.parseAsync(b.buffer, ''); return 'loaded'; } catch (e) { return `${e.name}: ${e.message}`; }
      };
      const res = {};
      const flipped = bytes.slice(); flipped[at + (bv.byteLength >> 1)] ^= 0x55;
      res.flipped = await load(flipped, Infinity);
      res.flippedWorker = await load(flipped, 0);
      const zeroed = bytes.slice(); zeroed.fill(0, at, at + bv.byteLength);
      res.zeroed = await load(zeroed, Infinity);
      // The JSON lying about the stream: an attribute number it does not have, a vertex count it does not decode to.
      const withJson = (edit) => {
        const j = structuredClone(json);
        edit(j);
        let text = new TextEncoder().encode(JSON.stringify(j));
        const padded = new Uint8Array((text.length + 3) & ~3).fill(0x20); padded.set(text); text = padded;
        const rest = bytes.subarray(20 + jsonLength);
        const b = new Uint8Array(20 + text.length + rest.length);
        const d = new DataView(b.buffer);
        b.set(bytes.subarray(0, 12)); d.setUint32(8, b.length, true);
        d.setUint32(12, text.length, true); d.setUint32(16, 0x4e4f534a, true);
        b.set(text, 20); b.set(rest, 20 + text.length);
        return b;
      };
      const prim = (j) => j.meshes[0].primitives[0];
      res.badAttribute = await load(withJson((j) => { prim(j).extensions.TSM_mesh_compression.attributes.NORMAL = 99; }), Infinity);
      res.badCount = await load(withJson((j) => { j.accessors[prim(j).attributes.POSITION].count += 1; }), Infinity);
      res.badView = await load(withJson((j) => { prim(j).extensions.TSM_mesh_compression.bufferView = 1e6; }), Infinity);
      // a second primitive naming the same accessors with another stream (a copy of the view under a new number)
      res.twoStreams = await load(withJson((j) => {
        const ext = prim(j).extensions.TSM_mesh_compression;
        j.bufferViews.push({ ...j.bufferViews[ext.bufferView] });
        const copy = structuredClone(prim(j));
        copy.extensions.TSM_mesh_compression.bufferView = j.bufferViews.length - 1;
        j.meshes[0].primitives.push(copy);
      }), Infinity);
      res.after = await load(bytes, Infinity);
      return res;
    }, assets[0].variants[0].url);
    const named = (x) => x.includes('TSM_mesh_compression');
    if (r.flipped.startsWith('TsmError') && r.flippedWorker.startsWith('TsmError') && r.zeroed.startsWith('TsmError') &&
        named(r.badAttribute) && named(r.badCount) && named(r.badView) && named(r.twoStreams) && r.after === 'loaded')
      ok(`damaged streams and lying JSON refused: ${JSON.stringify(r)}`);
    else fail(`damaged streams: ${JSON.stringify(r)}`);
  }
} finally {
  await browser.close();
  server.close();
}
console.log(`gltf: ${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
