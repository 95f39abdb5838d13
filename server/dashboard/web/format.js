// How the dashboard writes numbers and times: every time in UTC (the maps' rhythms are in the
// robots' clock; one zone for everyone reading the page), protobuf's JSON values (64-bit integers
// come as strings, Timestamps as RFC 3339, defaults omitted) read into numbers.

// A uint64/double field of protobuf's JSON mapping → Number (absent = 0).
export function num(value) {
  if (value === undefined || value === null || value === '') return 0;
  return Number(value);
}

// seconds → "2023-11-27 09:00 UTC" (with seconds when it has them).
export function formatTime(seconds) {
  if (!Number.isFinite(seconds)) return '—';
  const iso = new Date(seconds * 1000).toISOString();
  const hms = iso.slice(11, 19);
  return iso.slice(0, 10) + ' ' + (hms.endsWith(':00') ? hms.slice(0, 5) : hms) + ' UTC';
}

// seconds → "Mon 27 Nov 09:00" (a chart's tick).
export function formatTick(seconds) {
  const d = new Date(seconds * 1000);
  const day = ['Sun', 'Mon', 'Tue', 'Wed', 'Thu', 'Fri', 'Sat'][d.getUTCDay()];
  return day + ' ' + d.toISOString().slice(11, 16);
}

// A google.protobuf.Timestamp in JSON ("2023-11-27T09:00:00Z") → seconds, or NaN when unset.
export function timestampSeconds(value) {
  if (!value) return NaN;
  return Date.parse(value) / 1000;
}

// "2023-11-27T09:00:00Z", "2023-11-27T09:00Z" or seconds since the epoch → seconds; NaN otherwise.
export function parseTime(text) {
  if (text === undefined || text === null || text === '') return NaN;
  if (/^-?\d+(\.\d+)?(e\d+)?$/i.test(text)) return Number(text);
  return Date.parse(text) / 1000;
}

export function formatCount(value) {
  return num(value).toLocaleString('en-US');
}

export function formatBytes(value) {
  let n = num(value);
  for (const unit of ['B', 'KiB', 'MiB', 'GiB', 'TiB']) {
    if (n < 1024 || unit === 'TiB') return (unit === 'B' ? n : n.toFixed(1)) + ' ' + unit;
    n /= 1024;
  }
  return String(n);
}

export function formatFixed(value, digits = 3) {
  return Number.isFinite(value) ? value.toFixed(digits) : '—';
}

export function formatDuration(seconds) {
  const s = num(seconds);
  if (s < 1) return (s * 1000).toFixed(0) + ' ms';
  if (s < 120) return s.toFixed(1) + ' s';
  if (s < 7200) return (s / 60).toFixed(1) + ' min';
  if (s < 172800) return (s / 3600).toFixed(1) + ' h';
  return (s / 86400).toFixed(1) + ' d';
}

// An element with attributes and children: el('td', {class: 'num'}, '3').
export function el(tag, attributes = {}, ...children) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attributes)) {
    if (value === undefined || value === null || value === false) continue;
    if (key.startsWith('on')) node.addEventListener(key.slice(2), value);
    else node.setAttribute(key, value === true ? '' : value);
  }
  for (const child of children.flat(Infinity)) {
    if (child === undefined || child === null) continue;
    node.append(child instanceof Node ? child : String(child));
  }
  return node;
}

// A table of rows (arrays of cells: text, numbers right-aligned, or nodes).
export function table(headers, rows, attributes = {}) {
  const cell = (value) => (typeof value === 'number' ? el('td', {class: 'num'}, String(value)) : el('td', {}, value));
  return el('table', attributes,
    el('thead', {}, el('tr', {}, headers.map((h) => el('th', {}, h)))),
    el('tbody', {}, rows.map((row) => (row instanceof Node ? row : el('tr', {}, row.map(cell))))));
}
