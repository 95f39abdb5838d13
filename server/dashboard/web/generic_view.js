// A generic map's named states: GET /v1/maps/{map}/states (name, group), p now and at the slider's
// time t from one POST :predict by names, each state's selected order from GET …/model, and the
// top n of a group at t from POST :topStates. A state's name opens its model.
import {api, listAll, mapPath, mapsOfKind} from './api.js';
import {el, formatFixed, formatTime, num, table} from './format.js';
import {centerTime, timeSlider} from './time_slider.js';

const MAX_LISTED = 500;  // states shown (and predicted) at most; the count says how many there are

function modelLink(mapName, name) {
  return el('a', {href: '#/model/' + encodeURIComponent(mapName) + '?name=' + encodeURIComponent(name)}, name);
}

export async function render(root, mapName, params) {
  const {maps: genericMaps, name} = await mapsOfKind('MAP_KIND_GENERIC', mapName);
  if (!name) {
    root.append(el('p', {class: 'muted'}, 'No generic map: create one (fremenctl maps create NAME --generic) or run fremenctl demo.'));
    return null;
  }
  mapName = name;
  const states = await listAll(mapPath(mapName) + '/states', 'states', {}, MAX_LISTED);
  const listed = states.slice(0, MAX_LISTED);
  const names = listed.map((s) => s.name);
  const groups = [...new Set(listed.map((s) => s.group).filter(Boolean))].sort();

  const mapSelect = el('select', {id: 'map-select'}, genericMaps.map((m) => el('option', {value: m.name, selected: m.name === mapName}, m.name)));
  mapSelect.addEventListener('change', () => { location.hash = '#/generic/' + encodeURIComponent(mapSelect.value); });
  const tableBox = el('div', {});
  const topBox = el('div', {id: 'top-states'});
  const groupSelect = el('select', {id: 'group-select', disabled: !groups.length}, groups.map((g) => el('option', {value: g}, g)));
  const topN = el('input', {id: 'top-n', type: 'number', min: 1, max: 10000, value: 5, disabled: !groups.length});
  let request = 0;

  // The selected order of every listed state (one model call each, at most MAX_LISTED, once).
  const orders = Promise.all(names.map((name) => api(mapPath(mapName) + '/model', {query: {'state.name': name}})
      .then((r) => (r.model ? String(num(r.model.selectedOrder)) : 'unobserved'), (e) => e.message)));

  const showTop = async (time) => {
    if (!groups.length) {
      topBox.replaceChildren(el('p', {class: 'muted'}, 'No state of this map has a group.'));
      return;
    }
    const answer = await api(mapPath(mapName) + ':topStates', {method: 'POST', body: {group: groupSelect.value, time, n: Number(topN.value)}});
    topBox.replaceChildren(table(['name', 'p at t'], (answer.states || []).map((s) => [modelLink(mapName, s.name || s.id),
                                                                                       formatFixed(num(s.probability), 3)])));
  };

  const show = async (time) => {
    const current = ++request;
    if (!names.length) {
      tableBox.replaceChildren(el('p', {class: 'muted'}, 'No named states in this map yet (names are given at ingest).'));
      return;
    }
    const now = Date.now() / 1000;
    const [prediction, order] = await Promise.all([
      api(mapPath(mapName) + ':predict', {method: 'POST', body: {states: {names}, times: [now, time]}}), orders]);
    if (current !== request) return;
    const p = prediction.probabilities || [];
    const rows = listed.map((s, j) => el('tr', {'data-name': s.name},
      el('td', {}, modelLink(mapName, s.name)), el('td', {}, s.group || ''), el('td', {class: 'num'}, formatFixed(Number(p[j]), 3)),
      el('td', {class: 'num'}, formatFixed(Number(p[names.length + j]), 3)), el('td', {class: 'num'}, order[j])));
    tableBox.replaceChildren(el('div', {},
      table(['name', 'group', 'p now (' + formatTime(now) + ')', 'p at t', 'order'], rows, {id: 'states-table'}),
      states.length > MAX_LISTED ? el('p', {class: 'muted'}, 'The first ' + MAX_LISTED + ' states by name.') : null));
    await showTop(time);
  };
  const slider = timeSlider(centerTime(params), (t) => show(t).catch((e) => tableBox.replaceChildren(el('p', {class: 'error'}, e.message))));
  groupSelect.addEventListener('change', () => showTop(slider.time()));
  topN.addEventListener('change', () => showTop(slider.time()));

  root.append(
    el('h2', {}, 'Generic map ', mapName),
    el('div', {class: 'controls'}, el('label', {}, 'map ', mapSelect), el('span', {class: 'muted'}, states.length + ' named states')),
    el('div', {class: 'controls'}, slider.element),
    el('div', {class: 'columns'},
      el('div', {}, el('h2', {}, 'States'), tableBox),
      el('div', {}, el('h2', {}, 'Top of a group at t'),
         el('div', {class: 'controls'}, el('label', {}, 'group ', groupSelect), el('label', {}, 'n ', topN)), topBox)));
  await show(slider.time());
  return () => { slider.stop(); request = Infinity; };
}
