// The browser test: serves web/demo on localhost, opens it in headless
// Chromium (Debian's /usr/bin/chromium, driven by playwright-core), streams
// each mesh through the WebAssembly decoder, on the page's thread and in a Web
// Worker, and checks the vertex, face and corner counts and the FNV-1a
// checksums of the index and position arrays against the native decoder's
// (build/web/data/NAME.ref.json, from web/prepare-data.sh). Screenshots go
// to build/web/screenshots/.
//   node web/test/browser.mjs [NAME ...]
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
    if (m.segments > 1) runs.push([false, throttleFor(m)], [true, throttleFor(m)]);
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
          `first triangles ${result.firstMs.toFixed(1)} ms, all ${result.totalMs.toFixed(1)} ms  [${path.relative(root, file)}]`);
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
      return out;
    });
    const ok = r.flipped === 'TsmError:corrupt_data' && r.truncated.startsWith('TsmError:') &&
      r.streamTruncated.startsWith('TsmError:') && r.limit === 'TsmError:limit_exceeded' && r.after > 0;
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
} finally {
  await browser.close();
  server.close();
}
console.log(`web: ${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
