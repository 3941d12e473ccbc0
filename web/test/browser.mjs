// The browser test: serves web/demo on localhost, opens it in headless
// Chromium (Debian's /usr/bin/chromium, driven by playwright-core), streams
// each mesh through the WebAssembly decoder, on the page's thread and in a Web
// Worker, and checks the vertex, face and corner counts and the FNV-1a
// checksums of the index and position arrays against the native decoder's
// (build/web/data/NAME.ref.json, from web/prepare-data.sh). Screenshots go
// to build/web/screenshots/. Then: damaged input is refused, the API by hand,
// and attributes: corpus files with normals, texture coordinates and colours
// and a glTF file written here (face attribute, metadata), encoded by the
// native `tsm encode` (some in several segments), decode in
// the browser, whole, streamed and in a worker, with the same attribute
// values, corner indices and metadata (FNV-1a of their bytes) as the native decoder
// (web/test/attr-ref.c, a C client of tsm.h built here against the native
// library: $TSM/../../libcodec/libtsm.a and libtsm_decoder.a).
//   node web/test/browser.mjs [NAME ...]
// Env: TSM (the native CLI, default build/release/cli/tsm), CORPUS (../shared/corpus).
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { startServer } from '../serve.mjs';
import { launch } from './chromium.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
const root = path.resolve(here, '../..');
const dataDir = path.join(root, 'build/web/data');
const shots = path.join(root, 'build/web/screenshots');
fs.mkdirSync(shots, { recursive: true });

const index = JSON.parse(fs.readFileSync(path.join(dataDir, 'index.json'), 'utf8'));
const only = process.argv.slice(2).filter((a) => !a.startsWith('-'));
const info = JSON.parse(fs.readFileSync(path.join(process.env.TSM_WEB_DIST || path.join(root, 'build/web'), 'build-info.json'), 'utf8'));
let meshes = index.filter((m) => (only.length ? only.includes(m.name) : true));
if (info.zstd !== 'debian') {
  // built with web/zstd_stub.c: zstd-coded sections are refused by design
  console.log('note: this build has no zstd decompressor; the *_zstd files are left out');
  meshes = meshes.filter((m) => !m.name.endsWith('_zstd'));
}
// Files of several segments are also loaded slowly from the server, and must
// then show up in pieces, the first well before the last. The rate makes the
// download last about two seconds (at most 4 MB/s), so that on a loaded
// machine the page still sees the bytes arrive in several pieces.
const throttleFor = (m) => {
  const bytes = fs.statSync(path.join(dataDir, `${m.name}.tsm`)).size;
  return Math.max(16384, Math.min(4000000, Math.round(bytes / 2)));
};

