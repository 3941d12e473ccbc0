// A small WebGL2 renderer for a mesh that arrives in pieces: vertex and index
// buffers grow on the GPU (copyBufferSubData, no CPU copy of what is there),
// each piece is appended with bufferSubData. Flat shading from screen-space
// derivatives (no normals needed); each vertex is coloured by the segment
// that brought it, so the pieces show as they arrive.
const VS = `#version 300 es
in vec3 pos; in float seg;
uniform mat4 mvp; out vec3 vPos; out float vSeg;
void main() { vPos = pos; vSeg = seg; gl_Position = mvp * vec4(pos, 1.0); }`;
const FS = `#version 300 es
precision highp float;
in vec3 vPos; in float vSeg; uniform vec3 light; out vec4 color;
vec3 hue(float h) { return clamp(abs(mod(h * 6.0 + vec3(0, 4, 2), 6.0) - 3.0) - 1.0, 0.0, 1.0); }
void main() {
  vec3 n = normalize(cross(dFdx(vPos), dFdy(vPos)));
  float d = abs(dot(n, light));
  vec3 base = mix(vec3(0.85), hue(fract(vSeg * 0.618034)), 0.45);
  color = vec4(base * (0.25 + 0.75 * d), 1.0);
}`;

class GrowBuffer {
  constructor(gl, target, bytesPerItem) {
    this.gl = gl; this.target = target; this.bpi = bytesPerItem;
    this.buf = gl.createBuffer(); this.cap = 0; this.count = 0;
  }
  append(data, itemCount) {
    // Each buffer is bound to its own target first: WebGL2 fixes a buffer's
    // type (index or other data) at its first binding.
    const gl = this.gl;
    gl.bindVertexArray(null);
    if (this.count + itemCount > this.cap) {
      const cap = Math.max(this.count + itemCount, this.cap * 2, 4096);
      const nb = gl.createBuffer();
      gl.bindBuffer(this.target, nb);
      gl.bufferData(this.target, cap * this.bpi, gl.DYNAMIC_DRAW);
      if (this.count) {
        gl.bindBuffer(gl.COPY_READ_BUFFER, this.buf);
        gl.copyBufferSubData(gl.COPY_READ_BUFFER, this.target, 0, 0, this.count * this.bpi);
        gl.bindBuffer(gl.COPY_READ_BUFFER, null);
      }
      gl.deleteBuffer(this.buf);
      this.buf = nb; this.cap = cap;
    }
    gl.bindBuffer(this.target, this.buf);
    gl.bufferSubData(this.target, this.count * this.bpi, data);
    this.count += itemCount;
  }
}

