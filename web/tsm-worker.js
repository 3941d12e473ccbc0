// A module Web Worker that decodes a .tsm stream off the page's thread
// (used by decodeStreamInWorker in tsm.js). Messages in: {type:'start',
// wasmUrl?, decodeOptions?}, {type:'chunk', bytes}, {type:'end'}. Out:
// {type:'segment', segment} (its arrays transferred, not copied), {type:'done'},
// {type:'error', code, message}.
import { loadTsm } from './tsm.js';

let decoderReady = null;
let stream = null;
let queue = Promise.resolve();

function send(segments) {
  for (const s of segments) {
    const transfer = [s.positions.buffer, s.indices.buffer];
    if (s.faceOffsets) transfer.push(s.faceOffsets.buffer);
    self.postMessage({ type: 'segment', segment: s }, transfer);
  }
}

function fail(e) {
  self.postMessage({ type: 'error', code: e && e.code !== undefined ? e.code : 7, message: String(e && e.message || e) });
  if (stream) { stream.free(); stream = null; }
}

self.onmessage = (e) => {
  const msg = e.data;
  // Messages are handled one after another (the decoder loads asynchronously).
  queue = queue.then(async () => {
    try {
      if (msg.type === 'start') {
        decoderReady = decoderReady || loadTsm(msg.wasmUrl ? { wasmUrl: msg.wasmUrl } : {});
        const dec = await decoderReady;
        stream = dec.createStream(msg.decodeOptions);
      } else if (msg.type === 'chunk') {
        if (stream) send(stream.feed(msg.bytes));
      } else if (msg.type === 'end') {
        if (stream) {
          send(stream.finish());
          stream.free();
          stream = null;
          self.postMessage({ type: 'done' });
        }
      }
    } catch (err) {
      fail(err);
    }
  });
};
