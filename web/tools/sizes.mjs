// Download sizes of the decoder beside Draco's (draco3d npm package): raw,
// gzip -9 and brotli (quality 11), as a server would send them precompressed.
//   node web/tools/sizes.mjs [--json]
import fs from 'node:fs';
import path from 'node:path';
import zlib from 'node:zlib';
import { fileURLToPath } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const root = path.resolve(here, '../..');
const dist = process.env.TSM_WEB_DIST || path.join(root, 'build/web');
const draco = path.join(root, 'web/node_modules/draco3d');
const sets = {
  'tsm core (wasm + glue + tsm.js)': [path.join(dist, 'tsm_decoder.wasm'), path.join(dist, 'tsm_decoder.js'), path.join(dist, 'tsm.js')],
  'tsm full module, loaded when a file needs it (wasm + glue)': [path.join(dist, 'tsm_decoder_full.wasm'), path.join(dist, 'tsm_decoder_full.js')],
  'draco3d decoder (wasm + glue)': [path.join(draco, 'draco_decoder.wasm'), path.join(draco, 'draco_decoder_nodejs.js')],
};
const measure = (f) => {
  const b = fs.readFileSync(f);
  return {
    file: path.relative(root, f), raw: b.length,
    gzip: zlib.gzipSync(b, { level: 9 }).length,
    brotli: zlib.brotliCompressSync(b, { params: { [zlib.constants.BROTLI_PARAM_QUALITY]: 11,
      [zlib.constants.BROTLI_PARAM_SIZE_HINT]: b.length } }).length,
  };
};
const out = [];
for (const [name, files] of Object.entries(sets)) {
  const rows = files.filter((f) => fs.existsSync(f)).map(measure);
  const total = rows.reduce((a, r) => ({ raw: a.raw + r.raw, gzip: a.gzip + r.gzip, brotli: a.brotli + r.brotli }),
    { raw: 0, gzip: 0, brotli: 0 });
  out.push({ name, rows, total });
}
if (process.argv.includes('--json')) { console.log(JSON.stringify(out, null, 1)); process.exit(0); }
const n = (x) => x.toLocaleString('en-US');
console.log('| file | raw bytes | gzip -9 | brotli 11 |\n|---|---|---|---|');
for (const s of out) {
  for (const r of s.rows) console.log(`| ${r.file} | ${n(r.raw)} | ${n(r.gzip)} | ${n(r.brotli)} |`);
  console.log(`| **${s.name}** | **${n(s.total.raw)}** | **${n(s.total.gzip)}** | **${n(s.total.brotli)}** |`);
}
