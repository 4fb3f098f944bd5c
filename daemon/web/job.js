// job.js — #/jobs/{id}: one job. Its state (live over SSE until it
// ends), its numbers, the WebGL view of the result (or the input, or both
// overlaid) with colour layers, the facet under a click, downloads in
// every format and the statistics JSON.
//
// What a layer shows comes from the job's statistics where the daemon
// measured it (merge groups, self-intersecting pairs, report tiers), and
// is computed here from the model otherwise (inverted facets: winding
// against the facet's own plane; free edges: edges with one facet; the
// angles of a facet without a report). Facet indices in a report refer to
// the model that operation saw, so a layer is used only on the model with
// that many facets.
//
// Hash arguments: ?model=result|input|overlay and ?colour=plain|groups|
// tiers choose the first view (a link can show a job as it should be
// seen); ?bench=MS spins the camera for MS ms after the first frame and
// writes the frame rate into body[data-fps] (as while orbiting: a large
// mesh drawn coarse), then MS more ms into body[data-fps-full] (every
// frame in full).
import { api, getJson, events, download, el, fmt } from './api.js';
import { parseFmb1, buildMesh, facetTris, keyedTris, facetAngles } from './model.js';
import { View } from './gl.js';

const GREY = [0.75, 0.77, 0.8, 1], INPUT_GHOST = [0.9, 0.32, 0.24, 0.3];
const TIERS = ['table', 'crown', 'girdle', 'pavilion', 'culet'];
const TIER_RGB = [[0.94, 0.78, 0.24], [0.35, 0.63, 0.9], [0.6, 0.6, 0.6],
                  [0.43, 0.78, 0.47], [0.86, 0.35, 0.78]];
const FALLBACK_FORMATS = ['json', 'poly', 'obj', 'stl', 'stl-ascii', 'ply', 'ply-ascii', 'ase', 'fmb1'];
let formatsCache = null;

async function modelFormats() {
  if (formatsCache) return formatsCache;
  try {
    const doc = await getJson('/v1/openapi.json');
    const p = doc.paths['/v1/jobs/{id}/model'].get.parameters.find(x => x.name === 'format');
    formatsCache = p.schema.enum;
  } catch (e) {
    if (e.auth) throw e;
    formatsCache = FALLBACK_FORMATS;
  }
  return formatsCache;
}

// Every object in v (depth first, document order) for which test holds.
function collect(v, test, out = []) {
  if (v && typeof v === 'object') {
    if (!Array.isArray(v) && test(v)) out.push(v);
    for (const k of Object.keys(v)) collect(v[k], test, out);
  }
  return out;
}
const isInspect = o => 'orientation' in o && 'facets' in o && 'vertices' in o && 'valid' in o;

// What the statistics say about the models, by facet count.
function analyse(stats) {
  const inspects = collect(stats, isInspect);
  const groupsOf = collect(stats, o => Array.isArray(o.group_list));
  const reports = (stats && stats.ops || []).filter(o => o.op === 'report' && o.report);
  // a figure of the whole job: the last operation's report that has it
  const opFigure = key => {
    const r = (stats && stats.ops || []).map(o => o.report).filter(o => o && typeof o[key] === 'number');
    return r.length ? r[r.length - 1][key] : undefined;
  };
  return {
    inspects,
    inspectFor: nf => { const c = inspects.filter(r => r.facets === nf); return c[c.length - 1]; },
    firstInspect: inspects[0],
    groups: groupsOf.length ? groupsOf[groupsOf.length - 1] : null,
    report: reports.length ? reports[reports.length - 1].report : null,
    hausdorff: opFigure('hausdorff'),
    volumeChange: opFigure('volume_change'),
  };
}

function signedVolume(mesh) {
  const P = mesh.pos, T = mesh.tris;
  let v = 0;
  for (let t = 0; t < T.length; t += 3) {
    const a = 3 * T[t], b = 3 * T[t + 1], c = 3 * T[t + 2];
    v += P[a] * (P[b + 1] * P[c + 2] - P[b + 2] * P[c + 1]) -
         P[a + 1] * (P[b] * P[c + 2] - P[b + 2] * P[c]) +
         P[a + 2] * (P[b] * P[c + 1] - P[b + 1] * P[c]);
  }
  return v / 6;
}

