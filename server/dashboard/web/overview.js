// Overview: the daemon's status and every map with its figures (GET /v1/status, /v1/maps and
// /v1/maps/{map}/stats per map), refreshed every few seconds; the live ingest rate of a map is the
// change of its observation count between two refreshes over the time between them.
import {api, listAll, mapPath} from './api.js';
import {el, formatBytes, formatCount, formatDuration, formatFixed, formatTime, num, table, timestampSeconds} from './format.js';

const REFRESH_MS = 5000;

// The previous sample of each map's observations, kept across visits of the view so that coming
// back shows a rate at once: map → {observations, at (ms)}.
const samples = new Map();

export function mapLink(map) {
  const view = map.kind === 'MAP_KIND_GRID' ? 'grid' : 'generic';
  return el('a', {href: '#/' + view + '/' + encodeURIComponent(map.name)}, map.name);
}

function sizeOf(map) {
  if (map.kind !== 'MAP_KIND_GRID') return 'named states';
  const size = map.grid?.size || {};
  const z = num(size.z) > 1 ? ' × ' + num(size.z) : '';
  return num(size.x) + ' × ' + num(size.y) + z + ' cells of ' + num(map.grid?.resolution) + ' m';
}

// Observations per second since the previous sample, or '—' without one.
function rateOf(name, observations, now) {
  const previous = samples.get(name);
  samples.set(name, {observations, at: now});
  if (!previous || now <= previous.at) return '—';
  const rate = (observations - previous.observations) / ((now - previous.at) / 1000);
  return rate.toFixed(rate < 10 ? 1 : 0) + ' /s';
}

function lastUpdateOf(stats) {
  const update = stats.lastUpdate;
  if (!update) return 'never';
  return formatTime(timestampSeconds(update.startTime)) + ' (' + formatCount(update.statesUpdated) + ' states, ' +
         formatDuration(update.durationSeconds) + ')';
}

function statusFacts(status) {
  const facts = [
    ['version', status.version || '—'],
    ['store', status.storeState === 'STORE_STATE_OPEN' ? 'open' : (status.storeState || '—')],
    ['uptime', formatDuration(status.uptimeSeconds)],
    ['maps', formatCount(status.mapCount)],
    ['states (dynamic)', formatCount(status.stateCount) + ' (' + formatCount(status.dynamicStateCount) + ')'],
    ['running operations', formatCount(status.runningOperations)],
    ['next update', status.nextUpdateTime ? formatTime(timestampSeconds(status.nextUpdateTime)) +
                    ' (' + (status.updateSchedule || '') + ' ' + (status.updateTimeZone || '') + ')' : 'none scheduled'],
    ['data dir free', formatBytes(status.dataDirFreeBytes)],
    ['failed maps', String((status.failedMaps || []).length)],
  ];
  return el('dl', {class: 'facts', id: 'server-status'}, facts.map(([k, v]) => [el('dt', {}, k), el('dd', {}, v)]));
}

async function refresh(box) {
  const [status, maps] = await Promise.all([api('/v1/status'), listAll('/v1/maps', 'maps')]);
  const stats = await Promise.all(maps.map((m) => api(mapPath(m.name) + '/stats').then((r) => r.stats || {}, (e) => ({error: e}))));
  const now = performance.now();
  const rows = maps.map((map, i) => {
    const s = stats[i];
    if (s.error) return el('tr', {'data-map': map.name}, el('td', {}, mapLink(map)), el('td', {colspan: 8, class: 'error'}, s.error.message));
    const compression = num(s.compressionRatio);
    const cells = [['map', mapLink(map)], ['kind', map.kind === 'MAP_KIND_GRID' ? 'grid' : 'generic'], ['size', sizeOf(map)],
                   ['states', formatCount(s.states) + ' (' + formatCount(s.dynamicStates) + ')'],
                   ['observations', formatCount(s.observations)],
                   ['compression', formatFixed(compression, compression < 10 ? 2 : 1)],
                   ['error', formatFixed(num(s.meanPredictionError), 3)], ['update', lastUpdateOf(s)],
                   ['rate', rateOf(map.name, num(s.observations), now)]];
    const numeric = new Set(['observations', 'compression', 'error', 'rate']);
    return el('tr', {'data-map': map.name},
              cells.map(([column, c]) => el('td', {'data-column': column, class: numeric.has(column) ? 'num' : undefined}, c)));
  });
  const failed = (status.failedMaps || []).map((f) => [f.map, f.error]);
  box.replaceChildren(el('div', {},
    el('h2', {}, 'Daemon'), statusFacts(status),
    el('h2', {}, 'Maps'),
    maps.length ? table(['map', 'kind', 'size', 'states (dynamic)', 'observations', 'compression', 'ε_p', 'last update', 'ingest rate'],
                        rows, {id: 'maps-table'})
                : el('p', {class: 'muted'}, 'No maps yet: create one with fremenctl maps create, or try fremenctl demo.'),
    failed.length ? [el('h2', {}, 'Failed maps'), table(['map', 'why'], failed, {id: 'failed-maps'})] : null,
    el('p', {class: 'hint'}, 'Refreshed every ' + REFRESH_MS / 1000 + ' s; ε_p is the mean prediction error of the ' +
       'dynamic states, compression the raw observations (one bit each) over the bytes of the models.')));
}

export async function render(root) {
  const box = el('div', {id: 'overview'});
  root.append(box);
  await refresh(box);
  const timer = setInterval(() => refresh(box).catch((e) => box.prepend(el('p', {class: 'error'}, e.message))), REFRESH_MS);
  return () => clearInterval(timer);
}
