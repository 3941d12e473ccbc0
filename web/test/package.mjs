// The npm package test: `npm pack` of @tsm-codec/decoder (web/pack.sh), the
// tarball installed into a scratch project (build/web/pack-test/), which
// then, under Node, imports the package by name, decodes a .tsm file, loads
// a compressed .glb through three.js's GLTFLoader with the package's plugin,
// and type-checks a TypeScript client of both entry points against the
// package's declarations (tsc --strict; three.js and @types/three from web/).
//   node web/test/package.mjs
// Env: TSM (the native CLI, default build/release/cli/tsm).
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { sphereGlb } from './sphere-glb.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
const web = path.resolve(here, '..');
const root = path.resolve(web, '..');
const TSM = process.env.TSM || path.join(root, 'build/release/cli/tsm');
const scratch = path.join(root, 'build/web/pack-test');
const run = (cmd, args, opts = {}) => execFileSync(cmd, args, { encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'], ...opts });

let failed = 0;
const check = (cond, msg) => { console.log(`${cond ? 'ok  ' : 'FAIL'} package: ${msg}`); if (!cond) failed++; };

const tarball = run('bash', [path.join(web, 'pack.sh')]).trim();
const files = run('tar', ['tzf', tarball]).split('\n').filter(Boolean).map((f) => f.replace(/^package\//, '')).sort();
const want = ['README.md', 'gltf-tsm-extension.d.ts', 'gltf-tsm-extension.js', 'package.json', 'tsm-worker.js',
  'tsm.d.ts', 'tsm.js', 'tsm_decoder.js', 'tsm_decoder.wasm', 'tsm_decoder_full.js', 'tsm_decoder_full.wasm'];
check(JSON.stringify(files) === JSON.stringify(want), `${path.basename(tarball)} (${fs.statSync(tarball).size} bytes) holds ${files.join(', ')}`);

// The scratch project: the tarball installed by npm, three.js linked from web/.
fs.rmSync(scratch, { recursive: true, force: true });
fs.mkdirSync(scratch, { recursive: true });
fs.writeFileSync(path.join(scratch, 'package.json'), JSON.stringify({ name: 'pack-test', private: true, type: 'module' }));
run('npm', ['install', '--no-audit', '--no-fund', '--prefer-offline', tarball], { cwd: scratch });
for (const dep of ['three', '@types/three', '@types/webxr']) {
  fs.mkdirSync(path.dirname(path.join(scratch, 'node_modules', dep)), { recursive: true });
  fs.symlinkSync(path.join(web, 'node_modules', dep), path.join(scratch, 'node_modules', dep));
}
const tsmFile = path.join(scratch, 'sphere.tsm');
fs.writeFileSync(path.join(scratch, 'sphere.glb'), sphereGlb());
run(TSM, ['encode', path.join(scratch, 'sphere.glb'), '-o', tsmFile, '-f', '--quiet']);
const glb = path.join(scratch, 'sphere.tsm.glb');
run(TSM, ['encode', path.join(scratch, 'sphere.glb'), '-o', glb, '-f', '--quiet']);

fs.writeFileSync(path.join(scratch, 'client.mjs'), `
import fs from 'node:fs';
import { loadTsm, TsmError } from '@tsm-codec/decoder';
import { GLTFTsmExtension, EXTENSION_NAME } from '@tsm-codec/decoder/three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
const wasm = new URL(import.meta.resolve('@tsm-codec/decoder/tsm_decoder.wasm'));
const fullWasm = new URL(import.meta.resolve('@tsm-codec/decoder/tsm_decoder_full.wasm'));
const tsm = await loadTsm({ wasmBinary: fs.readFileSync(wasm), fullWasmBinary: fs.readFileSync(fullWasm) });
const mesh = await tsm.decodeAsync(fs.readFileSync('sphere.tsm')); // glTF metadata, zstd-coded: the full module
let refused = '';
try { tsm.decode(new Uint8Array(16)); } catch (e) { refused = e instanceof TsmError ? e.codeName : String(e); }
const loader = new GLTFLoader();
loader.register((parser) => new GLTFTsmExtension(parser, { decoder: tsm, workerThreshold: Infinity }));
const glb = fs.readFileSync('sphere.tsm.glb');
const gltf = await loader.parseAsync(glb.buffer.slice(glb.byteOffset, glb.byteOffset + glb.length), '');
const g = gltf.scene.getObjectByProperty('isMesh', true).geometry;
console.log(JSON.stringify({ version: tsm.version, vertices: mesh.vertexCount, faces: mesh.faceCount,
  kinds: mesh.attributes.map((a) => a.kind), refused, extension: EXTENSION_NAME,
  three: { vertices: g.attributes.position.count, indices: g.index.count, attributes: Object.keys(g.attributes).sort(),
    colorType: g.attributes.color.array.constructor.name, colorNormalized: g.attributes.color.normalized } }));
`);
let r = null;
try { r = JSON.parse(run(process.execPath, ['client.mjs'], { cwd: scratch })); } catch (e) { check(false, `client.mjs: ${e.stderr || e.message}`); }
if (r) {
  // the sphere of web/test/sphere-glb.mjs: 25 × 41 vertices, 2 × 24 × 40 − 80 triangles, which use all
  // vertices but 2 (the first of the top row, the last of the bottom one): the .tsm keeps them, the glTF writer not
  check(r.vertices === 1025 && r.faces === 1840 && r.kinds.join() === 'normal,texcoord,color' && r.refused !== '' &&
    r.three.vertices === 1023 && r.three.indices === 3 * 1840 && r.three.attributes.join() === 'color,normal,position,uv' &&
    r.three.colorType === 'Uint8Array' && r.three.colorNormalized, `imported by name under Node: ${JSON.stringify(r)}`);
}

fs.writeFileSync(path.join(scratch, 'tsconfig.json'), JSON.stringify({ compilerOptions: {
  target: 'es2022', module: 'nodenext', moduleResolution: 'nodenext', strict: true, noEmit: true, skipLibCheck: true,
  lib: ['es2022', 'dom'], types: [] }, files: ['client.ts'] }));
fs.writeFileSync(path.join(scratch, 'client.ts'), `
import { loadTsm, decodeInWorker, TsmError, type DecodedMesh, type Attribute } from '@tsm-codec/decoder';
import { GLTFTsmExtension } from '@tsm-codec/decoder/three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
export async function main(bytes: Uint8Array): Promise<number> {
  const tsm = await loadTsm({ wasmUrl: '/tsm_decoder.wasm' });
  const mesh: DecodedMesh = tsm.decode(bytes, { maxVertices: 1e6 });
  const normal: Attribute | undefined = mesh.attributes.find((a) => a.kind === 'normal');
  const loader = new GLTFLoader();
  loader.register((parser) => new GLTFTsmExtension(parser, { workerThreshold: 1 << 18, decoder: tsm }));
  const other = await decodeInWorker(bytes);
  for await (const seg of tsm.decodeStream([bytes])) if (seg.metadata) return seg.segmentsDone;
  // @ts-expect-error: decode takes bytes, not a string
  tsm.decode('not bytes');
  // @ts-expect-error: the plugin has no such option
  new GLTFTsmExtension(null as never, { threshold: 3 });
  try { tsm.decode(bytes); } catch (e) { if (e instanceof TsmError) return e.code; }
  return mesh.positions.length + (normal ? normal.components : 0) + other.vertexCount;
}
`);
try {
  run(process.execPath, [path.join(web, 'node_modules/typescript/bin/tsc'), '-p', scratch], { cwd: scratch });
  check(true, 'a TypeScript client of both entry points type-checks (tsc --strict), and two wrong calls are refused');
} catch (e) {
  check(false, `tsc: ${e.stdout || ''}${e.stderr || e.message}`);
}
process.exit(failed ? 1 : 0);
