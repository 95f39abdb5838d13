// One state's model, the paper's Fig. 1-2 for that state: GET /v1/maps/{map}/model (with its
// spectrum) for the published components, the per-order errors and the chosen order, persistence;
// a week of p(t) from POST :predict at many times, drawn with Chart.js, and on lossless maps the
// observed states of that week from POST :reconstruct drawn over it.
// Route: #/model/MAP?x=&y=&z= (a grid cell) or ?name= (a generic state); from= the week's start
// (seconds; default: the week before the state's last observation), t= the time it was opened at.
import {api, bytesField, mapPath} from './api.js';
import {el, formatCount, formatDuration, formatFixed, formatTick, formatTime, num, parseTime, table} from './format.js';

const WEEK = 7 * 86400;
const PLOT_STEP = 300;  // seconds between predicted points: 2016 a week

function refsOf(params) {
  if (params.name !== undefined) {
    return {label: 'state "' + params.name + '"', query: {'state.name': params.name}, refs: {names: [params.name]}};
  }
  const x = num(params.x), y = num(params.y), z = num(params.z);
  return {label: 'cell (' + x + ', ' + y + (z ? ', ' + z : '') + ')',
          query: {'state.cell.x': x, 'state.cell.y': y, 'state.cell.z': z}, refs: {cells: {x: [x], y: [y], z: [z]}}};
}

function componentsTable(components, id) {
  return table(['period', 'amplitude', 'phase (rad)'], (components || []).map((c) => [
    formatDuration(c.periodSeconds), formatFixed(num(c.amplitude), 4), formatFixed(num(c.phase), 3)]), {id});
}

function facts(rows, id) {
  return el('dl', {class: 'facts', id}, rows.map(([k, v]) => [el('dt', {}, k), el('dd', {}, v)]));
}

function modelTables(model, selectedOrder) {
  const persistence = model.persistence || {};
  const errors = (model.orderErrors || []).map((e) => el('tr', {class: num(e.order) === selectedOrder ? 'chosen' : undefined,
                                                                 'data-order': String(num(e.order))},
    el('td', {class: 'num'}, String(num(e.order))), el('td', {class: 'num'}, formatFixed(num(e.error), 4)),
    el('td', {class: 'num'}, formatFixed(num(e.weight), 1))));
  const spectrum = [...(model.spectrum || [])].sort((a, b) => num(b.amplitude) - num(a.amplitude)).slice(0, 12);
  const lossless = model.lossless;
  return el('div', {class: 'columns'},
    el('div', {},
      el('h2', {}, 'The state'),
      facts([
        ['key', model.id || '—'], ['name (group)', model.name ? model.name + (model.group ? ' (' + model.group + ')' : '') : '—'],
        ['observations', formatCount(model.observations)],
        ['observed', formatTime(num(model.firstTime)) + ' → ' + formatTime(num(model.lastTime))],
        ['mean γ0', formatFixed(num(model.mean), 4)],
        ['never changed', model.neverChanged ? 'yes (no spectrum, no P)' : 'no'],
      ], 'state-facts'),
      el('h2', {}, 'Persistence'),
      facts([['last observation', formatTime(num(persistence.lastTime))], ['last value', String(num(persistence.lastValue))],
             ['τ', num(persistence.tauSeconds) ? formatDuration(persistence.tauSeconds) : '— (fewer than two observations)']],
            'persistence')),
    el('div', {},
      el('h2', {}, 'Published model P'),
      el('p', {}, 'α0 = ' + formatFixed(num(model.publishedMean), 4) + ', order ' + selectedOrder),
      componentsTable(model.published, 'published-components')),
    el('div', {},
      el('h2', {}, 'Error per order'),
      errors.length ? table(['order', 'ε_p', 'weight'], errors, {id: 'order-errors'})
                    : el('p', {class: 'muted'}, 'No evidence yet (scored from the observations after an update).'),
      el('p', {class: 'hint'}, 'The chosen order is highlighted.')),
    spectrum.length ? el('div', {}, el('h2', {}, 'Spectrum (largest 12 of ' + model.spectrum.length + ')'),
                         componentsTable(spectrum, 'spectrum')) : null,
    lossless ? el('div', {}, el('h2', {}, 'Lossless history'), facts([
      ['sampling', formatDuration(lossless.samplingSeconds)], ['slots', formatCount(lossless.slotCount)],
      ['outlier intervals', String((lossless.outliers || []).length) + (lossless.truncated ? ' (truncated)' : '')],
      ['ε_e / ε_p', formatFixed(num(lossless.estimationError), 4) + ' / ' + formatFixed(num(lossless.predictionError), 4)],
      ['history order', String(num(lossless.selectedOrder))]], 'lossless')) : null);
}

