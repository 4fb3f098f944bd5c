// submit.js — #/submit: drop a model file (or choose one) and a
// pipeline; the file goes as it is to POST /v1/jobs?format=...&pipeline=...
// (the format from the file's extension), and the new job opens.
import { api, el } from './api.js';

const BY_EXT = { json: 'json', poly: 'poly', obj: 'obj', stl: 'stl', ply: 'ply', off: 'off', fmb: 'fmb1', fmb1: 'fmb1' };
const PRESETS = [
  ['correct', 'correct — the post-scan correction'],
  ['inspect', 'inspect — statistics only'],
  ['merge,inspect', 'merge, then inspect'],
  ['fill,inspect', 'fill the holes, then inspect'],
  ['correct,report', 'correct, then report'],
];

export async function submitView(app) {
  const file = el('input', { type: 'file', id: 'file', accept: Object.keys(BY_EXT).map(e => '.' + e).join(',') });
  const preset = el('select', { id: 'preset' }, PRESETS.map(([v, l]) => el('option', { value: v }, l)));
  const pipeline = el('input', { id: 'pipeline', value: PRESETS[0][0], size: 40 });
  preset.addEventListener('change', () => { pipeline.value = preset.value; });
  const label = el('input', { id: 'label', maxlength: 127 });
  const out = el('p', { id: 'submit-msg', role: 'status' });
  const zone = el('div', { id: 'drop', class: 'drop' }, 'Drop a model here (',
    Object.keys(BY_EXT).join(', '), ') or ', file);
  const send = async f => {
    const ext = (f.name.split('.').pop() || '').toLowerCase(), format = BY_EXT[ext];
    if (!format) { out.textContent = `${f.name}: unknown format (expected ${Object.keys(BY_EXT).join(', ')})`; return; }
    const q = new URLSearchParams({ format, pipeline: pipeline.value.trim() });
    q.set('label', label.value.trim() || f.name);
    out.textContent = `Sending ${f.name} (${f.size} bytes)…`;
    try {
      const r = await api('/v1/jobs?' + q, { method: 'POST', body: f,
                                             headers: { 'Content-Type': 'application/octet-stream' } });
      const j = await r.json();
      out.textContent = `Job ${j.id} queued.`;
      location.hash = `#/jobs/${j.id}`;
    } catch (e) {
      if (!e.auth) out.textContent = e.message;
    }
  };
  file.addEventListener('change', () => { if (file.files[0]) send(file.files[0]); });
  zone.addEventListener('dragover', e => { e.preventDefault(); zone.classList.add('over'); });
  zone.addEventListener('dragleave', () => zone.classList.remove('over'));
  zone.addEventListener('drop', e => {
    e.preventDefault();
    zone.classList.remove('over');
    if (e.dataTransfer.files[0]) send(e.dataTransfer.files[0]);
  });
  app.append(el('section', { id: 'submit' }, el('h1', {}, 'Submit a model'),
    el('p', {}, el('label', {}, 'Pipeline ', preset), ' ', el('label', {}, 'ops ', pipeline)),
    el('p', {}, el('label', {}, 'Label ', label)), zone, out,
    el('p', { class: 'muted' }, 'From a shell: ',
       el('code', {}, `curl -H 'Content-Type: application/octet-stream' --data-binary @stone.stl '${location.origin}/v1/jobs?format=stl&pipeline=correct'`))));
  document.body.dataset.state = 'ready';
  return () => {};
}
