// The demo: fetches a .tsm file, streams the body into the decoder (on this
// thread or in a Web Worker) and draws each segment as it is decoded; a
// progressive file's whole shape is drawn coarse first and redrawn at each
// finer level as the bytes arrive.
// Query: ?mesh=NAME&worker=1&throttle=BYTES_PER_SECOND&chunk=BYTES (mesh= loads at once).
// window.tsmDemo holds the state and, when done, the counts and checksums
// the browser test compares with the native decoder's.
import { loadTsm, decodeStreamInWorker, createTsmWorker } from '/dist/tsm.js';
import { MeshView } from './render.js';
import { fnv1a, hex } from './hash.js';

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
const state = (window.tsmDemo = { state: 'starting' });
const stats = $('stats');

function show(s) {
  const kb = (n) => (n / 1024).toFixed(1) + ' KiB';
  stats.textContent =
    `${s.name}: ${s.finished ? 'done' : 'loading'}${s.worker ? ' (Web Worker)' : ''}\n` +
    `bytes received ${kb(s.bytes)}${s.total ? ' of ' + kb(s.total) : ''}   ` +
    `triangles decoded ${s.triangles.toLocaleString()}   vertices ${s.vertices.toLocaleString()}   ` +
    `segments ${s.segmentsDone}/${s.segmentCount || '?'}` +
    (s.levels.length ? `   level ${s.levels.length - 1} (batches ${s.levels[s.levels.length - 1].batches}, ` +
      `error ${s.levels[s.levels.length - 1].error >= 0 ? s.levels[s.levels.length - 1].error.toPrecision(3) : '?'})` : '') + '\n' +
    `decode time ${s.decodeMs.toFixed(1)} ms   first triangles at ${s.firstMs == null ? '-' : s.firstMs.toFixed(1) + ' ms'}   ` +
    `total ${s.totalMs == null ? '-' : s.totalMs.toFixed(1) + ' ms'} (from the request to the last segment)`;
}

async function main() {
  const tsm = await loadTsm();
  const view = new MeshView($('view'));
  const index = await (await fetch('/data/index.json')).json();
  for (const m of index) $('mesh').add(new Option(`${m.name} (${(m.tsmBytes / 1024).toFixed(0)} KiB)`, m.name));
  if (params.get('mesh')) $('mesh').value = params.get('mesh');
  $('worker').checked = params.get('worker') === '1';
  if (params.get('throttle')) {
    const t = params.get('throttle');
    if (![...$('throttle').options].some((o) => o.value === t)) $('throttle').add(new Option(`${t} B/s`, t));
    $('throttle').value = t;
  }
  state.state = 'ready';
  state.version = tsm.version;
  stats.textContent = `decoder ${tsm.version} ready${tsm.hasStreaming ? '' : ' (no streaming C API in this build: whole-file decode at the end)'}`;

  let running = null;
  let worker = null; // made on the first load in a worker, then reused
  async function load() {
    if (running) return;
    const name = $('mesh').value, inWorker = $('worker').checked, throttle = Number($('throttle').value);
    const s = { name, worker: inWorker, bytes: 0, total: 0, triangles: 0, vertices: 0, faces: 0, corners: 0, segmentsDone: 0,
      segmentCount: 0, decodeMs: 0, firstMs: null, totalMs: null, pieces: 0, finished: false, levels: [] };
    Object.assign(state, { state: 'loading', stats: s, result: null, error: null });
    view.clear();
    let hIdx = 0x811c9dc5, hPos = 0x811c9dc5, hOff = fnv1a(new Uint32Array(1)), polygons = false;
    const t0 = performance.now();
    running = (async () => {
      const q = new URLSearchParams();
      if (throttle) q.set('throttle', throttle);
      const resp = await fetch(`/data/${name}.tsm${throttle ? '?' + q : ''}`);
      if (!resp.ok) throw new Error(`${resp.status} fetching ${name}.tsm`);
      s.total = Number(resp.headers.get('content-length')) || 0;
      const reader = resp.body.getReader();
      const counted = (async function* () {
        for (;;) {
          const { done, value } = await reader.read();
          if (done) return;
          s.bytes += value.length;
          show(s);
          yield value;
        }
      })();
      if (inWorker && !worker) worker = createTsmWorker();
      const segments = inWorker ? decodeStreamInWorker(counted, { worker }) : tsm.decodeStream(counted);
      for await (const seg of segments) {
        if (seg.level) {
          // A progressive file's level of detail: the whole mesh, drawn instead of the last one.
          view.clear();
          hIdx = hPos = 0x811c9dc5; hOff = fnv1a(new Uint32Array(1)); polygons = false;
          Object.assign(s, { triangles: 0, faces: 0, vertices: 0, corners: 0 });
          // (the loose vertices after the last batch come as that level again)
          if (s.levels.length && s.levels[s.levels.length - 1].batches === seg.batchesDone) s.levels.pop();
          s.levels.push({ batches: seg.batchesDone, vertices: seg.vertexCount, faces: seg.faceCount, error: seg.levelError,
            bytesIn: seg.bytesIn, ms: performance.now() - t0 });
        }
        const tris = seg.faceOffsets ? seg.indices.length - 2 * seg.faceCount : seg.faceCount;
        if (s.firstMs == null && seg.faceCount) s.firstMs = performance.now() - t0;
        s.triangles += tris; s.faces += seg.faceCount; s.vertices += seg.vertexCount; s.corners += seg.indices.length;
        s.segmentsDone = seg.segmentsDone; s.segmentCount = seg.segmentCount; s.decodeMs = seg.decodeMs; s.pieces++;
        hIdx = fnv1a(seg.indices, hIdx);
        hPos = fnv1a(seg.positions, hPos);
        if (seg.faceOffsets) { polygons = true; hOff = fnv1a(seg.faceOffsets.subarray(1), hOff); }
        else hOff = fnv1a(Uint32Array.from({ length: seg.faceCount }, (_, k) => seg.cornerStart + 3 * (k + 1)), hOff);
        view.add(seg);
        show(s);
        // let the page paint between pieces
        await new Promise((r) => setTimeout(r, 0));
      }
      s.totalMs = performance.now() - t0;
      s.finished = true;
      show(s);
      const result = { name, worker: inWorker, vertexCount: s.vertices, faceCount: s.faces, cornerCount: s.corners,
        triangles: !polygons, indexHash: hex(hIdx), positionHash: hex(hPos), bytes: s.bytes,
        pieces: s.pieces, segmentCount: s.segmentCount, decodeMs: s.decodeMs, firstMs: s.firstMs, totalMs: s.totalMs,
        levels: s.levels };
      if (polygons) result.faceOffsetHash = hex(hOff);
      // wait for the frame with the whole mesh before saying done
      await new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
      Object.assign(state, { state: 'done', result });
    })();
    try {
      await running;
    } catch (e) {
      Object.assign(state, { state: 'error', error: String(e && e.message || e) });
      stats.textContent += `\nerror: ${e.message || e}`;
      stats.classList.add('err');
    } finally {
      running = null;
    }
  }
  $('load').onclick = load;
  if (params.get('mesh')) load();
}

main().catch((e) => {
  Object.assign(state, { state: 'error', error: String(e && e.message || e) });
  stats.textContent = 'error: ' + (e.message || e);
  stats.classList.add('err');
});