// ---- attribute files and their native reference --------------------------------
// name, corpus file (or a function making the file), `tsm encode` options:
// corner normals and UVs with seams (OBJ), vertex normals and corner UVs
// (PLY), corner normals in 7 segments, u8 vertex colours in 5 segments, and a
// glTF file of two primitives (vertex normals and UVs, the primitive of each
// face as a face attribute, the document as metadata).
const ATTRIBUTE_FILES = [
  ['att_cube_obj', 'edge/cube_att.obj', []],
  ['att_cube_ply', 'edge/cube_att.ply', []],
  ['att_sphere_seg', 'edge/sphere.obj', ['--segment-faces', '32']],
  ['att_color_seg', 'edge/test_pos_color.ply', ['--segment-faces', '48']],
  ['att_gltf', twoPrimitiveGltf, []],
];
// Two triangles sharing an edge, one primitive each, with normals and UVs.
function twoPrimitiveGltf() {
  const f32 = (a) => Buffer.from(new Float32Array(a).buffer);
  const bin = Buffer.concat([f32([0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1]), f32([0, 0, 1, 0, 0, 1, 0.6, 0, 0.8, 0, 0.6, 0.8]),
    f32([0, 0, 1, 0, 0, 1, 0.5, 0.5]), Buffer.from(new Uint16Array([0, 1, 2, 0, 2, 3]).buffer)]);
  const prim = (indices, material) => ({ attributes: { POSITION: 0, NORMAL: 1, TEXCOORD_0: 2 }, indices, material });
  const doc = {
    asset: { version: '2.0' }, scene: 0, scenes: [{ nodes: [0] }], nodes: [{ mesh: 0, name: 'two' }],
    meshes: [{ primitives: [prim(3, 0), prim(4, 1)] }], materials: [{ name: 'red' }, { name: 'blue' }],
    buffers: [{ byteLength: bin.length, uri: `data:application/octet-stream;base64,${bin.toString('base64')}` }],
    bufferViews: [{ buffer: 0, byteOffset: 0, byteLength: 48 }, { buffer: 0, byteOffset: 48, byteLength: 48 },
      { buffer: 0, byteOffset: 96, byteLength: 32 }, { buffer: 0, byteOffset: 128, byteLength: 12 }],
    accessors: [{ bufferView: 0, componentType: 5126, count: 4, type: 'VEC3', min: [0, 0, 0], max: [1, 1, 1] },
      { bufferView: 1, componentType: 5126, count: 4, type: 'VEC3' },
      { bufferView: 2, componentType: 5126, count: 4, type: 'VEC2' },
      { bufferView: 3, byteOffset: 0, componentType: 5123, count: 3, type: 'SCALAR' },
      { bufferView: 3, byteOffset: 6, componentType: 5123, count: 3, type: 'SCALAR' }],
  };
  const file = path.join(dataDir, 'att_gltf.gltf');
  fs.writeFileSync(file, JSON.stringify(doc));
  return file;
}
// A progressive file: the whole shape first (the base, then one level per
// batch, each with more faces and no larger error), the last level the native
// decoder's mesh (checked above), and, loaded slowly, the base before the
// last byte (the server sends chunks of 16 KiB or more).
function levelProblems(m, result, throttle) {
  const out = [];
  const levels = result.levels || [];
  if (levels.length !== m.batches + 1) out.push(`levels: ${levels.length}, expected ${m.batches + 1} (the base and each batch)`);
  levels.forEach((l, k) => {
    if (l.batches !== k) out.push(`level ${k}: ${l.batches} batches`);
    if (k && !(l.faces > levels[k - 1].faces && l.vertices > levels[k - 1].vertices))
      out.push(`level ${k}: ${l.faces} faces after ${levels[k - 1].faces}`);
    // The encoder's error per level (a maximum distance): finer levels need
    // not lower it at every batch, but none is coarser than the base.
    if (k && levels[0].error >= 0 && !(l.error >= 0 && l.error <= levels[0].error))
      out.push(`level ${k}: error ${l.error}, the base's ${levels[0].error}`);
  });
  if (levels.length && levels[levels.length - 1].error !== 0) out.push(`last level's error ${levels[levels.length - 1].error}`);
  if (throttle && levels.length && !(levels[0].bytesIn < m.tsmBytes)) out.push(`the base came at byte ${levels[0].bytesIn} of ${m.tsmBytes}`);
  return out;
}

const newer = (a, b) => !fs.existsSync(b) || fs.statSync(a).mtimeMs > fs.statSync(b).mtimeMs;
// Encodes the files natively and prints the native decoder's figures; null
// (and a reason) when the native tool or library is missing.
function attributeReferences() {
  const tsm = process.env.TSM || path.join(root, 'build/release/cli/tsm');
  const lib = path.resolve(path.dirname(tsm), '../libcodec/libtsm.a');
  const decoderLib = path.resolve(path.dirname(tsm), '../libcodec/libtsm_decoder.a');
  const corpus = process.env.CORPUS || path.resolve(root, '../shared/corpus');
  if (!fs.existsSync(tsm) || !fs.existsSync(lib)) return { reason: `no native ${tsm} or ${lib}` };
  const helper = path.join(root, 'build/web/attr-ref');
  const src = path.join(here, 'attr-ref.c');
  if (newer(src, helper) || newer(lib, helper)) {
    execFileSync('cc', ['-std=c99', '-pedantic', '-Wall', '-Wextra', '-Werror', `-I${path.join(root, 'libcodec/include')}`,
      src, lib, decoderLib, '-lstdc++', '-lzstd', '-lxxhash', '-lm', '-lpthread', '-o', helper], { stdio: 'inherit' });
  }
  const out = [];
  for (const [name, rel, args] of ATTRIBUTE_FILES) {
    const file = typeof rel === 'function' ? rel() : path.join(corpus, rel);
    if (!fs.existsSync(file)) { console.log(`note: ${file} missing, ${name} left out`); continue; }
    const tsmFile = path.join(dataDir, `${name}.tsm`);
    execFileSync(tsm, ['encode', file, '-o', tsmFile, '-f', '--quiet', ...args]);
    out.push({ name, ref: JSON.parse(execFileSync(helper, [tsmFile], { encoding: 'utf8' })) });
  }
  return { files: out };
}

