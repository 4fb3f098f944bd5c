// scanners.js — #/scanners: every scanner facetd has seen, its state and
// progress, its last job, and a Scan button (POST
// /v1/scanners/{serial}/scan). Read again every 2 s.
import { api, getJson, el } from './api.js';

export async function scannersView(app) {
  const body = el('tbody');
  const note = el('p', { class: 'muted', id: 'scanners-msg' });
  app.append(el('section', { id: 'scanners' }, el('h1', {}, 'Scanners'),
    el('table', { class: 'jobs' }, el('thead', {}, el('tr', {},
      ['Serial', 'Model', 'Transport', 'State', 'Progress', 'Last job', 'Scans', ''].map(h => el('th', {}, h)))), body),
    note));
  let timer = null, stopped = false;
  const scan = async serial => {
    note.textContent = `Starting a scan on ${serial}…`;
    try {
      await api(`/v1/scanners/${encodeURIComponent(serial)}/scan`, { method: 'POST' });
      note.textContent = `${serial}: scan started; its job appears in the list when the model is in.`;
    } catch (e) {
      if (!e.auth) note.textContent = `${serial}: ${e.message}`;
    }
    load();
  };
  const load = async () => {
    clearTimeout(timer);
    try {
      const r = await getJson('/v1/scanners');
      if (stopped) return;
      body.replaceChildren(...r.scanners.map(s => {
        const pct = Math.round((s.progress || 0) * 100);
        return el('tr', { 'data-serial': s.serial },
          el('td', {}, s.serial), el('td', {}, [s.vendor, s.model].filter(Boolean).join(' ')),
          el('td', {}, s.transport || ''), el('td', { class: 'state ' + s.state }, s.state),
          el('td', {}, el('progress', { max: 100, value: pct }), ` ${s.contours_done}/${s.contours_total}`),
          el('td', {}, s.last_job ? el('a', { href: `#/jobs/${s.last_job}` }, s.last_job) : '—'),
          el('td', {}, `${s.scans_completed}`),
          el('td', {}, el('button', { type: 'button', onclick: () => scan(s.serial) }, 'Scan')));
      }));
      note.textContent = !r.enabled ? `The scanner intake is off${r.disabled_reason ? ': ' + r.disabled_reason : ''}.`
        : r.scanners.length ? '' : 'No scanner seen yet.';
      document.body.dataset.state = 'ready';
    } catch (e) {
      if (e.auth) { stopped = true; return; }
      note.textContent = e.message;
    }
    if (!stopped) timer = setTimeout(load, 2000);
  };
  await load();
  return () => { stopped = true; clearTimeout(timer); };
}
