// Loads a compressed .glb (TSM_mesh_compression) through three.js's
// GLTFLoader with the tsm plugin and draws it beside the uncompressed asset,
// with the same camera and lights.
// Query: ?a=URL (the compressed file) &b=URL (the original; optional)
//        &worker=BYTES (the plugin's workerThreshold) &plain=1 (no plugin) &size=PX
//        &t=SECONDS (the time in the first animation clip drawn, default 0.7)
// Without a=, the assets of /data/gltf/index.json are offered.
// window.tsmGltf: { state: 'loading' | 'done' | 'error', views: [{ url, loadMs,
// meshes: [{ name, vertexCount, usedVertices, indexCount, attributes: { name: { itemSize,
// normalized, array } } }] }], diff (a against b: { meanAbs, over32, pixels, drawn }) }.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { DRACOLoader } from 'three/addons/loaders/DRACOLoader.js';
import { MeshoptDecoder } from 'three/addons/libs/meshopt_decoder.module.js';
import { GLTFTsmExtension } from '/dist/gltf-tsm-extension.js';

const params = new URLSearchParams(location.search);
const SIZE = Number(params.get('size') || 480);
const state = (window.tsmGltf = { state: 'loading', views: [] });

// three.js's own Draco and meshopt support, for originals compressed with those
let draco = null;
function loader() {
  const l = new GLTFLoader();
  draco = draco || new DRACOLoader().setDecoderPath('/three/examples/jsm/libs/draco/gltf/');
  l.setDRACOLoader(draco);
  l.setMeshoptDecoder(MeshoptDecoder);
  const workerThreshold = params.has('worker') ? Number(params.get('worker')) : undefined;
  if (params.get('plain') !== '1') l.register((parser) => new GLTFTsmExtension(parser, { workerThreshold }));
  return l;
}

function describe(scene) {
  const meshes = [];
  scene.traverse((o) => {
    if (!o.isMesh) return;
    const g = o.geometry;
    const attributes = {};
    for (const [name, a] of Object.entries(g.attributes))
      attributes[name] = { itemSize: a.itemSize, normalized: a.normalized, array: a.array.constructor.name, count: a.count };
    // the vertices the triangles use (tsm keeps only those)
    const usedVertices = g.index ? new Set(g.index.array).size : g.attributes.position.count;
    meshes.push({ name: o.name, vertexCount: g.attributes.position.count, usedVertices, indexCount: g.index ? g.index.count : null,
      attributes, skinned: !!o.isSkinnedMesh });
  });
  return meshes;
}

// One camera for every view: fitted to the bounding box of the first view's scene.
function cameraFor(scene) {
  const box = new THREE.Box3().setFromObject(scene);
  const c = box.getCenter(new THREE.Vector3()), r = box.getSize(new THREE.Vector3()).length() / 2 || 1;
  const cam = new THREE.PerspectiveCamera(35, 1, r / 100, r * 100);
  cam.position.copy(c).add(new THREE.Vector3(1, 0.7, 1.3).normalize().multiplyScalar(r * 2.6));
  cam.lookAt(c);
  return cam;
}

function render(scene, camera, caption) {
  const canvas = document.createElement('canvas');
  const fig = document.createElement('figure');
  const cap = document.createElement('figcaption');
  cap.textContent = caption;
  fig.append(canvas, cap);
  document.getElementById('views').append(fig);
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setSize(SIZE, SIZE);
  renderer.setClearColor(0x30343a);
  const lit = new THREE.Scene();
  lit.add(new THREE.AmbientLight(0xffffff, 0.6));
  const sun = new THREE.DirectionalLight(0xffffff, 2.2);
  sun.position.set(3, 5, 4);
  lit.add(sun, scene);
  renderer.render(lit, camera);
  const gl = renderer.getContext();
  const px = new Uint8Array(SIZE * SIZE * 4);
  gl.readPixels(0, 0, SIZE, SIZE, gl.RGBA, gl.UNSIGNED_BYTE, px);
  return px;
}

// a against b: mean absolute difference (0..255, over RGB) and the share of
// pixels where some channel differs by more than 32.
function compare(a, b) {
  let sum = 0, off = 0;
  for (let i = 0; i < a.length; i += 4) {
    let worst = 0;
    for (let k = 0; k < 3; ++k) { const d = Math.abs(a[i + k] - b[i + k]); sum += d; worst = Math.max(worst, d); }
    if (worst > 32) off++;
  }
  const pixels = a.length / 4;
  // drawn: the share of b's pixels that are not the background (an empty picture matches nothing)
  let drawn = 0;
  for (let i = 0; i < b.length; i += 4) if (b[i] !== 0x30 || b[i + 1] !== 0x34 || b[i + 2] !== 0x3a) drawn++;
  return { meanAbs: sum / (3 * pixels), over32: off / pixels, pixels, drawn: drawn / pixels };
}

async function main() {
  let urls = [params.get('a'), params.get('b')].filter(Boolean);
  if (!urls.length) {
    const index = await (await fetch('/data/gltf/index.json')).json().catch(() => []);
    const pick = document.getElementById('asset');
    for (const x of index) pick.add(new Option(x.name, x.name));
    pick.onchange = () => { location.search = `?a=${index[pick.selectedIndex].compressed}&b=${index[pick.selectedIndex].original}`; };
    if (!index.length) throw new Error('no /data/gltf/index.json: run web/test.sh (or web/prepare-gltf.sh)');
    urls = [index[0].compressed, index[0].original];
  }
  let camera = null;
  const pixels = [];
  for (const url of urls) {
    const t0 = performance.now();
    const gltf = await loader().loadAsync(url);
    const loadMs = performance.now() - t0;
    // Animated assets are drawn 0.7 s into their first clip: a posed skin shows its joints and weights.
    if (gltf.animations.length) {
      const mixer = new THREE.AnimationMixer(gltf.scene);
      mixer.clipAction(gltf.animations[0]).play();
      mixer.update(Number(params.get('t') || 0.7));
    }
    camera = camera || cameraFor(gltf.scene);
    const meshes = describe(gltf.scene);
    const v = meshes.reduce((s, m) => s + m.vertexCount, 0), t = meshes.reduce((s, m) => s + (m.indexCount || m.vertexCount) / 3, 0);
    pixels.push(render(gltf.scene, camera, `${url.split('/').pop()}\n${v.toLocaleString()} vertices, ` +
      `${t.toLocaleString()} triangles, loaded in ${loadMs.toFixed(1)} ms`));
    state.views.push({ url, loadMs, meshes });
  }
  if (pixels.length === 2) state.diff = compare(pixels[0], pixels[1]);
  state.state = 'done';
}

main().catch((e) => {
  state.state = 'error';
  state.error = String(e && e.stack || e);
  const p = document.createElement('pre');
  p.className = 'err';
  p.textContent = state.error;
  document.body.append(p);
});
