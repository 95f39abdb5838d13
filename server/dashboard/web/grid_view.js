// A grid map at a time t: GET /v1/maps/{map}/region of one z-plane (output FLOAT for p, ENTROPY,
// or STATES at confidence c) drawn on a canvas, one image pixel per cell, scaled up without
// smoothing. Gray = 255·(1 − p): occupied (walls) dark, free floor light — region.png's mapping,
// so the canvas and `curl …/region.png` look alike; entropy 255·(1 − H); states 0 occupied / 255
// free. Image up = +y (row 0 is the highest y). Wheel zooms about the cursor, drag pans, hover
// tells a cell's value, a click opens the cell's model (#/model/MAP?x=&y=&z=).
//
// For tests and scripts the canvas says what it shows in data attributes: data-map, data-mode,
// data-z, data-time (the time of the region drawn last), data-scale (canvas pixels per cell),
// data-offset-x / data-offset-y (where the image's top-left corner is) and data-height (cells in y).
import {api, bytesField, mapPath, mapsOfKind} from './api.js';
import {el, formatTime, num} from './format.js';
import {centerTime, timeSlider} from './time_slider.js';

const OUTPUTS = {probability: 'REGION_OUTPUT_FLOAT', entropy: 'REGION_OUTPUT_ENTROPY', state: 'REGION_OUTPUT_STATES'};
const MAX_CANVAS = {width: 960, height: 600};

// The region's values as numbers in [0, 1] (p, H or the 0/1 state), x fastest then y.
export function regionValues(response, mode, cells) {
  if (mode === 'state') {
    const bytes = bytesField(response.bytesValues);
    return Float32Array.from({length: cells}, (_, i) => bytes[i] || 0);
  }
  const values = response.floatValues || [];
  return Float32Array.from({length: cells}, (_, i) => Number(values[i] ?? 0));
}

// The gray of a value: p and the state 1 → dark (255·(1 − v)), as region.png draws it.
export function grayOf(value) {
  return Math.round(255 * (1 - Math.min(1, Math.max(0, value))));
}

