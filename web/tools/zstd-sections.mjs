// Rewrites a .tsm file with every section zstd-coded (codec 1), even where
// that is larger (range-coded payloads do not shrink): the encoder never
// writes such files, but the format allows them, so this is how the
// WebAssembly build's zstd path is tested.
// Needs the zstd command-line tool.
//   node web/tools/zstd-sections.mjs in.tsm out.tsm
import fs from 'node:fs';
import { execFileSync } from 'node:child_process';

const P1 = 0x9e3779b1, P2 = 0x85ebca77, P3 = 0xc2b2ae3d, P4 = 0x27d4eb2f, P5 = 0x165667b1;
const rotl = (x, r) => ((x << r) | (x >>> (32 - r))) >>> 0;
const mul = (a, b) => Math.imul(a, b) >>> 0;
// XXH32, seed 0 (the container's checksum)
function xxh32(b, seed = 0) {
  const n = b.length;
  const u32 = (i) => (b[i] | (b[i + 1] << 8) | (b[i + 2] << 16) | (b[i + 3] << 24)) >>> 0;
  let i = 0, h;
  if (n >= 16) {
    let v1 = (seed + P1 + P2) >>> 0, v2 = (seed + P2) >>> 0, v3 = seed >>> 0, v4 = (seed - P1) >>> 0;
    const round = (v, x) => mul(rotl((v + mul(x, P2)) >>> 0, 13), P1);
    for (; i + 16 <= n; i += 16) {
      v1 = round(v1, u32(i)); v2 = round(v2, u32(i + 4)); v3 = round(v3, u32(i + 8)); v4 = round(v4, u32(i + 12));
    }
    h = (rotl(v1, 1) + rotl(v2, 7) + rotl(v3, 12) + rotl(v4, 18)) >>> 0;
  } else {
    h = (seed + P5) >>> 0;
  }
  h = (h + n) >>> 0;
  for (; i + 4 <= n; i += 4) h = mul(rotl((h + mul(u32(i), P3)) >>> 0, 17), P4);
  for (; i < n; ++i) h = mul(rotl((h + mul(b[i], P5)) >>> 0, 11), P1);
  h ^= h >>> 15; h = mul(h, P2); h ^= h >>> 13; h = mul(h, P3); h ^= h >>> 16;
  return h >>> 0;
}

const src = fs.readFileSync(process.argv[2]);
let at = 0;
const varint = () => { let v = 0, s = 1; for (;;) { const c = src[at++]; v += (c & 0x7f) * s; s *= 128; if (c < 0x80) return v; } };
const putVarint = (v, out) => { while (v >= 0x80) { out.push((v % 128) | 0x80); v = Math.floor(v / 128); } out.push(v); };
if (src.subarray(0, 4).toString('latin1') !== 'TSM\x1a') throw new Error('not a .tsm file');
// The header (FORMAT.md §3): version, three counts, grid and level bytes,
// origin and top (16 bytes), the segment count (level bit 4), the exact
// grid's fields (grid bit 5).
at = 4;
for (let i = 0; i < 4; i++) varint();
const grid = src[at], level = src[at + 1];
at += 18;
if (level & 0x10) varint();
if (grid & 0x20) { at += 8; for (let i = 0; i < 3; i++) varint(); }
const parts = [src.subarray(0, at)];
let first = true, recoded = 0;
for (;;) {
  const tag = varint();
  if (tag === 0) { parts.push(Buffer.from([0])); break; }
  const id = Math.floor(tag / 2), codec = tag % 2;
  const stored = varint(), raw = codec ? varint() : stored;
  const payload = src.subarray(at, at + stored);
  at += stored + 4;
  let out = payload;
  if (codec === 0) {
    out = execFileSync('zstd', ['-19', '-q', '-c'], { input: payload, maxBuffer: 1 << 30 });
    recoded++;
  }
  const head = [];
  putVarint(id * 2 + 1, head);
  putVarint(out.length, head);
  putVarint(raw, head);
  const section = Buffer.concat([Buffer.from(head), out]);
  // A section's checksum covers its bytes; the first section's, the header's too (FORMAT.md §4.1).
  const sum = xxh32(first ? Buffer.concat([parts[0], section]) : section);
  parts.push(section, Buffer.from([sum & 0xff, (sum >>> 8) & 0xff, (sum >>> 16) & 0xff, sum >>> 24]));
  first = false;
}
if (at !== src.length) throw new Error(`${src.length - at} bytes after the end marker`);
fs.writeFileSync(process.argv[3], Buffer.concat(parts));
console.error(`zstd-sections: ${recoded} section(s) zstd-coded`);
