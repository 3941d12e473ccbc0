// Runs web/demo/bench.html in headless Chromium and prints (and writes to
// build/web/bench.md and bench.json) decode times of tsm beside draco3d's
// WASM decoder, streaming times, and the download sizes of both decoders.
//   node web/test/bench.mjs [--reps N] [--throttle BYTES_PER_SECOND] [--meshes a,b]
import fs from 'node:fs';
import path from 'node:path';
import { execFileSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { runBenchPage } from './chromium.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
const root = path.resolve(here, '../..');
const arg = (name, d) => { const i = process.argv.indexOf(name); return i > 0 ? process.argv[i + 1] : d; };
const q = new URLSearchParams({ reps: arg('--reps', '15'), throttle: arg('--throttle', '2000000') });
if (arg('--meshes')) q.set('meshes', arg('--meshes'));

const r = await runBenchPage(`bench.html?${q}`, 900000);
if (r.state !== 'done') { console.error('bench failed:', r.error); process.exit(1); }
const n = (x) => x.toLocaleString('en-US');
const f = (x, d = 1) => (x == null ? '-' : x.toFixed(d));
const lines = [];
lines.push(`Chromium ${r.chromium}, headless, this machine; median of ${r.reps} samples (each the mean of enough decodes of bytes already in memory to take about 20 ms), after 0.5 s of warm-up decodes each.`);
lines.push('');
lines.push('Draco decodes positions and faces only; "tsm attributes": the attributes tsm decodes besides (bunny: confidence and intensity; bunny_pos is the same mesh without them).');
lines.push('');
lines.push('| mesh | V / F (tsm) | tsm attributes | V (Draco) | tsm bytes | Draco bytes | tsm ms | Draco ms | tsm time / Draco time |');
lines.push('|---|---|---|---|---|---|---|---|---|');
for (const x of r.rows)
  lines.push(`| ${x.name} | ${n(x.tsmVertices)} / ${n(x.tsmFaces)} | ${x.tsmAttributes} | ${n(x.dracoVertices)} | ${n(x.tsmBytes)} | ${n(x.drcBytes)} | ` +
    `${f(x.tsmMs)} | ${f(x.dracoMs)} | ${f(x.tsmMs / x.dracoMs, 2)} |`);
lines.push('');
lines.push(`Streaming at ${r.throttle / 1e6} MB/s (server-paced), decoded on the page's thread as the bytes arrive:`);
lines.push('');
lines.push('| file | segments | bytes | first triangles ms | last triangles ms | decode ms (in feeds) | whole file, then decode: ms |');
lines.push('|---|---|---|---|---|---|---|');
for (const x of r.streaming)
  lines.push(`| ${x.name} | ${x.segments} | ${n(x.bytes)} | ${f(x.firstMs)} | ${f(x.lastMs)} | ${f(x.decodeMs)} | ` +
    `${f(x.wholeMs)} (${f(x.downloadMs, 0)} + ${f(x.wholeMs - x.downloadMs)}) |`);
lines.push('');
lines.push(execFileSync(process.execPath, [path.join(root, 'web/tools/sizes.mjs')], { encoding: 'utf8' }).trimEnd());
const md = lines.join('\n');
console.log(md);
fs.writeFileSync(path.join(root, 'build/web/bench.md'), md + '\n');
fs.writeFileSync(path.join(root, 'build/web/bench.json'), JSON.stringify(r, null, 1) + '\n');
