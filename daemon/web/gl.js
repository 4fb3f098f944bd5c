// gl.js — the WebGL 2 view: an orbit camera (drag: orbit, right or
// shift drag: pan, wheel: zoom, fit), meshes as indexed triangle buffers
// over the model's shared vertices with flat shading from screen-space
// derivatives (no normal or colour attribute), and layers each drawn in
// one call: the surface in its colour, then colour layers (a subset of
// triangles in one colour: a merged group, a tier, the self-intersecting
// facets), then lines (facet edges, free edges). Frames are drawn on
// demand, not in a loop. While the camera moves, a mesh of more than
// LOD_MIN triangles is drawn as a coarse copy (vertex clustering) at a
// lower resolution, and in full again once it stops: what keeps 10^6
// triangles interactive on a software renderer.

const VS = `#version 300 es
in vec3 a_pos;
uniform mat4 u_mvp, u_mv;
out vec3 v_view;
void main() {
  v_view = (u_mv * vec4(a_pos, 1.0)).xyz;
  gl_Position = u_mvp * vec4(a_pos, 1.0);
}`;
const FS = `#version 300 es
precision highp float;
in vec3 v_view;
uniform vec4 u_col;     // the layer's colour
uniform int u_mode;     // 1 lit (surfaces), 2 unlit (lines)
out vec4 o;
void main() {
  vec4 c = u_col;
  if (u_mode == 2) { o = c; return; }
  vec3 n = normalize(cross(dFdx(v_view), dFdy(v_view)));
  // a key light above the camera, both sides lit (an open mesh's inside)
  float l = 0.32 + 0.68 * abs(dot(n, normalize(vec3(0.25, 0.45, 1.0))));
  o = vec4(c.rgb * l, c.a);
}`;

const LOD_MIN = 150000;     // triangles above which motion draws a coarse copy
const LOD_TRIS = 25000;     // about what the coarse copy keeps
const LOD_SCALE = 0.5;      // resolution while moving, for such meshes
const SETTLE_MS = 150;      // no input this long: the camera has stopped

// A coarse copy of a mesh: every vertex moved to the first vertex of its
// cell in a G³ grid over the mesh's box, the triangles that collapse
// dropped (vertex clustering, Rossignac & Borrel 1993), O(n). It has its
// own compact vertex array: a software renderer transforms every vertex
// of the range an indexed draw spans. G shrinks until about `want`
// triangles remain. Returns {pos: Float32Array, tris: Uint32Array}.
export function coarseMesh(pos, tris, want = LOD_TRIS) {
  const nv = pos.length / 3;
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < nv; i++)
    for (let k = 0; k < 3; k++) {
      const x = pos[3 * i + k];
      if (x < lo[k]) lo[k] = x;
      if (x > hi[k]) hi[k] = x;
    }
  const ext = Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) || 1;
  // a closed surface over a G³ grid keeps about 4·G² triangles
  let g = Math.max(8, Math.min(1024, Math.round(Math.sqrt(want / 4))));
  for (;;) {
    const rep = new Int32Array(nv), cells = new Map(), keep = [];
    for (let i = 0; i < nv; i++) {
      const c = [0, 1, 2].map(k => Math.min(g - 1, Math.floor((pos[3 * i + k] - lo[k]) / ext * g)));
      const key = (c[0] * g + c[1]) * g + c[2];
      let r = cells.get(key);
      if (r === undefined) { r = keep.length; keep.push(i); cells.set(key, r); }
      rep[i] = r;
    }
    const out = new Uint32Array(tris.length);
    let n = 0;
    for (let t = 0; t < tris.length; t += 3) {
      const a = rep[tris[t]], b = rep[tris[t + 1]], c = rep[tris[t + 2]];
      if (a === b || b === c || a === c) continue;
      out[n++] = a; out[n++] = b; out[n++] = c;
    }
    if (n / 3 <= 1.5 * want || g <= 8) {
      const cp = new Float32Array(3 * keep.length);
      keep.forEach((v, i) => { cp[3 * i] = pos[3 * v]; cp[3 * i + 1] = pos[3 * v + 1]; cp[3 * i + 2] = pos[3 * v + 2]; });
      return { pos: cp, tris: out.slice(0, n) };
    }
    g = Math.max(8, Math.floor(g / Math.sqrt(n / 3 / want)));
  }
}

