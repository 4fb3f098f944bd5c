// api.js — talking to facetd: every request carries the API token the
// user gave (kept in sessionStorage: gone when the tab closes), a 401
// asks for it again, and errors are the server's problem+json detail.
// Event streams are read with fetch (EventSource cannot send a token).

const KEY = 'facetd.token';

export function token() { return sessionStorage.getItem(KEY) || ''; }
export function setToken(t) {
  if (t) sessionStorage.setItem(KEY, t);
  else sessionStorage.removeItem(KEY);
}

export class AuthError extends Error {
  constructor() { super('this server needs an API token'); this.auth = true; }
}

let onAuth = () => {};
export function onAuthNeeded(fn) { onAuth = fn; }

export async function api(path, opts = {}) {
  const headers = Object.assign({}, opts.headers || {});
  const t = token();
  if (t) headers.Authorization = 'Bearer ' + t;
  const r = await fetch(path, Object.assign({}, opts, { headers }));
  if (r.status === 401) {
    onAuth();
    throw new AuthError();
  }
  if (!r.ok && r.status !== 304) {
    let detail = `${r.status} ${r.statusText}`;
    try {
      const p = await r.json();
      if (p.detail) detail = p.detail;
      if (p.errors) detail += ' — ' + p.errors.map(e => (e.path ? e.path + ': ' : '') + e.message).join('; ');
    } catch (e) { /* not a problem document */ }
    const err = new Error(detail);
    err.status = r.status;
    throw err;
  }
  return r;
}

export async function getJson(path) { return (await api(path)).json(); }

// Reads the SSE stream at path, calling onEvent(type, data) for each
// event, until it ends or signal aborts.
export async function events(path, onEvent, signal) {
  const r = await api(path, { signal, headers: { Accept: 'text/event-stream' } });
  const reader = r.body.getReader(), dec = new TextDecoder();
  let buf = '';
  for (;;) {
    const { value, done } = await reader.read();
    if (done) return;
    buf += dec.decode(value, { stream: true });
    let end;
    while ((end = buf.indexOf('\n\n')) >= 0) {
      const block = buf.slice(0, end);
      buf = buf.slice(end + 2);
      let type = 'message', data = '';
      for (const line of block.split('\n')) {
        if (line.startsWith('event:')) type = line.slice(6).trim();
        else if (line.startsWith('data:')) data += line.slice(5).trim();
      }
      if (data) onEvent(type, JSON.parse(data));
    }
  }
}

// Saves a response as a file: <a href> cannot carry the token.
export async function download(path, name) {
  const blob = await (await api(path)).blob();
  const url = URL.createObjectURL(blob);
  const a = document.createElement('a');
  a.href = url;
  a.download = name;
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

// Small DOM helper: el('td', {class: 'x'}, 'text', child, ...).
export function el(tag, attrs = {}, ...kids) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (v === undefined || v === null || v === false) continue;
    if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
    else if (k === 'class') e.className = v;
    else e.setAttribute(k, v === true ? '' : v);
  }
  for (const k of kids.flat()) {
    if (k === null || k === undefined || k === false) continue;
    e.append(k instanceof Node ? k : String(k));
  }
  return e;
}

export function fmt(v, digits = 4) {
  if (v === null || v === undefined) return '—';
  if (typeof v === 'boolean') return v ? 'yes' : 'no';
  if (typeof v === 'number') {
    if (Number.isInteger(v)) return String(v);
    return Math.abs(v) >= 1e-3 || v === 0 ? v.toFixed(digits) : v.toExponential(2);
  }
  return String(v);
}