export async function render(root, mapName, params) {
  const {maps: gridMaps, name} = await mapsOfKind('MAP_KIND_GRID', mapName);
  if (!name) {
    root.append(el('p', {class: 'muted'}, 'No grid map: create one (fremenctl maps create NAME --resolution R --size X Y) ' +
                   'or run fremenctl demo.'));
    return null;
  }
  mapName = name;
  const map = (await api(mapPath(mapName))).map;
  const size = map.grid?.size || {};
  const width = num(size.x), height = num(size.y), depth = Math.max(1, num(size.z));
  const state = {mode: 'probability', confidence: 0.5, z: Math.min(depth - 1, Math.max(0, num(params.z))), values: null,
                 drawnMode: 'probability', request: 0};
  const fit = Math.max(1, Math.min(MAX_CANVAS.width / width, MAX_CANVAS.height / height));
  const canvas = el('canvas', {id: 'grid-canvas', width: Math.min(MAX_CANVAS.width, Math.ceil(width * fit)),
                               height: Math.min(MAX_CANVAS.height, Math.ceil(height * fit)), 'data-map': mapName});
  const view = {scale: fit, offsetX: 0, offsetY: 0};
  const image = document.createElement('canvas');
  image.width = width;
  image.height = height;
  const hover = el('div', {id: 'hover-info', class: 'muted'}, 'Hover a cell for its value; click it for its model.');
  const status = el('span', {id: 'grid-status', class: 'muted'});

  const paint = () => {
    const g = canvas.getContext('2d');
    g.setTransform(1, 0, 0, 1, 0, 0);
    g.fillStyle = '#c9d3dd';
    g.fillRect(0, 0, canvas.width, canvas.height);
    g.imageSmoothingEnabled = false;
    g.drawImage(image, view.offsetX, view.offsetY, width * view.scale, height * view.scale);
    Object.assign(canvas.dataset, {scale: String(view.scale), offsetX: String(view.offsetX), offsetY: String(view.offsetY),
                                   height: String(height), width: String(width)});
  };

  const draw = async (time) => {
    const request = ++state.request;
    const mode = state.mode;
    const query = {'lo.x': 0, 'lo.y': 0, 'hi.x': width, 'hi.y': height, time, output: OUTPUTS[mode]};
    if (depth > 1) Object.assign(query, {'lo.z': state.z, 'hi.z': state.z + 1});
    if (mode === 'state') query.confidence = state.confidence;
    status.textContent = 'loading…';
    const response = await api(mapPath(mapName) + '/region', {query});
    if (request !== state.request) return;  // a later time or mode was asked for meanwhile
    const values = regionValues(response, mode, width * height);
    const pixels = new ImageData(width, height);
    for (let y = 0; y < height; ++y) {
      const row = height - 1 - y;
      for (let x = 0; x < width; ++x) {
        const gray = grayOf(values[y * width + x]);
        const at = 4 * (row * width + x);
        pixels.data[at] = pixels.data[at + 1] = pixels.data[at + 2] = gray;
        pixels.data[at + 3] = 255;
      }
    }
    image.getContext('2d').putImageData(pixels, 0, 0);
    state.values = values;
    state.drawnMode = mode;
    paint();
    Object.assign(canvas.dataset, {time: String(time), mode, z: String(state.z)});
    status.textContent = formatTime(time) + ', ' + mode + (mode === 'state' ? ' at c = ' + state.confidence : '');
  };
  const redraw = (time) => draw(time).catch((error) => { status.textContent = error.message; status.className = 'error'; });

  const slider = timeSlider(centerTime(params), redraw);

  // The cell under a mouse event, or null outside the grid.
  const cellAt = (event) => {
    const box = canvas.getBoundingClientRect();
    const px = (event.clientX - box.left) * canvas.width / box.width, py = (event.clientY - box.top) * canvas.height / box.height;
    const x = Math.floor((px - view.offsetX) / view.scale), row = Math.floor((py - view.offsetY) / view.scale);
    const y = height - 1 - row;
    if (x < 0 || x >= width || y < 0 || y >= height) return null;
    return {x, y, px, py};
  };
  let drag = null;
  canvas.addEventListener('mousedown', (event) => {
    drag = {x: event.clientX, y: event.clientY, moved: false};
  });
  const onUp = (event) => {
    if (!drag) return;
    const click = !drag.moved && event.target === canvas;
    drag = null;
    const cell = click && cellAt(event);
    if (cell) {
      location.hash = '#/model/' + encodeURIComponent(mapName) + '?x=' + cell.x + '&y=' + cell.y + '&z=' + state.z +
                      '&t=' + slider.time();
    }
  };
  window.addEventListener('mouseup', onUp);
  canvas.addEventListener('mousemove', (event) => {
    if (drag && (drag.moved || Math.abs(event.clientX - drag.x) + Math.abs(event.clientY - drag.y) > 3)) {
      view.offsetX += event.clientX - drag.x;
      view.offsetY += event.clientY - drag.y;
      drag.x = event.clientX;
      drag.y = event.clientY;
      drag.moved = true;
      paint();
      return;
    }
    const cell = cellAt(event);
    if (!cell || !state.values) {
      hover.textContent = '';
      return;
    }
    const value = state.values[cell.y * width + cell.x];
    const what = {probability: 'p', entropy: 'H', state: 'state'}[state.drawnMode];
    hover.textContent = 'cell (' + cell.x + ', ' + cell.y + (depth > 1 ? ', ' + state.z : '') + '): ' + what + ' = ' +
                        (state.drawnMode === 'state' ? String(value) : value.toFixed(3));
    Object.assign(hover.dataset, {x: String(cell.x), y: String(cell.y), value: String(value)});
  });
  canvas.addEventListener('wheel', (event) => {
    event.preventDefault();
    const box = canvas.getBoundingClientRect();
    const px = event.clientX - box.left, py = event.clientY - box.top;
    const factor = event.deltaY < 0 ? 1.25 : 0.8;
    const scale = Math.min(64 * fit, Math.max(fit / 8, view.scale * factor));
    view.offsetX = px - (px - view.offsetX) * scale / view.scale;
    view.offsetY = py - (py - view.offsetY) * scale / view.scale;
    view.scale = scale;
    paint();
  }, {passive: false});

  const mapSelect = el('select', {id: 'map-select'}, gridMaps.map((m) => el('option', {value: m.name, selected: m.name === mapName}, m.name)));
  mapSelect.addEventListener('change', () => { location.hash = '#/grid/' + encodeURIComponent(mapSelect.value); });
  const modeSelect = el('select', {id: 'mode-select'}, Object.keys(OUTPUTS).map((m) => el('option', {value: m}, m)));
  const confidence = el('input', {id: 'confidence', type: 'number', min: 0, max: 1, step: 0.05, value: 0.5, disabled: true});
  modeSelect.addEventListener('change', () => {
    state.mode = modeSelect.value;
    confidence.disabled = state.mode !== 'state';
    redraw(slider.time());
  });
  confidence.addEventListener('change', () => {
    state.confidence = Math.min(1, Math.max(0, Number(confidence.value)));
    redraw(slider.time());
  });
  const planes = depth > 1 ? el('select', {id: 'z-select'}, Array.from({length: depth}, (_, z) => el('option', {value: z, selected: z === state.z}, 'z = ' + z))) : null;
  planes?.addEventListener('change', () => {
    state.z = Number(planes.value);
    redraw(slider.time());
  });
  const reset = el('button', {type: 'button', onclick: () => { Object.assign(view, {scale: fit, offsetX: 0, offsetY: 0}); paint(); }}, 'fit');

  root.append(
    el('h2', {}, 'Grid map ', mapName),
    el('div', {class: 'controls'}, el('label', {}, 'map ', mapSelect), el('label', {}, 'mode ', modeSelect),
       el('label', {}, 'confidence c ', confidence), planes ? el('label', {}, 'plane ', planes) : null, reset),
    el('div', {class: 'controls'}, slider.element),
    el('div', {class: 'canvas-box'}, canvas), hover, status,
    el('p', {class: 'hint'}, width + ' × ' + height + (depth > 1 ? ' × ' + depth : '') + ' cells of ' + num(map.grid?.resolution) +
       ' m. Gray = 255·(1 − p): occupied dark, free light; entropy: 255·(1 − H), uncertain cells dark; state: ' +
       'black where p ≥ c. Wheel: zoom; drag: pan; click: the cell\'s model.'));
  await draw(slider.time());
  return () => {
    slider.stop();
    state.request = Infinity;
    window.removeEventListener('mouseup', onUp);
  };
}
