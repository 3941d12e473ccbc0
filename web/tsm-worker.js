// A module Web Worker that decodes a .tsm stream off the page's thread
// (used by decodeStreamInWorker in tsm.js). Messages in: {type:'start',
// wasmUrl?, decodeOptions?}, {type:'chunk', bytes}, {type:'end'},
// {type:'cancel'}; a new 'start' drops any stream left unfinished. Out:
// {type:'segment', segment} (a segment or a progressive file's level; its
// arrays, attributes' and metadata's too,
// transferred, not copied), {type:'done'},
// {type:'error', code, message}. Every message out carries the id of its 'start'.
// Whole files (decodeInWorker): in {type:'decode', id, bytes, wasmUrl?,
// decodeOptions?}, out {type:'mesh', id, mesh} (arrays transferred) or
// {type:'error', id, code, message}; they may come between a stream's messages.
import { loadTsm } from './tsm.js';

let decoderReady = null;
let stream = null;
let runId = 0; // the id of the current 'start', on every message out
let queue = Promise.resolve();

// The buffers of a decoded mesh or segment, to transfer rather than copy.
function buffersOf(s) {
  const transfer = [s.positions.buffer, s.indices.buffer];
  if (s.faceOffsets) transfer.push(s.faceOffsets.buffer);
  for (const a of s.attributes || []) {
    transfer.push(a.values.buffer);
    if (a.indices) transfer.push(a.indices.buffer);
  }
  for (const e of s.metadata || []) transfer.push(e.value.buffer);
  return transfer;
}

function send(segments) {
  for (const s of segments) self.postMessage({ type: 'segment', id: runId, segment: s }, buffersOf(s));
}

const errorMessage = (e, id) => ({ type: 'error', id, code: e && e.code !== undefined ? e.code : 7,
  message: String(e && e.message || e) });

function fail(e) {
  self.postMessage(errorMessage(e, runId));
  if (stream) { stream.free(); stream = null; }
}

function decoder(wasmUrl) {
  decoderReady = decoderReady || loadTsm(wasmUrl ? { wasmUrl } : {});
  return decoderReady.catch((err) => { decoderReady = null; throw err; });
}

self.onmessage = (e) => {
  const msg = e.data;
  // Messages are handled one after another (the decoder loads asynchronously).
  queue = queue.then(async () => {
    if (msg.type === 'decode') {
      let dec = null;
      try {
        dec = await decoder(msg.wasmUrl);
        const mesh = await dec.decodeAsync(msg.bytes, msg.decodeOptions);
        self.postMessage({ type: 'mesh', id: msg.id, mesh }, buffersOf(mesh));
      } catch (err) {
        if (dec && dec.dead) decoderReady = null; // the module aborted (out of memory): load a new one next time
        self.postMessage(errorMessage(err, msg.id));
      }
      return;
    }
    try {
      if (msg.type === 'start' || msg.type === 'cancel') {
        if (stream) { stream.free(); stream = null; }
        if (msg.type === 'cancel') return;
        runId = msg.id;
        const dec = await decoder(msg.wasmUrl);
        stream = dec.createStream(msg.decodeOptions);
      } else if (msg.type === 'chunk') {
        if (stream) send(await stream.feedAsync(msg.bytes));
      } else if (msg.type === 'end') {
        if (stream) {
          send(await stream.finishAsync());
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