const server = await startServer();
const base = `http://localhost:${server.address().port}`;
const browser = await launch();
let passed = 0, failed = 0;
const problems = [];
try {
  const page = await browser.newPage({ viewport: { width: 960, height: 720 } });
  page.on('pageerror', (e) => problems.push(`page error: ${e.message}`));
  page.on('console', (m) => { if (m.type() === 'error') problems.push(`console: ${m.text()}`); });
  for (const m of meshes) {
    const runs = [[false, 0], [true, 0]];
    if (m.segments > 1 || m.batches > 0) runs.push([false, throttleFor(m)], [true, throttleFor(m)]);
    for (const [worker, throttle] of runs) {
      const label = `${m.name}${worker ? ' (worker)' : ''}${throttle ? ` (${(throttle / 1e6).toFixed(2)} MB/s)` : ''}`;
      const before = problems.length;
      await page.goto(`${base}/?mesh=${m.name}${worker ? '&worker=1' : ''}${throttle ? `&throttle=${throttle}` : ''}`);
      let result = null, error = null;
      try {
        await page.waitForFunction(() => ['done', 'error'].includes(window.tsmDemo && window.tsmDemo.state), null,
          { timeout: 120000 });
        ({ result, error } = await page.evaluate(() => ({ result: window.tsmDemo.result, error: window.tsmDemo.error })));
      } catch (e) {
        error = `timed out: ${e.message.split('\n')[0]}`;
      }
      const want = m.ref;
      const diffs = [];
      if (error) diffs.push(error);
      else {
        for (const k of ['vertexCount', 'faceCount', 'cornerCount', 'indexHash', 'positionHash', 'faceOffsetHash'])
          if (want[k] !== result[k]) diffs.push(`${k}: browser ${result[k]}, native ${want[k]}`);
        if (result.segmentCount !== m.segments) diffs.push(`segments: browser ${result.segmentCount}, native ${m.segments}`);
        if (throttle && !(result.pieces >= 2 && result.firstMs < result.totalMs / 2))
          diffs.push(`not progressive: ${result.pieces} piece(s), first triangles at ${result.firstMs} ms of ${result.totalMs} ms`);
        if (m.batches > 0) diffs.push(...levelProblems(m, result, throttle));
      }
      diffs.push(...problems.slice(before));
      const file = path.join(shots, `${m.name}${worker ? '-worker' : ''}${throttle ? '-throttled' : ''}.png`);
      await page.screenshot({ path: file });
      if (diffs.length) {
        failed++;
        console.log(`FAIL ${label}: ${diffs.join('; ')}`);
      } else {
        passed++;
        console.log(`ok   ${label}: ${result.vertexCount} vertices, ${result.faceCount} faces, indices ${result.indexHash}, ` +
          `${result.segmentCount} segment(s) in ${result.pieces} piece(s), decode ${result.decodeMs.toFixed(1)} ms, ` +
          `first triangles ${result.firstMs.toFixed(1)} ms, all ${result.totalMs.toFixed(1)} ms` +
          `${m.batches ? `, ${result.levels.length} levels (base ${result.levels[0].faces} faces at byte ${result.levels[0].bytesIn})` : ''}` +
          `  [${path.relative(root, file)}]`);
      }
    }
  }
  // The decoder refuses a damaged file with an error, not a crash.
  {
    const r = await page.evaluate(async () => {
      const { loadTsm } = await import('/dist/tsm.js');
      const tsm = await loadTsm();
      const bytes = new Uint8Array(await (await fetch('/data/dragon_res4.tsm')).arrayBuffer());
      const out = {};
      const bad = bytes.slice(); bad[bad.length >> 1] ^= 0x55;
      try { tsm.decode(bad); out.flipped = 'decoded'; } catch (e) { out.flipped = `${e.name}:${e.codeName}`; }
      try { tsm.decode(bytes.subarray(0, bytes.length - 7)); out.truncated = 'decoded'; } catch (e) { out.truncated = `${e.name}:${e.codeName}`; }
      const s = tsm.createStream();
      try { s.feed(bytes.subarray(0, 100)); s.finish(); out.streamTruncated = 'decoded'; } catch (e) { out.streamTruncated = `${e.name}:${e.codeName}`; }
      s.free();
      try { tsm.decode(bytes, { maxVertices: 100 }); out.limit = 'decoded'; } catch (e) { out.limit = `${e.name}:${e.codeName}`; }
      out.after = tsm.decode(bytes).faceCount; // the module still works
      // A progressive file needs the full module: decode() says so until loadFull().
      const prog = new Uint8Array(await (await fetch('/data/bunny_prog.tsm')).arrayBuffer());
      try { tsm.decode(prog); out.needsFull = 'decoded'; } catch (e) { out.needsFull = e.needsFull ? 'needsFull' : `${e.name}:${e.codeName}`; }
      await tsm.loadFull();
      out.fullAfter = tsm.decode(prog).faceCount;
      return out;
    });
    const ok = r.flipped === 'TsmError:corrupt_data' && r.truncated.startsWith('TsmError:') &&
      r.streamTruncated.startsWith('TsmError:') && r.limit === 'TsmError:limit_exceeded' && r.after > 0 &&
      r.needsFull === 'needsFull' && r.fullAfter > 0;
    if (ok) { passed++; console.log(`ok   damaged input refused: ${JSON.stringify(r)}`); }
    else { failed++; console.log(`FAIL damaged input: ${JSON.stringify(r)}`); }
  }
  // The API by hand: odd chunkings, a worker reused across files and left early.
  {
    const want = Object.fromEntries(index.map((m) => [m.name, m.ref]));
    const r = await page.evaluate(async () => {
      const { loadTsm, decodeStreamInWorker, createTsmWorker } = await import('/dist/tsm.js');
      const { fnv1a, hex } = await import('/hash.js');
      const tsm = await loadTsm();
      const get = async (n) => new Uint8Array(await (await fetch(`/data/${n}.tsm`)).arrayBuffer());
      const sum = async (segments) => {
        let h = 0x811c9dc5, v = 0, f = 0, pieces = 0;
        for await (const s of segments) { h = fnv1a(s.indices, h); v += s.vertexCount; f += s.faceCount; pieces++; }
        return { vertexCount: v, faceCount: f, indexHash: hex(h), pieces };
      };
      function* sliced(bytes, n) { for (let i = 0; i < bytes.length; i += n) yield bytes.subarray(i, i + n); }
      const out = {};
      const seg = await get('bunny_seg4k');
      out.bytewise = await sum(tsm.decodeStream(sliced(seg, 1)));
      out.odd = await sum(tsm.decodeStream(sliced(seg, 4093)));
      const worker = createTsmWorker();
      // leave a stream early, then reuse the worker for two more files
      for await (const s of decodeStreamInWorker(sliced(seg, 2048), { worker })) { out.leftAfter = s.segmentsDone; break; }
      out.reused1 = await sum(decodeStreamInWorker(sliced(await get('dragon_res4'), 1000), { worker }));
      out.reused2 = await sum(decodeStreamInWorker(seg, { worker }));
      out.sourceIntact = seg.length > 0 && seg[0] === 0x54; // not transferred away
      worker.terminate();
      return out;
    });
    const same = (a, b) => a.vertexCount === b.vertexCount && a.faceCount === b.faceCount && a.indexHash === b.indexHash;
    const ok = same(r.bytewise, want.bunny_seg4k) && r.bytewise.pieces > 16 && same(r.odd, want.bunny_seg4k) &&
      r.leftAfter >= 1 && same(r.reused1, want.dragon_res4) && same(r.reused2, want.bunny_seg4k) && r.sourceIntact;
    if (ok) { passed++; console.log(`ok   API: byte-by-byte feed (${r.bytewise.pieces} pieces), odd chunks, reused worker left early`); }
    else { failed++; console.log(`FAIL API: ${JSON.stringify(r)}`); }
  }
  // Progressive files by hand: streamed in odd chunks, on this thread and in
  // a worker, the last level's arrays equal element by element those of a
  // whole-file decode (whose checksums are the native decoder's), one level per
  // batch.
  for (const m of meshes.filter((x) => x.batches > 0)) {
    const r = await page.evaluate(async (name) => {
      const { loadTsm, decodeStreamInWorker } = await import('/dist/tsm.js');
      const { fnv1a, hex } = await import('/hash.js');
      const tsm = await loadTsm();
      const bytes = new Uint8Array(await (await fetch(`/data/${name}.tsm`)).arrayBuffer());
      const whole = await tsm.decodeAsync(bytes);
      function* sliced(b, k) { for (let i = 0; i < b.length; i += k) yield b.subarray(i, i + k); }
      const equal = (a, b) => a.length === b.length && a.every((x, i) => Object.is(x, b[i]));
      const run = async (pieces) => {
        let last = null, levels = 0, faces = [];
        for await (const p of pieces) {
          if (!p.level) continue;
          if (!last || p.batchesDone !== last.batchesDone) { levels++; faces.push(p.faceCount); }
          last = p;
        }
        return { levels, grows: faces.every((f, i) => i === 0 || f > faces[i - 1]),
          same: !!last && equal(last.positions, whole.positions) && equal(last.indices, whole.indices) };
      };
      return {
        indexHash: hex(fnv1a(whole.indices)), positionHash: hex(fnv1a(whole.positions)),
        odd: await run(tsm.decodeStream(sliced(bytes, 997))),
        once: await run(tsm.decodeStream(bytes)),
        worker: await run(decodeStreamInWorker(sliced(bytes, 4096))),
      };
    }, m.name);
    const want = m.batches + 1;
    const runs = [r.odd, r.once, r.worker];
    const ok = r.indexHash === m.ref.indexHash && r.positionHash === m.ref.positionHash &&
      runs.every((x) => x.levels === want && x.grows && x.same);
    if (ok) { passed++; console.log(`ok   progressive ${m.name}: ${want} levels streamed (997-byte chunks, whole, worker), last = tsm decode's arrays`); }
    else { failed++; console.log(`FAIL progressive ${m.name}: ${JSON.stringify(r)} (want ${want} levels, native ${m.ref.indexHash}/${m.ref.positionHash})`); }
  }
  // Attributes: the browser's values and indices are the native decoder's.
  {
    const refs = attributeReferences();
    if (!refs.files) { failed++; console.log(`FAIL attributes: ${refs.reason}`); }
    for (const { name, ref } of refs.files || []) {
      const r = await page.evaluate(async (n) => {
        const { loadTsm, decodeStreamInWorker } = await import('/dist/tsm.js');
        const { fnv1a, hex } = await import('/hash.js');
        const tsm = await loadTsm();
        const bytes = new Uint8Array(await (await fetch(`/data/${n}.tsm`)).arrayBuffer());
        // Appends the pieces' attribute lists as a client would, checking
        // that each piece continues the lists so far; checksums of the whole.
        const sum = async (pieces) => {
          let acc = null, pieces_ = 0, vertexCount = 0, faceCount = 0, cornerCount = 0, metadata = [];
          const errors = [];
          for await (const p of pieces) {
            pieces_++;
            if (p.metadata) metadata = p.metadata.map((e) => ({ key: e.key, valueHash: hex(fnv1a(e.value)) }));
            if (!acc && p.attributes.length) {
              acc = p.attributes.map((a) => ({ name: a.name, kind: a.kind, domain: a.domain, type: a.type,
                components: a.components, valueCount: 0, vh: 0x811c9dc5, ih: a.indices ? 0x811c9dc5 : null }));
            }
            p.attributes.forEach((a, i) => {
              const s = acc[i];
              const want = a.domain === 'vertex' ? [p.vertexStart, p.vertexCount]
                : a.domain === 'face' ? [p.faceStart, p.faceCount] : [s.valueCount, a.valueCount];
              if (a.valueStart !== s.valueCount || a.valueStart !== want[0] || a.valueCount !== want[1] ||
                  a.values.length !== a.valueCount * a.components || !(a.values instanceof Float32Array))
                errors.push(`piece ${pieces_} ${a.name}: values ${a.valueStart}+${a.valueCount}, expected ${want}`);
              if (a.domain === 'corner') {
                if (!(a.indices instanceof Uint32Array) || a.indices.length !== p.indices.length)
                  errors.push(`piece ${pieces_} ${a.name}: ${a.indices && a.indices.length} indices for ${p.indices.length} corners`);
                else if (a.indices.some((x) => x >= a.valueStart + a.valueCount))
                  errors.push(`piece ${pieces_} ${a.name}: an index names a value not yet given`);
              } else if (a.indices !== null) errors.push(`piece ${pieces_} ${a.name}: indices outside the corner domain`);
              s.vh = fnv1a(a.values, s.vh);
              if (a.indices) s.ih = fnv1a(a.indices, s.ih);
              s.valueCount += a.valueCount;
            });
            vertexCount += p.vertexCount; faceCount += p.faceCount; cornerCount += p.indices.length;
          }
          const attributes = (acc || []).map(({ vh, ih, ...d }) => ({ ...d, valuesHash: hex(vh),
            indicesHash: ih === null ? null : hex(ih) }));
          return { vertexCount, faceCount, cornerCount, attributes, metadata, pieces: pieces_, errors };
        };
        function* sliced(b, k) { for (let i = 0; i < b.length; i += k) yield b.subarray(i, i + k); }
        return {
          whole: await sum([await tsm.decodeAsync(bytes)]),
          streamed: await sum(tsm.decodeStream(sliced(bytes, 61))),
          worker: await sum(decodeStreamInWorker(sliced(bytes, 200))),
        };
      }, name);
      const diffs = [];
      for (const [how, got] of Object.entries(r)) {
        const { pieces, errors, ...figures } = got;
        diffs.push(...errors.map((e) => `${how}: ${e}`));
        if (JSON.stringify(figures) !== JSON.stringify(ref))
          diffs.push(`${how}: browser ${JSON.stringify(figures)}, native ${JSON.stringify(ref)}`);
      }
      const segmented = ATTRIBUTE_FILES.find((f) => f[0] === name)[2].length > 0;
      if (segmented && !(r.streamed.pieces > 2 && r.worker.pieces > 1))
        diffs.push(`not in pieces: ${r.streamed.pieces} streamed, ${r.worker.pieces} in the worker`);
      if (!ref.attributes.length) diffs.push('the native decoder gives no attributes');
      if (name === 'att_gltf' && !(ref.metadata.length && ref.attributes.some((a) => a.domain === 'face')))
        diffs.push('the glTF file has no metadata or no face attribute');
      if (diffs.length) { failed++; console.log(`FAIL attributes ${name}: ${diffs.join('; ')}`); }
      else {
        passed++;
        console.log(`ok   attributes ${name}: ${ref.attributes.map((a) => `${a.name} (${a.domain}, ${a.valueCount} values, ` +
          `${a.valuesHash}${a.indicesHash ? `/${a.indicesHash}` : ''})`).join(', ')}` +
          `${ref.metadata.length ? `, metadata ${ref.metadata.map((e) => `${e.key} (${e.valueHash})`).join(', ')}` : ''}; whole, streamed in ` +
          `${r.streamed.pieces} pieces, worker in ${r.worker.pieces}`);
      }
    }
  }
} finally {
  await browser.close();
  server.close();
}
console.log(`web: ${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