export class MeshView {
  constructor(canvas) {
    const gl = canvas.getContext('webgl2', { antialias: true, preserveDrawingBuffer: true });
    if (!gl) throw new Error('WebGL2 is not available');
    this.gl = gl; this.canvas = canvas;
    this.prog = program(gl, VS, FS);
    this.loc = { pos: gl.getAttribLocation(this.prog, 'pos'), seg: gl.getAttribLocation(this.prog, 'seg'),
      mvp: gl.getUniformLocation(this.prog, 'mvp'), light: gl.getUniformLocation(this.prog, 'light') };
    this.yaw = 0.6; this.pitch = 0.25;
    this.clear();
    let drag = null;
    canvas.addEventListener('pointerdown', (e) => { drag = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
    canvas.addEventListener('pointerup', () => { drag = null; });
    canvas.addEventListener('pointermove', (e) => {
      if (!drag) return;
      this.yaw += (e.clientX - drag[0]) * 0.01; this.pitch += (e.clientY - drag[1]) * 0.01;
      this.pitch = Math.max(-1.5, Math.min(1.5, this.pitch));
      drag = [e.clientX, e.clientY]; this.requestDraw();
    });
    window.addEventListener('resize', () => this.requestDraw());
  }

  clear() {
    const gl = this.gl;
    for (const b of [this.pos, this.seg, this.idx]) if (b) gl.deleteBuffer(b.buf);
    this.pos = new GrowBuffer(gl, gl.ARRAY_BUFFER, 12);
    this.seg = new GrowBuffer(gl, gl.ARRAY_BUFFER, 4);
    this.idx = new GrowBuffer(gl, gl.ELEMENT_ARRAY_BUFFER, 4);
    this.vao = null;
    this.min = [Infinity, Infinity, Infinity]; this.max = [-Infinity, -Infinity, -Infinity];
    this.requestDraw();
  }

  /** Appends a decoded piece: { positions, indices, faceOffsets?, cornerStart, index }. */
  add(piece) {
    const p = piece.positions;
    const nv = p.length / 3;
    if (nv) {
      this.pos.append(p, nv);
      this.seg.append(new Float32Array(nv).fill(piece.index || 0), nv);
      for (let i = 0; i < p.length; i += 3)
        for (let k = 0; k < 3; ++k) {
          const x = p[i + k];
          if (x < this.min[k]) this.min[k] = x;
          if (x > this.max[k]) this.max[k] = x;
        }
    }
    const tris = piece.faceOffsets ? fanTriangulate(piece) : piece.indices;
    if (tris.length) this.idx.append(tris, tris.length);
    this.vao = null; // buffers may have been replaced
    this.requestDraw();
  }

  requestDraw() {
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame(() => { this.pending = false; this.draw(); });
  }

  draw() {
    const gl = this.gl, c = this.canvas;
    const w = c.clientWidth * devicePixelRatio | 0, h = c.clientHeight * devicePixelRatio | 0;
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
    gl.viewport(0, 0, w, h);
    gl.clearColor(0.11, 0.12, 0.13, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    if (!this.idx.count) return;
    if (!this.vao) {
      this.vao = gl.createVertexArray();
      gl.bindVertexArray(this.vao);
      gl.bindBuffer(gl.ARRAY_BUFFER, this.pos.buf);
      gl.enableVertexAttribArray(this.loc.pos);
      gl.vertexAttribPointer(this.loc.pos, 3, gl.FLOAT, false, 0, 0);
      gl.bindBuffer(gl.ARRAY_BUFFER, this.seg.buf);
      gl.enableVertexAttribArray(this.loc.seg);
      gl.vertexAttribPointer(this.loc.seg, 1, gl.FLOAT, false, 0, 0);
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.idx.buf);
    }
    gl.bindVertexArray(this.vao);
    gl.useProgram(this.prog);
    gl.enable(gl.DEPTH_TEST);
    const center = [0, 1, 2].map((k) => (this.min[k] + this.max[k]) / 2);
    const radius = Math.max(1e-9, Math.hypot(...[0, 1, 2].map((k) => this.max[k] - this.min[k])) / 2);
    gl.uniformMatrix4fv(this.loc.mvp, false, viewProjection(center, radius, this.yaw, this.pitch, w / h));
    gl.uniform3fv(this.loc.light, normalize([0.4, 0.7, 0.6]));
    gl.drawElements(gl.TRIANGLES, this.idx.count, gl.UNSIGNED_INT, 0);
    gl.bindVertexArray(null);
  }
}

function fanTriangulate(piece) {
  const off = piece.faceOffsets, idx = piece.indices, base = piece.cornerStart;
  let n = 0;
  for (let f = 0; f + 1 < off.length; ++f) n += Math.max(0, off[f + 1] - off[f] - 2);
  const out = new Uint32Array(3 * n);
  let o = 0;
  for (let f = 0; f + 1 < off.length; ++f) {
    const a = off[f] - base, b = off[f + 1] - base;
    for (let k = a + 1; k + 1 < b; ++k) { out[o++] = idx[a]; out[o++] = idx[k]; out[o++] = idx[k + 1]; }
  }
  return out;
}

function program(gl, vs, fs) {
  const p = gl.createProgram();
  for (const [type, src] of [[gl.VERTEX_SHADER, vs], [gl.FRAGMENT_SHADER, fs]]) {
    const s = gl.createShader(type);
    gl.shaderSource(s, src); gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
    gl.attachShader(p, s);
  }
  gl.linkProgram(p);
  if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
  return p;
}

const normalize = (v) => { const l = Math.hypot(...v); return v.map((x) => x / l); };

// projection * view (column-major): orbit camera around center at 2.6 radii
function viewProjection(center, radius, yaw, pitch, aspect) {
  const dist = radius * 2.6;
  const eye = [center[0] + dist * Math.cos(pitch) * Math.sin(yaw), center[1] + dist * Math.sin(pitch),
    center[2] + dist * Math.cos(pitch) * Math.cos(yaw)];
  const f = normalize([center[0] - eye[0], center[1] - eye[1], center[2] - eye[2]]);
  const s = normalize([f[1] * 0 - f[2] * 1, f[2] * 0 - f[0] * 0, f[0] * 1 - f[1] * 0]);
  const u = [s[1] * f[2] - s[2] * f[1], s[2] * f[0] - s[0] * f[2], s[0] * f[1] - s[1] * f[0]];
  const view = [s[0], u[0], -f[0], 0, s[1], u[1], -f[1], 0, s[2], u[2], -f[2], 0,
    -(s[0] * eye[0] + s[1] * eye[1] + s[2] * eye[2]), -(u[0] * eye[0] + u[1] * eye[1] + u[2] * eye[2]),
    f[0] * eye[0] + f[1] * eye[1] + f[2] * eye[2], 1];
  const near = dist - radius * 1.5 > 0 ? Math.max(dist - radius * 1.5, radius * 0.01) : radius * 0.01;
  const far = dist + radius * 1.5;
  const t = 1 / Math.tan(0.4);
  const proj = [t / aspect, 0, 0, 0, 0, t, 0, 0, 0, 0, (far + near) / (near - far), -1, 0, 0, 2 * far * near / (near - far), 0];
  const out = new Float32Array(16);
  for (let c = 0; c < 4; ++c)
    for (let r = 0; r < 4; ++r) {
      let acc = 0;
      for (let k = 0; k < 4; ++k) acc += proj[k * 4 + r] * view[c * 4 + k];
      out[c * 4 + r] = acc;
    }
  return out;
}
