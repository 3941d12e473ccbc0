// A module Web Worker that decodes a .tsm stream off the page's thread
// (used by decodeStreamInWorker in tsm.js). Messages in: {type:'start',
// wasmUrl?, decodeOptions?}, {type:'chunk', bytes}, {type:'end'},
// {type:'cancel'}; a new 'start' drops any stream left unfinished. Out:
// {type:'segment', segment} (its arrays, attributes' and metadata's too,
// transferred, not copied), {type:'done'},
// {type:'error', code, message}.
import { loadTsm } from './tsm.js';

let decoderReady = null;
let stream = null;
let runId = 0; // the id of the current 'start', on every message out
let queue = Promise.resolve();

function send(segments) {
  for (const s of segments) {
    const transfer = [s.positions.buffer, s.indices.buffer];
    if (s.faceOffsets) transfer.push(s.faceOffsets.buffer);
    for (const a of s.attributes || []) {
      transfer.push(a.values.buffer);
      if (a.indices) transfer.push(a.indices.buffer);
    }
    for (const e of s.metadata || []) transfer.push(e.value.buffer);
    self.postMessage({ type: 'segment', id: runId, segment: s }, transfer);
  }
}

function fail(e) {
  self.postMessage({ type: 'error', id: runId, code: e && e.code !== undefined ? e.code : 7,
    message: String(e && e.message || e) });
  if (stream) { stream.free(); stream = null; }
}

self.onmessage = (e) => {
  const msg = e.data;
  // Messages are handled one after another (the decoder loads asynchronously).
  queue = queue.then(async () => {
    try {
      if (msg.type === 'start' || msg.type === 'cancel') {
        if (stream) { stream.free(); stream = null; }
        if (msg.type === 'cancel') return;
        runId = msg.id;
        decoderReady = decoderReady || loadTsm(msg.wasmUrl ? { wasmUrl: msg.wasmUrl } : {});
        const dec = await decoderReady.catch((err) => { decoderReady = null; throw err; });
        stream = dec.createStream(msg.decodeOptions);
      } else if (msg.type === 'chunk') {
        if (stream) send(stream.feed(msg.bytes));
      } else if (msg.type === 'end') {
        if (stream) {
          send(stream.finish());
          stream.free();
          stream = null;
          self.postMessage({ type: 'done', id: runId });
        }
      }
    } catch (err) {
      fail(err);
    }
  });
};
