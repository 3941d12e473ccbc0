// Minimal glTF binary (.glb) reading and writing for the tests: a JSON
// document and one binary chunk.
export function writeGlb(json, bin) {
  const pad = (b, fill) => Buffer.concat([b, Buffer.alloc((4 - (b.length % 4)) % 4, fill)]);
  const j = pad(Buffer.from(JSON.stringify(json)), 0x20);
  const parts = [j];
  const header = Buffer.alloc(12), jh = Buffer.alloc(8);
  jh.writeUInt32LE(j.length, 0); jh.writeUInt32LE(0x4e4f534a, 4);
  const chunks = [jh, j];
  if (bin && bin.length) {
    const b = pad(bin, 0), bh = Buffer.alloc(8);
    bh.writeUInt32LE(b.length, 0); bh.writeUInt32LE(0x004e4942, 4);
    chunks.push(bh, b);
    parts.push(b);
  }
  const body = Buffer.concat(chunks);
  header.writeUInt32LE(0x46546c67, 0); header.writeUInt32LE(2, 4); header.writeUInt32LE(12 + body.length, 8);
  return Buffer.concat([header, body]);
}

export function readGlb(buf) {
  if (buf.readUInt32LE(0) !== 0x46546c67) throw new Error('not a .glb (no glTF magic)');
  const jl = buf.readUInt32LE(12);
  const json = JSON.parse(buf.subarray(20, 20 + jl).toString('utf8'));
  let bin = null;
  const at = 20 + jl;
  if (at + 8 <= buf.length && buf.readUInt32LE(at + 4) === 0x004e4942) bin = buf.subarray(at + 8, at + 8 + buf.readUInt32LE(at));
  return { json, bin };
}

// Appends typed arrays to a binary buffer as bufferViews (4-byte aligned).
export class BinWriter {
  constructor(json) { this.json = json; this.parts = []; this.length = 0; json.bufferViews = json.bufferViews || []; }
  view(array, target) {
    const b = Buffer.from(array.buffer, array.byteOffset, array.byteLength);
    const pad = (4 - (this.length % 4)) % 4;
    if (pad) { this.parts.push(Buffer.alloc(pad)); this.length += pad; }
    const v = { buffer: 0, byteOffset: this.length, byteLength: b.length };
    if (target) v.target = target;
    this.parts.push(b); this.length += b.length;
    this.json.bufferViews.push(v);
    return this.json.bufferViews.length - 1;
  }
  finish() {
    const bin = Buffer.concat(this.parts);
    this.json.buffers = [{ byteLength: bin.length }];
    return bin;
  }
}
