// The dashboard's shell: hash routing between the views, the server line in the header and the
// token button. A route is #/VIEW/MAP?key=value: the view's module renders into <main> and may
// return a function that stops its timers when another view takes over.
//   #/               overview.js      every map, the daemon's status, ingest rates
//   #/grid/MAP       grid_view.js     the predicted grid at a time (t=center time, z=plane)
//   #/model/MAP      model_view.js    one state's model (x, y, z for a cell or name=)
//   #/generic/MAP    generic_view.js  a generic map's states, p now and at t, top-n of a group
//   #/jobs           jobs_view.js     update operations, run an update, failed maps
import {api, askForToken, showError} from './api.js';
import {formatDuration} from './format.js';
import * as overview from './overview.js';
import * as gridView from './grid_view.js';
import * as modelView from './model_view.js';
import * as genericView from './generic_view.js';
import * as jobsView from './jobs_view.js';

const views = {'': overview, grid: gridView, model: modelView, generic: genericView, jobs: jobsView};
const navOf = {'': 'overview', grid: 'grid', model: 'grid', generic: 'generic', jobs: 'jobs'};

let stopView = null;
let generation = 0;

// "#/grid/demo-office?t=2023-11-27T00:00:00Z" → {view: 'grid', map: 'demo-office', params: {t: ...}}
export function parseRoute(hash) {
  const [path, search = ''] = hash.replace(/^#\/?/, '').split('?');
  const [view = '', ...rest] = path.split('/');
  return {view, map: rest.length ? decodeURIComponent(rest.join('/')) : '', params: Object.fromEntries(new URLSearchParams(search))};
}

async function route() {
  const current = ++generation;
  if (stopView) stopView();
  stopView = null;
  showError(null);
  const {view, map, params} = parseRoute(location.hash);
  const module = views[view] || overview;
  for (const link of document.querySelectorAll('nav a')) {
    link.classList.toggle('active', link.dataset.nav === navOf[view in views ? view : '']);
  }
  const root = document.getElementById('view');
  root.replaceChildren();
  root.dataset.view = view || 'overview';
  root.dataset.ready = 'false';
  try {
    const stop = await module.render(root, map, params);
    if (current !== generation) {
      if (stop) stop();
      return;
    }
    stopView = stop || null;
    root.dataset.ready = 'true';
  } catch (error) {
    if (current === generation) showError(error);
  }
}

async function showServer() {
  try {
    const status = await api('/v1/status');
    document.getElementById('server-line').textContent =
        'fremend ' + (status.version || '') + ', up ' + formatDuration(status.uptimeSeconds) +
        (status.tokensRequired ? ', tokens required' : '') + (status.tls ? ', TLS' : '');
  } catch (error) {
    document.getElementById('server-line').textContent = 'status unavailable: ' + error.message;
  }
}

document.getElementById('token-button').addEventListener('click', async () => {
  if (await askForToken('The token sent with every API call (empty: none).')) {
    showServer();
    route();
  }
});
window.addEventListener('hashchange', route);
showServer();
route();