function hue(i) {
  const h = (i * 0.618033988749895) % 1, s = 0.55, l = 0.58;
  const f = n => { const k = (n + h * 12) % 12; return l - s * Math.min(l, 1 - l) * Math.max(-1, Math.min(k - 3, 9 - k, 1)); };
  return [f(0), f(8), f(4), 1];
}

// "table 1, crown 32, …": the facets of each tier of the report op, the
// tiers legend (and what a test reads); "" without a report.
function tierCounts(report) {
  if (!report || !report.facets) return '';
  const n = TIERS.map(t => report.facets.filter(f => f.tier === t).length);
  return TIERS.map((t, i) => `${t} ${n[i]}`).join(', ');
}

export async function jobView(app, id, args) {
  let job = await getJson(`/v1/jobs/${encodeURIComponent(id)}`);
  const ac = new AbortController();
  const head = el('div', { class: 'jobhead' });
  const numbers = el('dl', { id: 'numbers', class: 'numbers' });
  const canvas = el('canvas', { id: 'view' });
  const controls = el('div', { class: 'controls', id: 'controls' });
  const pickBox = el('div', { id: 'pick', class: 'pick' }, 'Click a facet.');
  const downloads = el('div', { id: 'downloads', class: 'downloads' });
  const statsPre = el('pre', { id: 'stats' });
  const msg = el('p', { id: 'job-msg', class: 'muted' });
  app.append(el('section', { id: 'job', 'data-id': id },
    el('h1', {}, 'Job ', el('code', {}, id)), head, msg,
    el('div', { class: 'jobgrid' },
      el('div', { class: 'viewer' }, canvas, controls),
      el('div', { class: 'side' }, el('h2', {}, 'Numbers'), numbers, el('h2', {}, 'Facet'), pickBox,
         el('h2', {}, 'Downloads'), downloads)),
    el('details', {}, el('summary', {}, 'Statistics JSON'), statsPre)));

  const showHead = () => {
    const pct = Math.round((job.progress || 0) * 100);
    head.replaceChildren(
      el('span', { class: 'state ' + job.state, id: 'job-state' }, job.state), ' ',
      el('progress', { max: 100, value: pct }), ` ${pct}% · source ${job.source || '—'}`,
      job.label ? ` · ${job.label}` : '', ' · pipeline ',
      el('code', {}, (job.pipeline || []).map(o => o.op).join(' → ')),
      job.error ? el('p', { class: 'error' }, job.error) : '');
  };
  showHead();

  let view = null, loaded = false;
  const onEnd = async () => {
    if (loaded || job.state !== 'succeeded') {
      if (job.state === 'failed' || job.state === 'canceled') {
        msg.textContent = `No result: the job ${job.state}.`;
        showNumbers(numbers, job, null, null, null);
        document.body.dataset.state = 'ready';
      }
      return;
    }
    loaded = true;
    view = await showResult({ id, job, args, canvas, controls, numbers, pickBox, downloads, statsPre, msg });
  };
  if (job.state === 'queued' || job.state === 'running') {
    msg.textContent = 'Waiting for the result…';
    events(`/v1/jobs/${id}/events`, (type, data) => {
      if (type === 'gone') { msg.textContent = 'The job was deleted.'; return; }
      job = data;
      showHead();
      if (type === 'state') onEnd().catch(e => { msg.textContent = e.message; });
    }, ac.signal).catch(e => { if (e.name !== 'AbortError') msg.textContent = e.message; });
  } else {
    await onEnd();
  }
  return () => { ac.abort(); if (view) view.meshes = []; };
}

