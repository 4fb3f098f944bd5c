// jobs.js — #/jobs: the job list, newest first, filtered by state and
// source (?state=running&source=usb:SN1 in the hash). Live: the list is
// read again every 2 s (new jobs), and the jobs still queued or running
// get their SSE streams (at most 3 at once: a browser keeps 6
// connections to one server), whose events update their rows at once.
import { api, getJson, events, el, fmt } from './api.js';

const STATES = ['', 'queued', 'running', 'succeeded', 'failed', 'canceled'];
const MAX_STREAMS = 3;

export function row(j) {
  const s = j.summary || {};
  const pct = Math.round((j.progress || 0) * 100);
  return el('tr', { 'data-id': j.id, 'data-state': j.state },
    el('td', {}, el('a', { href: `#/jobs/${j.id}` }, j.id)),
    el('td', {}, (j.created || '').replace('T', ' ').replace(/\.\d+Z$/, 'Z')),
    el('td', { class: 'state ' + j.state }, j.state),
    el('td', {}, el('progress', { max: 100, value: pct }), ` ${pct}%`),
    el('td', {}, j.source || ''),
    el('td', {}, j.label || ''),
    el('td', { class: 'num' }, s.facets_before !== undefined || s.facets_after !== undefined
      ? `${fmt(s.facets_before)} → ${fmt(s.facets_after)}` : ''),
    el('td', {}, s.valid === undefined ? '' : s.valid ? 'valid' : 'invalid'));
}

export async function jobsView(app, args) {
  const state = args.get('state') || '', source = args.get('source') || '';
  const stateSel = el('select', { id: 'filter-state' },
    STATES.map(s => el('option', { value: s, selected: s === state }, s || 'any state')));
  const sourceIn = el('input', { id: 'filter-source', placeholder: 'http or usb:SERIAL', value: source,
                                 list: 'sources' });
  const sources = el('datalist', { id: 'sources' }, el('option', { value: 'http' }));
  const apply = () => {
    const q = new URLSearchParams();
    if (stateSel.value) q.set('state', stateSel.value);
    if (sourceIn.value.trim()) q.set('source', sourceIn.value.trim());
    location.hash = '#/jobs' + (q.toString() ? '?' + q : '');
  };
  stateSel.addEventListener('change', apply);
  sourceIn.addEventListener('change', apply);
  const tbody = el('tbody');
  const status = el('p', { class: 'muted', id: 'jobs-status' });
  app.append(el('section', { id: 'jobs' },
    el('h1', {}, 'Jobs'),
    el('div', { class: 'filters' }, el('label', {}, 'State ', stateSel),
       el('label', {}, 'Source ', sourceIn), sources),
    el('table', { class: 'jobs' },
      el('thead', {}, el('tr', {}, ['Job', 'Created', 'State', 'Progress', 'Source', 'Label',
                                     'Facets before → after', 'Valid'].map(h => el('th', {}, h)))),
      tbody),
    status));

  const streams = new Map(); // id → AbortController
  let timer = null, stopped = false;
  const put = j => {
    const old = tbody.querySelector(`tr[data-id="${j.id}"]`);
    if (old) old.replaceWith(row(j));
  };
  const follow = jobs => {
    for (const [id, ac] of streams)
      if (!jobs.some(j => j.id === id && (j.state === 'queued' || j.state === 'running'))) {
        ac.abort();
        streams.delete(id);
      }
    for (const j of jobs) {
      if (streams.size >= MAX_STREAMS) break;
      if (streams.has(j.id) || (j.state !== 'queued' && j.state !== 'running')) continue;
      const ac = new AbortController();
      streams.set(j.id, ac);
      events(`/v1/jobs/${j.id}/events`, (type, data) => put(data), ac.signal)
        .catch(() => {}).finally(() => streams.delete(j.id));
    }
  };
  const load = async () => {
    const q = new URLSearchParams({ limit: '100' });
    if (state) q.set('status', state);
    if (source) q.set('source', source);
    try {
      const { jobs } = await getJson('/v1/jobs?' + q);
      if (stopped) return;
      tbody.replaceChildren(...jobs.map(row));
      for (const s of new Set(jobs.map(j => j.source)))
        if (s && !sources.querySelector(`option[value="${CSS.escape(s)}"]`))
          sources.append(el('option', { value: s }));
      status.textContent = jobs.length ? `${jobs.length} job(s)` : 'no jobs';
      follow(jobs);
      document.body.dataset.state = 'ready';
    } catch (e) {
      if (e.auth) { stopped = true; return; }
      status.textContent = e.message;
    }
    if (!stopped) timer = setTimeout(load, 2000);
  };
  await load();
  return () => {
    stopped = true;
    clearTimeout(timer);
    for (const ac of streams.values()) ac.abort();
  };
}


