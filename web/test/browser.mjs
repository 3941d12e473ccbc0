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
const meshes = index.filter((m) => (only.length ? only.includes(m.name) : true));
// Files of several segments are also loaded slowly (4 MB/s from the server),
// and must then show up in pieces, the first well before the last.
const THROTTLE = 4000000;

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
    if (m.segments > 1) runs.push([false, THROTTLE], [true, THROTTLE]);
    for (const [worker, throttle] of runs) {
      const label = `${m.name}${worker ? ' (worker)' : ''}${throttle ? ` (${throttle / 1e6} MB/s)` : ''}`;
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
} finally {
  await browser.close();
  server.close();
}
console.log(`web: ${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