// Observed states (0/1) of the week on a lossless map, as chart points at each slot's middle.
async function observationsOf(mapName, map, refs, start, end) {
  if (!(num(map.losslessSamplingSeconds) > 0)) return null;
  const history = await api(mapPath(mapName) + ':reconstruct', {method: 'POST', body: {states: refs, startTime: start, endTime: end}});
  const slots = bytesField(history.histories?.[0]?.slots);
  const first = num(history.firstSlotTime), step = num(history.slotSeconds);
  const points = [];
  slots.forEach((s, i) => { if (s !== 2) points.push({x: first + (i + 0.5) * step, y: s}); });
  return points;
}

export async function render(root, mapName, params) {
  const which = refsOf(params);
  const [map, answer] = await Promise.all([api(mapPath(mapName)).then((r) => r.map),
                                           api(mapPath(mapName) + '/model', {query: {...which.query, include_spectrum: true}})]);
  const model = answer.model;
  const back = el('a', {href: map.kind === 'MAP_KIND_GRID' ? '#/grid/' + encodeURIComponent(mapName) + (params.t ? '?t=' + params.t : '')
                                                           : '#/generic/' + encodeURIComponent(mapName)}, '← ' + mapName);
  root.append(el('h2', {}, 'Model of ', which.label, ' in ', back));
  if (!model) {
    root.append(el('p', {id: 'model-unobserved', class: 'muted'}, 'This state was never observed: it predicts 0.5 at every time.'));
    return null;
  }
  const selectedOrder = num(model.selectedOrder);
  let start = parseTime(params.from);
  if (!Number.isFinite(start)) {
    // The observed week (ending at the state's last observation, from the next midnight UTC), or
    // the week around the time the model was opened at.
    start = num(model.lastTime) > 0 ? Math.ceil((num(model.lastTime) - WEEK) / 86400) * 86400 : centerOf(params) - WEEK / 2;
  }
  start = Math.floor(start / PLOT_STEP) * PLOT_STEP;

  const canvas = el('canvas', {id: 'model-chart'});
  const caption = el('p', {id: 'model-caption', class: 'muted'});
  const weekLink = (days) => '#/model/' + encodeURIComponent(mapName) + '?' +
      new URLSearchParams({...params, from: String(start + days * 86400)}).toString();
  root.append(el('div', {class: 'controls'}, el('a', {href: weekLink(-7)}, '◀ week before'), el('a', {href: weekLink(7)}, 'week after ▶')),
              el('div', {class: 'chart-box'}, canvas), caption, modelTables(model, selectedOrder));

  const times = Array.from({length: WEEK / PLOT_STEP + 1}, (_, i) => start + i * PLOT_STEP);
  const [prediction, observed] = await Promise.all([
    api(mapPath(mapName) + ':predict', {method: 'POST', body: {states: which.refs, times}}),
    observationsOf(mapName, map, which.refs, start, start + WEEK).catch((e) => { caption.textContent = e.message; return null; })]);
  const p = (prediction.probabilities || []).map((v, i) => ({x: times[i], y: Number(v)}));
  const datasets = [{label: 'p(t), order ' + selectedOrder, data: p, borderColor: '#0b62a4', borderWidth: 1.5, pointRadius: 0, tension: 0}];
  if (observed) {
    datasets.push({label: 'observed s(t)', type: 'scatter', data: observed, backgroundColor: 'rgba(179, 38, 30, 0.6)', pointRadius: 2});
  }
  const chart = new window.Chart(canvas, {
    type: 'line',
    data: {datasets},
    options: {
      animation: false, maintainAspectRatio: false, parsing: false, normalized: true,
      scales: {
        x: {type: 'linear', min: start, max: start + WEEK, ticks: {stepSize: 43200, callback: (v) => formatTick(v), maxRotation: 0, autoSkip: true}},
        y: {min: -0.02, max: 1.02, title: {display: true, text: 'p'},
            afterBuildTicks: (axis) => { axis.ticks = [0, 0.2, 0.4, 0.6, 0.8, 1].map((value) => ({value})); }},
      },
      plugins: {tooltip: {callbacks: {title: (items) => formatTime(items[0].parsed.x)}}},
    },
  });
  canvas.dataset.points = String(p.length);
  canvas.dataset.observations = String(observed ? observed.length : 0);
  caption.textContent = 'A week of p(t) from ' + formatTime(start) + ', every ' + PLOT_STEP / 60 + ' min' +
      (observed ? ', with the ' + observed.length + ' observed slots of the lossless history' :
                  ' (the map keeps no lossless history: no observations to draw)') + '.';
  return () => chart.destroy();
}

function centerOf(params) {
  const t = parseTime(params.t);
  return Number.isFinite(t) ? t : Date.now() / 1000;
}
