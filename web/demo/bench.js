// Decode-time bench: tsm (this build) beside Draco's WASM decoder (draco3d),
// same page, same bytes-in-memory conditions; then streaming: time to the
// first and the last segment of a throttled download. window.benchResult
// holds everything for web/test/bench.mjs.
import { loadTsm } from '/dist/tsm.js';
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
const THROTTLE = Number(params.get('throttle') || 2000000);
const only = params.get('meshes') ? params.get('meshes').split(',') : null;
const out = document.getElementById('out');
const log = (s) => { document.getElementById('log').textContent += '\n' + s; };
const result = (window.benchResult = { state: 'running', reps: REPS, throttle: THROTTLE, rows: [], streaming: [] });

const median = (a) => { const s = [...a].sort((x, y) => x - y); const n = s.length; return n % 2 ? s[n >> 1] : (s[n / 2 - 1] + s[n / 2]) / 2; };
const fetchBytes = async (url) => new Uint8Array(await (await fetch(url)).arrayBuffer());

function table(title, head, rows) {
  const h = document.createElement('h2');
  h.textContent = title;
  const t = document.createElement('table');
  t.innerHTML = '<tr>' + head.map((x) => `<th>${x}</th>`).join('') + '</tr>' +
    rows.map((r) => '<tr>' + r.map((x) => `<td>${x}</td>`).join('') + '</tr>').join('');
  out.append(h, t);
}

async function main() {
  const index = await (await fetch('/data/index.json')).json();
  let t = performance.now();
  const tsm = await loadTsm();
  result.tsmLoadMs = performance.now() - t;
  t = performance.now();
  const draco = await loadDraco();
  result.dracoLoadMs = performance.now() - t;
  log(`modules ready: tsm ${result.tsmLoadMs.toFixed(1)} ms, draco ${result.dracoLoadMs.toFixed(1)} ms (fetch + compile)`);

  const rowsHtml = [];
  // A level variant (name_lN) and a positions-only one (name_pos) are timed
  // against their whole mesh's Draco file. Draco's PLY reader keeps positions
  // only: where the tsm file has attributes (the bunny's confidence and
  // intensity), tsm decodes more than Draco; the row says how many.
  const byName = Object.fromEntries(index.map((x) => [x.name, x]));
  for (const m of index) {
    const base = byName[m.name.replace(/_(l\d|pos)$/, '')] || m;
    if (!base.drcBytes || m.ref.faceCount < 1000 || (only && !only.includes(m.name))) continue;
    const tb = await fetchBytes(`/data/${m.name}.tsm`);
    const db = await fetchBytes(`/data/${base.name}.drc`);
    const a = await tsm.decodeAsync(tb), b = dracoDecode(draco, db); // the full module, if this file needs it
    warm(() => tsm.decode(tb)); warm(() => dracoDecode(draco, db));
    // One sample decodes `inner` times (about 20 ms of tsm's work): the page's clock ticks in 0.1 ms steps.
    const time = (f, inner) => { const t0 = performance.now(); for (let k = 0; k < inner; ++k) f(); return (performance.now() - t0) / inner; };
    const once = Math.min(time(() => tsm.decode(tb), 1), time(() => tsm.decode(tb), 1), time(() => tsm.decode(tb), 1));
    const inner = Math.max(1, Math.ceil(20 / Math.max(0.1, once)));
    const ts = [], ds = [];
    for (let i = 0; i < REPS; ++i) {
      ts.push(time(() => tsm.decode(tb), inner));
      ds.push(time(() => dracoDecode(draco, db), inner));
    }
    const row = { name: m.name, segments: m.segments, tsmBytes: tb.length, drcBytes: db.length,
      tsmVertices: a.vertexCount, tsmFaces: a.faceCount, tsmAttributes: a.attributes.length, dracoVertices: b.vertexCount, dracoFaces: b.faceCount,
      tsmMs: median(ts), tsmMinMs: Math.min(...ts), dracoMs: median(ds), dracoMinMs: Math.min(...ds) };
    result.rows.push(row);
    log(`${m.name}: tsm ${row.tsmMs.toFixed(2)} ms, draco ${row.dracoMs.toFixed(2)} ms`);
    rowsHtml.push([m.name, `${row.tsmVertices.toLocaleString()} / ${row.tsmFaces.toLocaleString()}`, row.tsmAttributes,
      row.tsmBytes.toLocaleString(), row.drcBytes.toLocaleString(), row.tsmMs.toFixed(2), row.dracoMs.toFixed(2),
      (row.tsmMs / row.dracoMs).toFixed(2), `${row.dracoVertices.toLocaleString()} / ${row.dracoFaces.toLocaleString()}`]);
    await new Promise((r) => setTimeout(r, 0));
  }
  table(`Decode time, ms (median of ${REPS})`, ['mesh', 'tsm V / F', 'tsm attributes', 'tsm bytes', 'Draco bytes', 'tsm ms', 'Draco ms',
    'tsm time / Draco time', 'Draco V / F'], rowsHtml);

  // Streaming: a throttled download, decoded as it arrives, on this thread.
  const sHtml = [];
  for (const m of index) {
    if (only && !only.includes(m.name)) continue;
    if (m.segments < 2 && m.name !== 'dragon_res2') continue;
    const t0 = performance.now();
    let first = null, pieces = 0, faces = 0, dec = 0;
    const resp = await fetch(`/data/${m.name}.tsm?throttle=${THROTTLE}`);
    for await (const seg of tsm.decodeStream(resp.body)) {
      if (first == null && seg.faceCount) first = performance.now() - t0;
      pieces++; faces += seg.faceCount; dec = seg.decodeMs;
    }
    const last = performance.now() - t0;
    // The same download taken whole, then decoded (no streaming).
    const w0 = performance.now();
    const whole = await fetchBytes(`/data/${m.name}.tsm?throttle=${THROTTLE}`);
    const wDownload = performance.now() - w0;
    tsm.decode(whole);
    const wholeMs = performance.now() - w0;
    const row = { name: m.name, segments: m.segments, bytes: m.tsmBytes, firstMs: first, lastMs: last, pieces, faces,
      decodeMs: dec, downloadMs: wDownload, wholeMs };
    result.streaming.push(row);
    log(`${m.name} streamed: first triangles ${first.toFixed(1)} ms, last ${last.toFixed(1)} ms; whole file then decode ${wholeMs.toFixed(1)} ms`);
    sHtml.push([m.name, m.segments, m.tsmBytes.toLocaleString(), first.toFixed(1), last.toFixed(1), pieces, dec.toFixed(1),
      wDownload.toFixed(1), wholeMs.toFixed(1)]);
  }
  table(`Streaming at ${THROTTLE / 1e6} MB/s (decoded on the page's thread as the bytes arrive)`,
    ['file', 'segments', 'bytes', 'first triangles ms', 'last triangles ms', 'pieces', 'decode ms',
      'whole file: download ms', 'whole file: download + decode ms'], sHtml);
  result.state = 'done';
  log('done');
}

main().catch((e) => { result.state = 'error'; result.error = String(e && e.stack || e); log('error: ' + (e.stack || e)); });
