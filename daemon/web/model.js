// model.js — a model as the viewer draws it: FMB1 parsed (the daemon's
// binary model: "FMB1", u32 vertices, u32 facets, vertices 3×f64, per
// facet u16 n, plane 4×f64, n×u32 indices, little-endian), its facets
// triangulated, and what the colour layers need per facet (area, normal,
// inverted, free edges), all in typed arrays so that 10^6 triangles stay
// a few hundred milliseconds and a few tens of MB.
//
// Positions are float32 relative to the model's centre, which keeps µm
// detail of a stone far from the origin.

export function parseFmb1(buf) {
  const dv = new DataView(buf);
  const magic = String.fromCharCode(dv.getUint8(0), dv.getUint8(1),
                                    dv.getUint8(2), dv.getUint8(3));
  if (buf.byteLength < 12 || magic !== 'FMB1')
    throw new Error('model: not FMB1');
  const nv = dv.getUint32(4, true), nf = dv.getUint32(8, true);
  let o = 12;
  const verts = new Float64Array(3 * nv);
  for (let i = 0; i < 3 * nv; i++, o += 8) verts[i] = dv.getFloat64(o, true);
  // first pass: corner count (the daemon checked every length)
  let nc = 0;
  for (let f = 0, p = o; f < nf; f++) {
    const n = dv.getUint16(p, true);
    nc += n;
    p += 34 + 4 * n;
  }
  const fstart = new Uint32Array(nf + 1), fidx = new Uint32Array(nc);
  const planes = new Float64Array(4 * nf);
  let c = 0;
  for (let f = 0; f < nf; f++) {
    const n = dv.getUint16(o, true);
    o += 2;
    for (let k = 0; k < 4; k++, o += 8) planes[4 * f + k] = dv.getFloat64(o, true);
    fstart[f] = c;
    for (let k = 0; k < n; k++, o += 4) fidx[c++] = dv.getUint32(o, true);
  }
  fstart[nf] = c;
  return { nv, nf, verts, fstart, fidx, planes };
}

// An open-addressing set of undirected edges (u, v) counting corners.
function edgeCounts(m) {
  const nc = m.fidx.length;
  let size = 1;
  while (size < 2 * nc) size <<= 1;
  const ka = new Int32Array(size).fill(-1), kb = new Int32Array(size);
  const cnt = new Uint8Array(size);
  const slotOf = new Uint32Array(nc); // corner → its edge's slot
  const mask = size - 1;
  for (let f = 0; f < m.nf; f++) {
    const s = m.fstart[f], e = m.fstart[f + 1];
    for (let i = s; i < e; i++) {
      let a = m.fidx[i], b = m.fidx[i + 1 < e ? i + 1 : s];
      if (a > b) { const t = a; a = b; b = t; }
      let h = (Math.imul(a, 0x9e3779b1) ^ Math.imul(b, 0x85ebca77)) & mask;
      while (ka[h] !== -1 && (ka[h] !== a || kb[h] !== b)) h = (h + 1) & mask;
      if (ka[h] === -1) { ka[h] = a; kb[h] = b; }
      if (cnt[h] < 255) cnt[h]++;
      slotOf[i] = h;
    }
  }
  return { cnt, slotOf };
}

// Newell normal (not unit; its length is twice the area) of facet f.
function newell(m, f, out) {
  const s = m.fstart[f], e = m.fstart[f + 1], V = m.verts;
  let x = 0, y = 0, z = 0;
  for (let i = s; i < e; i++) {
    const a = 3 * m.fidx[i], b = 3 * m.fidx[i + 1 < e ? i + 1 : s];
    x += (V[a + 1] - V[b + 1]) * (V[a + 2] + V[b + 2]);
    y += (V[a + 2] - V[b + 2]) * (V[a] + V[b]);
    z += (V[a] - V[b]) * (V[a + 1] + V[b + 1]);
  }
  out[0] = x; out[1] = y; out[2] = z;
}

