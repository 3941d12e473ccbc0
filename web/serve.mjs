// A static file server for the demo and the browser test, on localhost only.
//   node web/serve.mjs [--port 8321]
// Routes: /            -> web/demo/           (the pages)
//         /dist/       -> build/web/          (tsm.js, tsm-worker.js, tsm_decoder.{js,wasm})
//         /data/       -> build/web/data/     (.tsm and .drc files made by web/prepare-data.sh)
//         /draco/      -> web/node_modules/draco3d/
//         /three/      -> web/node_modules/three/  (three.js for gltf.html)
//         /meshopt/    -> web/node_modules/meshoptimizer/  (its decoder, for gltf-bench.html)
//         /corpus/     -> the corpus (CORPUS, default ../shared/corpus), read only: the original glTF assets
// --throttle BYTES_PER_SECOND slows the /data/ responses down (to watch streaming);
// so does ?throttle=N on a request. TSM_WEB_DIST=DIR serves another build as /dist/.
import http from 'node:http';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const root = path.resolve(here, '..');
const routes = [
  ['/dist/', path.resolve(process.env.TSM_WEB_DIST || path.join(root, 'build/web'))],
  ['/data/', path.join(root, 'build/web/data')],
  ['/draco/', path.join(here, 'node_modules/draco3d')],
  ['/three/', path.join(here, 'node_modules/three')],
  ['/meshopt/', path.join(here, 'node_modules/meshoptimizer')],
  ['/corpus/', path.resolve(process.env.CORPUS || path.join(root, '../shared/corpus'))],
  ['/', path.join(here, 'demo')],
];
const types = {
  '.html': 'text/html; charset=utf-8', '.js': 'text/javascript; charset=utf-8', '.mjs': 'text/javascript; charset=utf-8',
  '.wasm': 'application/wasm', '.css': 'text/css', '.json': 'application/json', '.png': 'image/png',
  '.glb': 'model/gltf-binary', '.gltf': 'model/gltf+json',
};

export function startServer({ port = 0, throttle = 0, chunk = 16384 } = {}) {
  const server = http.createServer((req, res) => {
    const url = new URL(req.url, 'http://localhost');
    let file = null;
    for (const [prefix, dir] of routes) {
      if (url.pathname.startsWith(prefix)) {
        const rel = decodeURIComponent(url.pathname.slice(prefix.length)) || 'index.html';
        const p = path.resolve(dir, rel);
        if (p.startsWith(dir + path.sep) || p === dir) file = p;
        break;
      }
    }
    if (!file || !fs.existsSync(file) || !fs.statSync(file).isFile()) {
      res.writeHead(404, { 'content-type': 'text/plain' });
      res.end('not found');
      return;
    }
    const size = fs.statSync(file).size;
    res.writeHead(200, {
      'content-type': types[path.extname(file)] || 'application/octet-stream',
      'content-length': size,
      'cache-control': 'no-store',
    });
    const rate = Number(url.searchParams.get('throttle') || (url.pathname.startsWith('/data/') ? throttle : 0));
    if (!rate) { fs.createReadStream(file).pipe(res); return; }
    // Throttled: `chunk` bytes at a time, paced to `rate` bytes per second.
    const fd = fs.openSync(file, 'r');
    let at = 0;
    let closed = false;
    const close = () => { if (!closed) { closed = true; fs.closeSync(fd); } };
    const step = () => {
      if (closed) return;
      if (at >= size) { close(); res.end(); return; }
      const n = Math.min(chunk, size - at);
      const buf = Buffer.alloc(n);
      fs.readSync(fd, buf, 0, n, at);
      at += n;
      res.write(buf);
      setTimeout(step, (1000 * n) / rate);
    };
    res.on('close', close);
    step();
  });
  return new Promise((resolve) => server.listen(port, '127.0.0.1', () => resolve(server)));
}

if (process.argv[1] && fileURLToPath(import.meta.url) === path.resolve(process.argv[1])) {
  const arg = (name, d) => { const i = process.argv.indexOf(name); return i > 0 ? process.argv[i + 1] : d; };
  const server = await startServer({ port: Number(arg('--port', 8321)), throttle: Number(arg('--throttle', 0)) });
  const { port } = server.address();
  console.log(`tsm demo: http://localhost:${port}/  (bench: http://localhost:${port}/bench.html)`);
}
