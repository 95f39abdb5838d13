// fremend's JSON API (docs/http.md) from the browser: one fetch wrapper that sends the token the
// user typed, asks for one when fremend answers 401 (no or a bad token) or 403 (a read token where
// a write token is needed) and retries, and turns a google.rpc.Status body into an ApiError whose
// message is the server's own (the same text gRPC clients get).

const TOKEN_KEY = 'fremen.token';

export class ApiError extends Error {
  constructor(httpStatus, code, message) {
    super(message);
    this.httpStatus = httpStatus;
    this.code = code;  // the gRPC code number of the Status body, or 0 when the body was not one
  }
}

export function currentToken() {
  return sessionStorage.getItem(TOKEN_KEY) || '';
}

function setToken(token) {
  if (token) sessionStorage.setItem(TOKEN_KEY, token);
  else sessionStorage.removeItem(TOKEN_KEY);
}

// One prompt at a time: calls refused together wait for the same answer.
let pendingPrompt = null;

// Shows the token dialog; resolves true when the user gave a token (calls are then retried).
export function askForToken(reason) {
  if (pendingPrompt) return pendingPrompt;
  const dialog = document.getElementById('token-dialog');
  const input = document.getElementById('token-input');
  document.getElementById('token-reason').textContent = reason;
  input.value = currentToken();
  pendingPrompt = new Promise((resolve) => {
    dialog.addEventListener('close', () => {
      pendingPrompt = null;
      if (dialog.returnValue === 'save' && input.value.trim()) {
        setToken(input.value.trim());
        resolve(true);
      } else {
        if (dialog.returnValue === 'clear') setToken('');
        resolve(false);
      }
    }, {once: true});
  });
  dialog.showModal();
  input.focus();
  return pendingPrompt;
}

// {a: 1, b: [2, 3]} → "a=1&b=2&b=3" (a repeated field is a repeated parameter, as the gateway reads).
export function queryString(params) {
  const search = new URLSearchParams();
  for (const [key, value] of Object.entries(params)) {
    if (value === undefined || value === null) continue;
    for (const item of Array.isArray(value) ? value : [value]) search.append(key, String(item));
  }
  return search.toString();
}

async function errorOf(response) {
  const text = await response.text();
  try {
    const status = JSON.parse(text);
    if (status && typeof status.message === 'string') {
      return new ApiError(response.status, status.code || 0, status.message);
    }
  } catch (e) {
    // Not a Status body (a proxy's page, a plain-text 401): its text is the message.
  }
  return new ApiError(response.status, 0, text.trim() || response.statusText || 'HTTP ' + response.status);
}

// Calls the API: api('/v1/maps/demo/stats'), api('/v1/maps/demo:predict', {method: 'POST', body}),
// api('/v1/maps/demo/region', {query: {...}}). Resolves to the parsed JSON answer; rejects with an
// ApiError carrying the server's message.
export async function api(path, {method = 'GET', body, query} = {}) {
  const url = path + (query ? '?' + queryString(query) : '');
  for (;;) {
    const headers = {Accept: 'application/json'};
    const token = currentToken();
    if (token) headers.Authorization = 'Bearer ' + token;
    if (body !== undefined) headers['Content-Type'] = 'application/json';
    const response = await fetch(url, {method, headers, body: body === undefined ? undefined : JSON.stringify(body)});
    if (response.ok) {
      const text = await response.text();
      return text ? JSON.parse(text) : {};
    }
    const error = await errorOf(response);
    if (response.status === 401 || response.status === 403) {
      const reason = response.status === 401 ? 'fremend wants a token: ' + error.message
                                             : 'This needs a write token: ' + error.message;
      if (await askForToken(reason)) continue;
    }
    throw error;
  }
}

// Every item of a paged list (ListMaps, ListStates, ListOperations), following next_page_token.
export async function listAll(path, field, query = {}, limit = 10000) {
  const items = [];
  let pageToken = '';
  do {
    const page = await api(path, {query: {...query, page_size: 1000, page_token: pageToken || undefined}});
    items.push(...(page[field] || []));
    pageToken = page.nextPageToken || '';
  } while (pageToken && items.length < limit);
  return items;
}

// The maps of one kind ('MAP_KIND_GRID', 'MAP_KIND_GENERIC') and the one a view shows: `chosen`,
// else the first of them ('' when there is none).
export async function mapsOfKind(kind, chosen) {
  const maps = (await listAll('/v1/maps', 'maps')).filter((m) => m.kind === kind);
  return {maps, name: chosen || (maps.length ? maps[0].name : '')};
}

// A bytes field of protobuf's JSON mapping (base64) → its bytes.
export function bytesField(base64) {
  const binary = atob(base64 || '');
  return Uint8Array.from(binary, (c) => c.charCodeAt(0));
}

export function mapPath(map) {
  return '/v1/maps/' + encodeURIComponent(map);
}

// Shows (or with null hides) an error above the current view.
export function showError(error) {
  const banner = document.getElementById('error-banner');
  if (!error) {
    banner.hidden = true;
    banner.textContent = '';
    return;
  }
  const status = error instanceof ApiError && error.httpStatus ? ' (HTTP ' + error.httpStatus + ')' : '';
  banner.textContent = (error.message || String(error)) + status;
  banner.hidden = false;
}