// column-major 4×4 matrices
function mul(a, b) {
  const o = new Float32Array(16);
  for (let c = 0; c < 4; c++)
    for (let r = 0; r < 4; r++) {
      let s = 0;
      for (let k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
      o[c * 4 + r] = s;
    }
  return o;
}
function invert(m) {
  const inv = new Float64Array(16);
  const a = m;
  inv[0] = a[5]*a[10]*a[15]-a[5]*a[11]*a[14]-a[9]*a[6]*a[15]+a[9]*a[7]*a[14]+a[13]*a[6]*a[11]-a[13]*a[7]*a[10];
  inv[4] = -a[4]*a[10]*a[15]+a[4]*a[11]*a[14]+a[8]*a[6]*a[15]-a[8]*a[7]*a[14]-a[12]*a[6]*a[11]+a[12]*a[7]*a[10];
  inv[8] = a[4]*a[9]*a[15]-a[4]*a[11]*a[13]-a[8]*a[5]*a[15]+a[8]*a[7]*a[13]+a[12]*a[5]*a[11]-a[12]*a[7]*a[9];
  inv[12] = -a[4]*a[9]*a[14]+a[4]*a[10]*a[13]+a[8]*a[5]*a[14]-a[8]*a[6]*a[13]-a[12]*a[5]*a[10]+a[12]*a[6]*a[9];
  inv[1] = -a[1]*a[10]*a[15]+a[1]*a[11]*a[14]+a[9]*a[2]*a[15]-a[9]*a[3]*a[14]-a[13]*a[2]*a[11]+a[13]*a[3]*a[10];
  inv[5] = a[0]*a[10]*a[15]-a[0]*a[11]*a[14]-a[8]*a[2]*a[15]+a[8]*a[3]*a[14]+a[12]*a[2]*a[11]-a[12]*a[3]*a[10];
  inv[9] = -a[0]*a[9]*a[15]+a[0]*a[11]*a[13]+a[8]*a[1]*a[15]-a[8]*a[3]*a[13]-a[12]*a[1]*a[11]+a[12]*a[3]*a[9];
  inv[13] = a[0]*a[9]*a[14]-a[0]*a[10]*a[13]-a[8]*a[1]*a[14]+a[8]*a[2]*a[13]+a[12]*a[1]*a[10]-a[12]*a[2]*a[9];
  inv[2] = a[1]*a[6]*a[15]-a[1]*a[7]*a[14]-a[5]*a[2]*a[15]+a[5]*a[3]*a[14]+a[13]*a[2]*a[7]-a[13]*a[3]*a[6];
  inv[6] = -a[0]*a[6]*a[15]+a[0]*a[7]*a[14]+a[4]*a[2]*a[15]-a[4]*a[3]*a[14]-a[12]*a[2]*a[7]+a[12]*a[3]*a[6];
  inv[10] = a[0]*a[5]*a[15]-a[0]*a[7]*a[13]-a[4]*a[1]*a[15]+a[4]*a[3]*a[13]+a[12]*a[1]*a[7]-a[12]*a[3]*a[5];
  inv[14] = -a[0]*a[5]*a[14]+a[0]*a[6]*a[13]+a[4]*a[1]*a[14]-a[4]*a[2]*a[13]-a[12]*a[1]*a[6]+a[12]*a[2]*a[5];
  inv[3] = -a[1]*a[6]*a[11]+a[1]*a[7]*a[10]+a[5]*a[2]*a[11]-a[5]*a[3]*a[10]-a[9]*a[2]*a[7]+a[9]*a[3]*a[6];
  inv[7] = a[0]*a[6]*a[11]-a[0]*a[7]*a[10]-a[4]*a[2]*a[11]+a[4]*a[3]*a[10]+a[8]*a[2]*a[7]-a[8]*a[3]*a[6];
  inv[11] = -a[0]*a[5]*a[11]+a[0]*a[7]*a[9]+a[4]*a[1]*a[11]-a[4]*a[3]*a[9]-a[8]*a[1]*a[7]+a[8]*a[3]*a[5];
  inv[15] = a[0]*a[5]*a[10]-a[0]*a[6]*a[9]-a[4]*a[1]*a[10]+a[4]*a[2]*a[9]+a[8]*a[1]*a[6]-a[8]*a[2]*a[5];
  const det = a[0] * inv[0] + a[1] * inv[4] + a[2] * inv[8] + a[3] * inv[12];
  for (let i = 0; i < 16; i++) inv[i] /= det;
  return inv;
}

export class View {
  // antialias: multisampling, which a software renderer pays for on
  // every frame; worth it for a stone, not for 10^6 triangles.
  constructor(canvas, onPick, antialias = true) {
    this.canvas = canvas;
    const gl = canvas.getContext('webgl2', { antialias, preserveDrawingBuffer: false });
    if (!gl) throw new Error('this browser has no WebGL 2');
    this.gl = gl;
    this.prog = this.program(VS, FS);
    this.loc = {
      pos: gl.getAttribLocation(this.prog, 'a_pos'),
      mvp: gl.getUniformLocation(this.prog, 'u_mvp'),
      mv: gl.getUniformLocation(this.prog, 'u_mv'),
      ucol: gl.getUniformLocation(this.prog, 'u_col'),
      mode: gl.getUniformLocation(this.prog, 'u_mode'),
    };
    this.meshes = [];     // {mesh, vao, pb, tb, ntri, color, layers}
    this.yaw = 0.6; this.pitch = 0.5; this.dist = 3; this.target = [0, 0, 0];
    this.radius = 1;
    this.frames = 0;
    this.onFrame = null;
    this.onPick = onPick;
    this.pending = false;
    this.moving = false;  // the camera is moving: coarse copies, lower resolution
    this.settle = 0;
    this.input(canvas);
    new ResizeObserver(() => this.redraw()).observe(canvas);
  }

  program(vs, fs) {
    const gl = this.gl;
    const sh = (type, src) => {
      const s = gl.createShader(type);
      gl.shaderSource(s, src);
      gl.compileShader(s);
      if (!gl.getShaderParameter(s, gl.COMPILE_STATUS))
        throw new Error('shader: ' + gl.getShaderInfoLog(s));
      return s;
    };
    const p = gl.createProgram();
    gl.attachShader(p, sh(gl.VERTEX_SHADER, vs));
    gl.attachShader(p, sh(gl.FRAGMENT_SHADER, fs));
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS))
      throw new Error('program: ' + gl.getProgramInfoLog(p));
    return p;
  }

  // Replaces the meshes drawn. Each entry: {mesh, color: [r, g, b, a]}
  // (a < 1: translucent, drawn without depth writes); returns handles
  // for setLayers.
  setMeshes(list) {
    for (const h of this.meshes) this.release(h);
    this.meshes = list.map(e => {
      const { vao, pb, tb } = this.buffers(e.mesh);
      let coarse = null;
      if (e.mesh.tris.length / 3 > LOD_MIN) {
        const cm = e.mesh.coarse || (e.mesh.coarse = coarseMesh(e.mesh.pos, e.mesh.tris));
        coarse = this.buffers(cm);
      }
      return { mesh: e.mesh, vao, pb, tb, ntri: e.mesh.tris.length, coarse,
               color: e.color, layers: [] };
    });
    this.redraw();
    return this.meshes;
  }

  // A VAO with its own vertex and index buffers: {vao, pb, tb, ntri}.
  buffers(m) {
    const gl = this.gl;
    const vao = gl.createVertexArray();
    gl.bindVertexArray(vao);
    const pb = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, pb);
    gl.bufferData(gl.ARRAY_BUFFER, m.pos, gl.STATIC_DRAW);
    gl.enableVertexAttribArray(this.loc.pos);
    gl.vertexAttribPointer(this.loc.pos, 3, gl.FLOAT, false, 0, 0);
    const tb = gl.createBuffer();
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, tb);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, m.tris, gl.STATIC_DRAW);
    gl.bindVertexArray(null);
    return { vao, pb, tb, ntri: m.tris.length };
  }

  release(h) {
    const gl = this.gl;
    for (const l of h.layers) gl.deleteBuffer(l.buf);
    for (const b of h.coarse ? [h, h.coarse] : [h]) {
      gl.deleteBuffer(b.pb); gl.deleteBuffer(b.tb);
      gl.deleteVertexArray(b.vao);
    }
  }

  // Layers of h: [{kind: 'tris'|'lines', index: Uint32Array, color: [r,g,b,a]}]
  setLayers(h, layers) {
    const gl = this.gl;
    for (const l of h.layers) gl.deleteBuffer(l.buf);
    gl.bindVertexArray(h.vao);
    h.layers = layers.filter(l => l.index.length > 0).map(l => {
      const buf = gl.createBuffer();
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, buf);
      gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, l.index, gl.STATIC_DRAW);
      return { kind: l.kind, buf, n: l.index.length, color: l.color };
    });
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, h.tb); // the VAO's own triangles
    gl.bindVertexArray(null);
    this.redraw();
  }

  fit(radius) {
    if (radius) this.radius = radius;
    this.target = [0, 0, 0];
    this.dist = this.radius / Math.sin(this.fov() / 2) * 1.02;
    this.redraw();
  }
  fov() { return 35 * Math.PI / 180; }

  matrices() {
    const c = this.canvas, w = c.width, h = c.height;
    const cy = Math.cos(this.yaw), sy = Math.sin(this.yaw);
    const cp = Math.cos(this.pitch), sp = Math.sin(this.pitch);
    // the camera looks at target from yaw/pitch, z up
    const eye = [this.target[0] + this.dist * cp * cy, this.target[1] + this.dist * cp * sy,
                 this.target[2] + this.dist * sp];
    const f = [this.target[0] - eye[0], this.target[1] - eye[1], this.target[2] - eye[2]];
    const fl = Math.hypot(...f);
    for (let k = 0; k < 3; k++) f[k] /= fl;
    let s = [f[1] * 1 - f[2] * 0, f[2] * 0 - f[0] * 1, 0];
    const sl = Math.hypot(...s) || 1;
    s = s.map(x => x / sl);
    const u = [s[1] * f[2] - s[2] * f[1], s[2] * f[0] - s[0] * f[2], s[0] * f[1] - s[1] * f[0]];
    const view = new Float32Array([s[0], u[0], -f[0], 0, s[1], u[1], -f[1], 0, s[2], u[2], -f[2], 0,
      -(s[0] * eye[0] + s[1] * eye[1] + s[2] * eye[2]),
      -(u[0] * eye[0] + u[1] * eye[1] + u[2] * eye[2]),
      f[0] * eye[0] + f[1] * eye[1] + f[2] * eye[2], 1]);
    const near = Math.max(this.dist - 2 * this.radius, this.dist * 1e-3);
    const far = this.dist + 2 * this.radius;
    const t = 1 / Math.tan(this.fov() / 2), asp = w / Math.max(1, h);
    const proj = new Float32Array([t / asp, 0, 0, 0, 0, t, 0, 0, 0, 0, (far + near) / (near - far), -1,
                                   0, 0, 2 * far * near / (near - far), 0]);
    return { view, proj, mvp: mul(proj, view), s, u };
  }

  // The camera moved: coarse frames until SETTLE_MS pass without input,
  // then one full frame.
  moved() {
    this.moving = true;
    clearTimeout(this.settle);
    this.settle = setTimeout(() => { this.moving = false; this.redraw(); }, SETTLE_MS);
    this.redraw();
  }

  // Whether this frame is drawn coarse: moving, with a mesh that has a
  // coarse copy.
  coarse() { return this.moving && this.meshes.some(h => h.coarse); }

  redraw() {
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame(() => { this.pending = false; this.draw(); });
  }

  draw() {
    const gl = this.gl, c = this.canvas;
    const coarse = this.coarse();
    const dpr = (window.devicePixelRatio || 1) * (coarse ? LOD_SCALE : 1);
    const w = Math.max(1, Math.round(c.clientWidth * dpr)), h = Math.max(1, Math.round(c.clientHeight * dpr));
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
    gl.viewport(0, 0, w, h);
    gl.clearColor(0.97, 0.97, 0.98, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    gl.useProgram(this.prog);
    const { view, mvp } = this.matrices();
    gl.uniformMatrix4fv(this.loc.mvp, false, mvp);
    gl.uniformMatrix4fv(this.loc.mv, false, view);
    for (const h of this.meshes) {
      gl.bindVertexArray(h.vao);
      const translucent = h.color[3] < 1;
      if (translucent) {
        gl.enable(gl.BLEND);
        gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA);
        gl.depthMask(false);
      }
      // surfaces pushed back a little so that lines on them win
      gl.enable(gl.POLYGON_OFFSET_FILL);
      gl.polygonOffset(1, 1);
      gl.uniform1i(this.loc.mode, 1);
      gl.uniform4fv(this.loc.ucol, h.color);
      if (coarse && h.coarse) {
        // the shape only: layers and lines come back when it stops
        gl.bindVertexArray(h.coarse.vao);
        gl.drawElements(gl.TRIANGLES, h.coarse.ntri, gl.UNSIGNED_INT, 0);
        gl.disable(gl.POLYGON_OFFSET_FILL);
        if (translucent) { gl.disable(gl.BLEND); gl.depthMask(true); }
        continue;
      }
      gl.drawElements(gl.TRIANGLES, h.ntri, gl.UNSIGNED_INT, 0);
      gl.polygonOffset(0.5, 0.5);
      for (const l of h.layers) {
        if (l.kind !== 'tris') continue;
        gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, l.buf);
        gl.uniform1i(this.loc.mode, 1);
        gl.uniform4fv(this.loc.ucol, l.color);
        gl.drawElements(gl.TRIANGLES, l.n, gl.UNSIGNED_INT, 0);
      }
      gl.disable(gl.POLYGON_OFFSET_FILL);
      for (const l of h.layers) {
        if (l.kind !== 'lines') continue;
        gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, l.buf);
        gl.uniform1i(this.loc.mode, 2);
        gl.uniform4fv(this.loc.ucol, l.color);
        gl.drawElements(gl.LINES, l.n, gl.UNSIGNED_INT, 0);
      }
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, h.tb);
      if (translucent) { gl.disable(gl.BLEND); gl.depthMask(true); }
    }
    gl.bindVertexArray(null);
    this.frames++;
    if (this.onFrame) this.onFrame(this.frames);
  }

  // Spins the camera for ms and resolves with frames per second: as in
  // an orbit with the mouse (coarse frames for a large mesh), or with
  // full = true every frame drawn in full.
  spin(ms, full = false) {
    return new Promise(resolve => {
      const t0 = performance.now();
      let n = 0;
      this.moving = !full;
      const step = () => {
        const t = performance.now();
        if (t - t0 >= ms) {
          this.moving = false;
          this.redraw();
          resolve(n * 1000 / (t - t0));
          return;
        }
        this.yaw += 0.02;
        this.draw();
        n++;
        requestAnimationFrame(step);
      };
      requestAnimationFrame(step);
    });
  }

  input(c) {
    let drag = null;
    c.addEventListener('contextmenu', e => e.preventDefault());
    c.addEventListener('pointerdown', e => {
      drag = { x: e.clientX, y: e.clientY, moved: false,
               pan: e.button === 2 || e.shiftKey };
      c.setPointerCapture(e.pointerId);
    });
    c.addEventListener('pointermove', e => {
      if (!drag) return;
      const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
      if (Math.abs(dx) + Math.abs(dy) > 2) drag.moved = true;
      drag.x = e.clientX; drag.y = e.clientY;
      if (drag.pan) {
        const { s, u } = this.matrices();
        const k = 2 * this.dist * Math.tan(this.fov() / 2) / Math.max(1, c.clientHeight);
        for (let i = 0; i < 3; i++) this.target[i] += (-dx * s[i] + dy * u[i]) * k;
      } else {
        this.yaw -= dx * 0.01;
        this.pitch = Math.max(-1.55, Math.min(1.55, this.pitch + dy * 0.01));
      }
      this.moved();
    });
    c.addEventListener('pointerup', e => {
      if (drag && !drag.moved && e.button === 0 && this.onPick) {
        const r = c.getBoundingClientRect();
        this.onPick(this.pick(e.clientX - r.left, e.clientY - r.top));
      }
      drag = null;
    });
    c.addEventListener('wheel', e => {
      e.preventDefault();
      this.dist *= Math.exp(e.deltaY * 0.001);
      this.moved();
    }, { passive: false });
  }

  // The facet of the first mesh under canvas point (x, y) in CSS pixels,
  // by a ray cast over its triangles (Möller–Trumbore); -1 when none.
  pick(x, y) {
    const h = this.meshes[0];
    if (!h) return -1;
    const c = this.canvas;
    const { mvp } = this.matrices();
    const inv = invert(mvp);
    const nx = 2 * x / c.clientWidth - 1, ny = 1 - 2 * y / c.clientHeight;
    const un = (z) => {
      const v = [0, 1, 2, 3].map(r => inv[r] * nx + inv[4 + r] * ny + inv[8 + r] * z + inv[12 + r]);
      return [v[0] / v[3], v[1] / v[3], v[2] / v[3]];
    };
    const o = un(-1), e = un(1);
    const d = [e[0] - o[0], e[1] - o[1], e[2] - o[2]];
    const P = h.mesh.pos, T = h.mesh.tris;
    let best = Infinity, hit = -1;
    for (let t = 0; t < T.length; t += 3) {
      const a = 3 * T[t], b = 3 * T[t + 1], cc = 3 * T[t + 2];
      const e1x = P[b] - P[a], e1y = P[b + 1] - P[a + 1], e1z = P[b + 2] - P[a + 2];
      const e2x = P[cc] - P[a], e2y = P[cc + 1] - P[a + 1], e2z = P[cc + 2] - P[a + 2];
      const px = d[1] * e2z - d[2] * e2y, py = d[2] * e2x - d[0] * e2z, pz = d[0] * e2y - d[1] * e2x;
      const det = e1x * px + e1y * py + e1z * pz;
      if (Math.abs(det) < 1e-20) continue;
      const id = 1 / det;
      const tx = o[0] - P[a], ty = o[1] - P[a + 1], tz = o[2] - P[a + 2];
      const u = (tx * px + ty * py + tz * pz) * id;
      if (u < 0 || u > 1) continue;
      const qx = ty * e1z - tz * e1y, qy = tz * e1x - tx * e1z, qz = tx * e1y - ty * e1x;
      const v = (d[0] * qx + d[1] * qy + d[2] * qz) * id;
      if (v < 0 || u + v > 1) continue;
      const dist = (e2x * qx + e2y * qy + e2z * qz) * id;
      if (dist > 0 && dist < best) { best = dist; hit = h.mesh.triFacet[t / 3]; }
    }
    return hit;
  }
}