function showNumbers(dl, job, stats, result, input) {
  const s = job.summary || {};
  const a = analyse(stats);
  const after = result ? a.inspectFor(result.model.nf) : null;
  const before = input ? a.inspectFor(input.model.nf) : a.firstInspect;
  let vc = a.volumeChange, vcNote = '';
  if (vc === undefined && before && after && before !== after) vc = after.volume - before.volume;
  const rows = [
    ['vertices_before', 'Vertices before', s.vertices_before],
    ['vertices_after', 'Vertices after', s.vertices_after ?? (result && result.model.nv)],
    ['facets_before', 'Facets before', s.facets_before],
    ['facets_after', 'Facets after', s.facets_after ?? (result && result.model.nf)],
    ['valid', 'Valid', s.valid ?? (after && after.valid)],
    ['orientation', 'Orientation', s.orientation ?? (after && after.orientation)],
    ['self_intersections', 'Self-intersections',
     typeof s.self_intersections === 'number' ? s.self_intersections
       : after ? after.self_intersections.count : undefined],
    ['hausdorff', 'Hausdorff (mm)', s.hausdorff ?? a.hausdorff],
    ['volume_change', 'Volume change (mm³)' + vcNote, vc],
  ];
  if (result) rows.push(['volume', 'Volume (mm³)', after ? after.volume : signedVolume(result)]);
  dl.replaceChildren(...rows.flatMap(([k, label, v]) => [
    el('dt', {}, label), el('dd', { 'data-k': k }, v === undefined ? '—' : fmt(v, 6))]));
}

