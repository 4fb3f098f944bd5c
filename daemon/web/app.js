// app.js — the viewer's entry: the router (#/jobs, #/jobs/{id},
// #/submit, #/scanners; arguments after '?' in the hash) and the token
// gate: with a token configured, nothing but the prompt is shown until a
// request with the token succeeds.
import { getJson, setToken, token, onAuthNeeded } from './api.js';
import { jobsView } from './jobs.js';
import { jobView } from './job.js';
import { submitView } from './submit.js';
import { scannersView } from './scanners.js';

const app = document.getElementById('app');
const form = document.getElementById('token-form');
let leave = null; // the current view's cleanup (streams, timers)

function askToken(msg) {
  if (leave) { leave(); leave = null; }
  app.replaceChildren();
  form.hidden = false;
  document.getElementById('token-msg').textContent = msg || '';
  document.getElementById('token').focus();
  document.body.dataset.state = 'token';
}

onAuthNeeded(() => askToken(token() ? 'that token was refused' : ''));

form.addEventListener('submit', e => {
  e.preventDefault();
  setToken(document.getElementById('token').value);
  document.getElementById('token').value = '';
  start();
});
document.getElementById('logout').addEventListener('click', () => {
  setToken('');
  start();
});

function parseHash() {
  const h = location.hash.replace(/^#/, '') || '/jobs';
  const [path, query] = h.split('?');
  return { parts: path.split('/').filter(Boolean), args: new URLSearchParams(query || '') };
}

async function route() {
  if (leave) { leave(); leave = null; }
  const { parts, args } = parseHash();
  app.replaceChildren();
  document.body.dataset.state = 'loading';
  for (const a of document.querySelectorAll('nav a'))
    a.classList.toggle('here', location.hash.startsWith(a.getAttribute('href')));
  try {
    if (parts[0] === 'jobs' && parts[1]) leave = await jobView(app, parts[1], args);
    else if (parts[0] === 'submit') leave = await submitView(app);
    else if (parts[0] === 'scanners') leave = await scannersView(app);
    else leave = await jobsView(app, args);
  } catch (e) {
    if (e.auth) return;
    app.append(Object.assign(document.createElement('p'), { className: 'error', textContent: e.message }));
    document.body.dataset.state = 'error';
    throw e;
  }
}

async function start() {
  try {
    // the version route needs the token when one is set: it is the gate
    const v = await getJson('/v1/version');
    form.hidden = true;
    document.getElementById('server').textContent = `facetd ${v.version || ''}`;
    document.getElementById('logout').hidden = !token();
    await route();
  } catch (e) {
    if (!e.auth) throw e;
  }
}

window.addEventListener('hashchange', () => { if (form.hidden) route(); });
start();