// Triangles of facet f (corner offsets from fstart[f]) to pushTri, by ear
// clipping in the facet's plane: a fan would fold a non-convex facet.
function triangulate(m, f, nrm, unused, pushTri) {
  const s = m.fstart[f], n = m.fstart[f + 1] - s, V = m.verts;
  if (n === 3) { pushTri(0, 1, 2); return; }
  // drop the normal's largest axis: a 2-D polygon with the same winding
  const ax = Math.abs(nrm[0]), ay = Math.abs(nrm[1]), az = Math.abs(nrm[2]);
  let u = 0, v = 1, sign = nrm[2];
  if (ax >= ay && ax >= az) { u = 1; v = 2; sign = nrm[0]; }
  else if (ay >= az) { u = 2; v = 0; sign = nrm[1]; }
  const px = new Float64Array(n), py = new Float64Array(n);
  for (let k = 0; k < n; k++) {
    const b = 3 * m.fidx[s + k];
    px[k] = V[b + u]; py[k] = sign < 0 ? -V[b + v] : V[b + v];
  }
  const idx = [];
  for (let k = 0; k < n; k++) idx.push(k);
  const cross = (a, b, c) =>
    (px[b] - px[a]) * (py[c] - py[a]) - (py[b] - py[a]) * (px[c] - px[a]);
  let guard = 0;
  while (idx.length > 3 && guard++ < 4 * n * n) {
    const L = idx.length;
    let cut = -1;
    for (let i = 0; i < L && cut < 0; i++) {
      const a = idx[(i + L - 1) % L], b = idx[i], c = idx[(i + 1) % L];
      if (cross(a, b, c) <= 0) continue; // reflex or flat corner
      let inside = false;
      for (let j = 0; j < L && !inside; j++) {
        const q = idx[j];
        if (q === a || q === b || q === c) continue;
        inside = cross(a, b, q) >= 0 && cross(b, c, q) >= 0 && cross(c, a, q) >= 0;
      }
      if (!inside) cut = i;
    }
    if (cut < 0) break; // degenerate polygon: fan the rest
    const L2 = idx.length;
    pushTri(idx[(cut + L2 - 1) % L2], idx[cut], idx[(cut + 1) % L2]);
    idx.splice(cut, 1);
  }
  for (let k = 1; k + 1 < idx.length; k++) pushTri(idx[0], idx[k], idx[k + 1]);
}

// Everything the renderer and the layers need, from a parsed model. The
// GPU gets the model's own vertices (shared: a triangle mesh of 10^6
// facets is 5·10^5 vertices, not 3·10^6 corners); a facet's flat shade
// comes from screen-space derivatives and its colour from the layer that
// draws it, so nothing per corner is needed.
export function buildMesh(m) {
  const nc = m.fidx.length, V = m.verts;
  let lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < m.nv; i++)
    for (let k = 0; k < 3; k++) {
      const x = V[3 * i + k];
      if (x < lo[k]) lo[k] = x;
      if (x > hi[k]) hi[k] = x;
    }
  if (m.nv === 0) { lo = [0, 0, 0]; hi = [0, 0, 0]; }
  const centre = [0, 1, 2].map(k => (lo[k] + hi[k]) / 2);
  const pos = new Float32Array(3 * m.nv);
  let r2 = 0; // the bounding sphere about the centre: what "fit" frames
  for (let i = 0; i < m.nv; i++) {
    for (let k = 0; k < 3; k++) pos[3 * i + k] = V[3 * i + k] - centre[k];
    r2 = Math.max(r2, pos[3 * i] ** 2 + pos[3 * i + 1] ** 2 + pos[3 * i + 2] ** 2);
  }
  const radius = Math.max(1e-9, Math.sqrt(r2));
  // per facet: unit normal, area, inverted (winding against its plane)
  const normal = new Float32Array(3 * m.nf), area = new Float64Array(m.nf);
  const inverted = [];
  const ntri = nc - 2 * m.nf;
  const tris = new Uint32Array(3 * ntri), triFacet = new Uint32Array(ntri);
  let nt = 0, f = 0, base = 0;
  const pushTri = (a, b, c) => {
    tris[3 * nt] = m.fidx[base + a]; tris[3 * nt + 1] = m.fidx[base + b];
    tris[3 * nt + 2] = m.fidx[base + c];
    triFacet[nt++] = f;
  };
  const nrm = [0, 0, 0], P = m.planes;
  for (f = 0; f < m.nf; f++) {
    newell(m, f, nrm);
    const len = Math.hypot(nrm[0], nrm[1], nrm[2]);
    area[f] = len / 2;
    if (len > 0)
      for (let k = 0; k < 3; k++) normal[3 * f + k] = nrm[k] / len;
    if (nrm[0] * P[4 * f] + nrm[1] * P[4 * f + 1] + nrm[2] * P[4 * f + 2] < 0)
      inverted.push(f);
    base = m.fstart[f];
    if (m.fstart[f + 1] - base === 3) pushTri(0, 1, 2);
    else triangulate(m, f, nrm, null, pushTri);
  }
  // facet edges once each (the facet with u < v draws a shared edge),
  // free edges (one facet: a hole's border)
  const { cnt, slotOf } = edgeCounts(m);
  const lines = new Uint32Array(2 * nc);
  let nl = 0, nfree = 0;
  for (let i = 0; i < nc; i++) if (cnt[slotOf[i]] === 1) nfree++;
  const free = new Uint32Array(2 * nfree);
  nfree = 0;
  for (let g = 0; g < m.nf; g++) {
    const s = m.fstart[g], e = m.fstart[g + 1];
    for (let i = s; i < e; i++) {
      const a = m.fidx[i], b = m.fidx[i + 1 < e ? i + 1 : s], c = cnt[slotOf[i]];
      if (c === 1) { free[nfree++] = a; free[nfree++] = b; }
      if (c !== 2 || a < b) { lines[nl++] = a; lines[nl++] = b; }
    }
  }
  return {
    model: m, pos, tris: tris.subarray(0, 3 * nt), triFacet, ntris: nt,
    lines: lines.slice(0, nl), free, normal, area, inverted, centre, radius,
  };
}