async function showResult(c) {
  const { id, job, args, canvas, controls, numbers, pickBox, downloads, statsPre, msg } = c;
  const t0 = performance.now();
  const [stats, buf] = await Promise.all([
    getJson(`/v1/jobs/${id}/stats`),
    api(`/v1/jobs/${id}/model?format=fmb1`).then(r => r.arrayBuffer()),
  ]);
  const result = buildMesh(parseFmb1(buf));
  const tParse = performance.now();
  statsPre.textContent = JSON.stringify(stats, null, 1);
  const a = analyse(stats);
  let input = null, inputTried = false;
  const loadInput = async () => {
    if (inputTried) return input;
    inputTried = true;
    try {
      const r = await api(`/v1/jobs/${id}/model?which=input&format=fmb1`);
      input = buildMesh(parseFmb1(await r.arrayBuffer()));
    } catch (e) {
      if (e.auth) throw e;
      msg.textContent = 'No input model: ' + e.message;
    }
    return input;
  };
  showNumbers(numbers, job, stats, result, null);

  // downloads
  const formats = await modelFormats();
  downloads.replaceChildren(
    ...formats.map(f => el('button', { type: 'button', 'data-format': f,
      onclick: () => download(`/v1/jobs/${id}/model?format=${f}`, `${id}.${f.replace(/-ascii$/, '').replace('fmb1', 'fmb')}`) }, f)),
    el('button', { type: 'button', onclick: () => download(`/v1/jobs/${id}/stats`, `${id}.stats.json`) }, 'stats'),
    el('button', { type: 'button', onclick: () => download(`/v1/jobs/${id}/model?which=input&format=json`, `${id}-input.json`) }, 'input'));

  const view = new View(canvas, f => showPick(f), result.ntris <= 200000);
  let state = {
    model: ['result', 'input', 'overlay'].includes(args.get('model')) ? args.get('model') : 'result',
    colour: ['groups', 'tiers'].includes(args.get('colour')) ? args.get('colour') : 'plain',
    edges: result.model.nf <= 300000, selfint: true, inverted: true, free: true,
  };
  // per-model facet sets of the layers
  const layerSets = mesh => {
    const ins = mesh === result ? a.inspectFor(mesh.model.nf) : (a.inspectFor(mesh.model.nf) || null);
    const pairs = ins && ins.self_intersections ? ins.self_intersections.pairs || [] : [];
    const si = new Set();
    for (const [p, q] of pairs) { si.add(p); si.add(q); }
    return { selfint: [...si], pairs, inverted: mesh.inverted };
  };
  // the colour scheme on mesh: {key: facet → layer key or -1, colour}
  const scheme = mesh => {
    const nf = mesh.model.nf;
    if (state.colour === 'groups' && a.groups) {
      const key = new Int32Array(nf).fill(-1);
      const onInput = mesh !== result;
      if (onInput && a.groups.facets_before !== undefined && a.groups.facets_before !== nf) return null;
      a.groups.group_list.forEach((g, i) => {
        if (!g.merged) return;
        if (onInput) { for (const f of g.facets) if (f < nf) key[f] = i; }
        else if (g.facet !== undefined && g.facet < nf) key[g.facet] = i;
      });
      return { key: f => key[f], colour: hue };
    }
    if (state.colour === 'tiers' && a.report && a.report.facets && a.report.facets.length === nf) {
      return { key: f => TIERS.indexOf(a.report.facets[f].tier), colour: k => TIER_RGB[k] };
    }
    return null;
  };
  let handles = [];
  const apply = async () => {
    const list = [];
    if (state.model === 'result' || state.model === 'overlay') list.push({ mesh: result, color: GREY });
    if (state.model === 'input' || state.model === 'overlay') {
      const inp = await loadInput();
      if (inp) list.push({ mesh: inp, color: state.model === 'overlay' ? INPUT_GHOST : GREY });
    }
    if (!list.length) list.push({ mesh: result, color: GREY });
    handles = view.setMeshes(list);
    handles.forEach((h, i) => {
      const m = h.mesh, sets = layerSets(m), layers = [];
      const ghost = list[i].color[3] < 1;
      const sc = ghost ? null : scheme(m);
      if (sc)
        for (const [k, index] of keyedTris(m, sc.key)) layers.push({ kind: 'tris', index, color: sc.colour(k) });
      if (state.selfint && !ghost) layers.push({ kind: 'tris', index: facetTris(m, sets.selfint), color: [0.9, 0.1, 0.1, 1] });
      if (state.inverted && !ghost) layers.push({ kind: 'tris', index: facetTris(m, sets.inverted), color: [0.6, 0.1, 0.9, 1] });
      if (state.edges) layers.push({ kind: 'lines', index: m.lines, color: ghost ? [0.8, 0.2, 0.1, 0.6] : [0.12, 0.14, 0.2, 1] });
      if (state.free) layers.push({ kind: 'lines', index: m.free, color: [1, 0.55, 0, 1] });
      view.setLayers(h, layers);
    });
    const r = Math.max(...list.map(e => e.mesh.radius));
    if (!view.fitted) { view.fit(r); view.fitted = true; } else view.radius = r;
    const cur = list[0].mesh, sets = layerSets(cur);
    counts.selfint.textContent = ` (${sets.selfint.length})`;
    counts.inverted.textContent = ` (${sets.inverted.length})`;
    counts.free.textContent = ` (${cur.free.length / 2})`;
    counts.edges.textContent = ` (${cur.lines.length / 2})`;
    showNumbers(numbers, job, stats, result, input);
  };

  // controls
  const counts = { selfint: el('span'), inverted: el('span'), free: el('span'), edges: el('span') };
  const radio = (name, value, label, disabled) => el('label', {},
    el('input', { type: 'radio', name, value, checked: state[name] === value, disabled,
                  onchange: () => { state[name] = value; apply(); } }), label);
  const check = (key, label) => el('label', {},
    el('input', { type: 'checkbox', 'data-layer': key, checked: state[key],
                  onchange: e => { state[key] = e.target.checked; apply(); } }), label, counts[key]);
  controls.append(
    el('fieldset', {}, el('legend', {}, 'Model'), radio('model', 'result', 'result'),
       radio('model', 'input', 'input'), radio('model', 'overlay', 'before/after')),
    el('fieldset', {}, el('legend', {}, 'Colour'), radio('colour', 'plain', 'plain'),
       radio('colour', 'groups', `merged groups${a.groups ? ` (${a.groups.group_list.filter(g => g.merged).length})` : ''}`, !a.groups),
       el('span', { 'data-tiers': tierCounts(a.report) },
          radio('colour', 'tiers', `report tiers${tierCounts(a.report) ? ` (${tierCounts(a.report)})` : ''}`,
                !(a.report && a.report.facets)))),
    el('fieldset', {}, el('legend', {}, 'Layers'), check('edges', 'facet edges'),
       check('selfint', 'self-intersecting'), check('inverted', 'inverted'), check('free', 'holes / free edges')),
    el('button', { type: 'button', id: 'fit', onclick: () => view.fit() }, 'Fit'),
    el('span', { class: 'muted' }, ' drag: orbit · right/shift-drag: pan · wheel: zoom · click: facet'));

  function showPick(f) {
    if (f < 0) { pickBox.textContent = 'No facet there.'; return; }
    const mesh = handles[0].mesh;
    const rep = mesh === result && a.report && a.report.facets && a.report.facets.length === mesh.model.nf
      ? a.report.facets[f] : null;
    const g = rep || facetAngles(mesh, f);
    const sets = layerSets(mesh);
    const partners = sets.pairs.filter(([p, q]) => p === f || q === f).map(([p, q]) => (p === f ? q : p));
    let group = null;
    if (a.groups && mesh === result) group = a.groups.group_list.find(x => x.merged && x.facet === f);
    pickBox.replaceChildren(el('dl', { class: 'numbers' },
      el('dt', {}, 'Facet'), el('dd', { 'data-k': 'facet' }, f),
      rep ? [el('dt', {}, 'Tier'), el('dd', {}, rep.tier)] : null,
      el('dt', {}, 'Inclination (°)'), el('dd', { 'data-k': 'inclination' }, fmt(g.inclination_deg, 3)),
      el('dt', {}, 'Azimuth (°)'), el('dd', { 'data-k': 'azimuth' }, fmt(g.azimuth_deg, 3)),
      el('dt', {}, 'Index'), el('dd', { 'data-k': 'index' }, fmt(g.index, 2)),
      el('dt', {}, 'Area (mm²)'), el('dd', { 'data-k': 'area' }, fmt(g.area_mm2 ?? mesh.area[f], 5)),
      el('dt', {}, 'Vertices'), el('dd', {}, mesh.model.fstart[f + 1] - mesh.model.fstart[f]),
      group ? [el('dt', {}, 'Merged from'), el('dd', {}, `${group.facets.length} input facets`)] : null,
      partners.length ? [el('dt', {}, 'Intersects'), el('dd', {}, partners.join(', '))] : null,
      mesh.inverted.includes(f) ? [el('dt', {}, 'Inverted'), el('dd', {}, 'yes')] : null),
      rep ? '' : el('p', { class: 'muted' }, 'Angles from the largest facet as the table (no report op in this job).'));
  }

  view.onFrame = n => {
    if (n !== 1) return;
    const body = document.body.dataset;
    body.firstFrameMs = String(Math.round(performance.now()));
    body.loadMs = String(Math.round(tParse - t0));
    body.triangles = String(result.ntris);
    // what an orbit draws instead of a large mesh (gl.js coarseMesh)
    const co = view.meshes[0] && view.meshes[0].coarse;
    body.coarseTriangles = String(co ? co.ntri / 3 : result.ntris);
    // where the canvas is, for a test that looks at a screenshot of it
    const r = canvas.getBoundingClientRect();
    body.canvas = [r.left, r.top, r.right, r.bottom].map(Math.round).join(' ');
    body.state = 'ready';
    const bench = Number(args.get('bench') || 0);
    if (bench > 0) {
      body.state = 'bench';
      // as the mouse orbits it (coarse while moving), then every frame in full
      view.spin(bench).then(fps => {
        body.fps = fps.toFixed(1);
        return view.spin(bench, true);
      }).then(fps => { body.fpsFull = fps.toFixed(1); body.state = 'ready'; });
    }
  };
  await apply();
  return view;
}