// Index buffers of facets grouped by key(f) (a non-negative integer, or
// -1 for none), in one pass: a colour layer per key.
export function keyedTris(mesh, key) {
  const counts = new Map();
  const keys = new Int32Array(mesh.model.nf);
  for (let f = 0; f < keys.length; f++) keys[f] = key(f);
  for (let t = 0; t < mesh.ntris; t++) {
    const k = keys[mesh.triFacet[t]];
    if (k >= 0) counts.set(k, (counts.get(k) || 0) + 1);
  }
  const out = new Map(), fill = new Map();
  for (const [k, n] of counts) { out.set(k, new Uint32Array(3 * n)); fill.set(k, 0); }
  for (let t = 0; t < mesh.ntris; t++) {
    const k = keys[mesh.triFacet[t]];
    if (k < 0) continue;
    const a = out.get(k);
    let o = fill.get(k);
    a[o++] = mesh.tris[3 * t]; a[o++] = mesh.tris[3 * t + 1]; a[o++] = mesh.tris[3 * t + 2];
    fill.set(k, o);
  }
  return out;
}

// The triangles of a set of facets (an index buffer for one layer).
export function facetTris(mesh, facets) {
  const want = new Uint8Array(mesh.model.nf);
  for (const f of facets) if (f >= 0 && f < want.length) want[f] = 1;
  let n = 0;
  for (let t = 0; t < mesh.ntris; t++) n += want[mesh.triFacet[t]];
  const out = new Uint32Array(3 * n);
  for (let t = 0, o = 0; t < mesh.ntris; t++)
    if (want[mesh.triFacet[t]]) {
      out[o++] = mesh.tris[3 * t];
      out[o++] = mesh.tris[3 * t + 1];
      out[o++] = mesh.tris[3 * t + 2];
    }
  return out;
}

// Inclination, azimuth and gear index of facet f without a report: the
// axis is the normal of the largest facet (a stone's table); azimuth is
// measured in the table plane from the model's x axis projected into it.
export function facetAngles(mesh, f, gear = 96) {
  if (mesh.table === undefined) {
    let best = 0;
    for (let g = 1; g < mesh.model.nf; g++) if (mesh.area[g] > mesh.area[best]) best = g;
    mesh.table = best;
  }
  const N = mesh.normal, t = 3 * mesh.table;
  const ax = [N[t], N[t + 1], N[t + 2]], n = [N[3 * f], N[3 * f + 1], N[3 * f + 2]];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  // the angle between the facet's plane and the table's: 0–90°, crown
  // and pavilion alike, as a cutter states it
  const incl = Math.acos(Math.min(1, Math.abs(dot(n, ax)))) * 180 / Math.PI;
  let ref = Math.abs(ax[0]) < 0.9 ? [1, 0, 0] : [0, 1, 0];
  const d = dot(ref, ax);
  ref = [ref[0] - d * ax[0], ref[1] - d * ax[1], ref[2] - d * ax[2]];
  const rl = Math.hypot(...ref);
  ref = ref.map(x => x / rl);
  const side = [ax[1] * ref[2] - ax[2] * ref[1], ax[2] * ref[0] - ax[0] * ref[2],
                ax[0] * ref[1] - ax[1] * ref[0]];
  let az = Math.atan2(dot(n, side), dot(n, ref)) * 180 / Math.PI;
  if (az < 0) az += 360;
  const flat = Math.hypot(dot(n, side), dot(n, ref)) < 1e-9;
  return { inclination_deg: incl, azimuth_deg: flat ? null : az,
           index: flat ? null : az / 360 * gear, area_mm2: mesh.area[f] };
}
