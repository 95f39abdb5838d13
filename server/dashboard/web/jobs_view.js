// Jobs: the update operations of every map (GET /v1/operations) with their progress, refreshed
// every 2 s; "run the update now" (POST /v1/maps/{map}:runUpdate, which needs a write token: the
// 403 of a read token opens the token prompt); the last job's record and the maps that failed to
// open, with their reasons (GET /v1/status).
import {api, listAll, mapPath} from './api.js';
import {el, formatCount, formatDuration, formatFixed, formatTime, num, table, timestampSeconds} from './format.js';

const REFRESH_MS = 2000;

function stageOf(operation) {
  const stage = (operation.stage || '').replace('OPERATION_STAGE_', '').toLowerCase();
  if (!operation.done) return stage || 'queued';
  if (operation.error && operation.error.code) return 'failed';
  return operation.cancelRequested ? 'cancelled' : 'done';
}

function progressOf(operation) {
  const p = operation.progress || {};
  const total = num(p.statesTotal), done = num(p.statesDone);
  if (operation.done) return operation.update ? formatCount(operation.update.statesPublished) + ' states published' : '';
  if (!total) return 'starting';
  return el('span', {}, el('progress', {max: total, value: done}), ' ' + formatCount(done) + ' / ' + formatCount(total) +
            (num(p.etaSeconds) ? ', ' + formatDuration(p.etaSeconds) + ' left' : ''));
}

function operationRows(operations) {
  return operations.map((o) => el('tr', {'data-operation': o.name, 'data-stage': stageOf(o)},
    el('td', {}, o.name), el('td', {}, o.map), el('td', {}, stageOf(o)), el('td', {}, progressOf(o)), el('td', {}, o.trigger || ''),
    el('td', {}, formatTime(timestampSeconds(o.createTime))), el('td', {}, o.endTime ? formatTime(timestampSeconds(o.endTime)) : ''),
    el('td', {class: o.error?.code ? 'error' : undefined}, o.error?.message || o.message || '')));
}

function jobRecord(operation) {
  if (!operation) return el('p', {class: 'muted'}, 'No update job has finished since the daemon started.');
  const u = operation.update || {};
  const rows = [['operation', operation.name], ['map', operation.map], ['result', stageOf(operation)],
                ['ended', formatTime(timestampSeconds(operation.endTime))], ['duration', formatDuration(u.durationSeconds)],
                ['states published', formatCount(u.statesPublished)],
                ['ε_p before → after', formatFixed(num(u.predictionErrorBefore), 4) + ' → ' + formatFixed(num(u.predictionErrorAfter), 4)],
                ['states by order', (u.orderHistogram || []).map((n, k) => k + ': ' + formatCount(n)).join(', ') || '—']];
  if (operation.error?.message) rows.push(['error', operation.error.message]);
  return el('dl', {class: 'facts', id: 'last-job'}, rows.map(([k, v]) => [el('dt', {}, k), el('dd', {}, v)]));
}

export async function render(root) {
  const maps = await listAll('/v1/maps', 'maps');
  const mapSelect = el('select', {id: 'update-map'}, maps.map((m) => el('option', {value: m.name}, m.name)));
  const runMessage = el('span', {id: 'run-update-result', class: 'muted'});
  const run = el('button', {id: 'run-update', type: 'button', disabled: !maps.length}, 'Run the update now');
  const operationsBox = el('div', {});
  const lastBox = el('div', {});
  const failedBox = el('div', {});

  const refresh = async () => {
    const [operations, status] = await Promise.all([listAll('/v1/operations', 'operations'), api('/v1/status')]);
    operationsBox.replaceChildren(operations.length
      ? table(['operation', 'map', 'stage', 'progress', 'trigger', 'created', 'ended', 'message'], operationRows(operations), {id: 'operations-table'})
      : el('p', {class: 'muted', id: 'operations-table'}, 'No update operations.'));
    const finished = [...(status.lastUpdates || [])].sort((a, b) => timestampSeconds(b.endTime) - timestampSeconds(a.endTime));
    lastBox.replaceChildren(jobRecord(finished[0]));
    const failed = status.failedMaps || [];
    failedBox.replaceChildren(failed.length ? table(['map', 'why it failed to open'], failed.map((f) => [f.map, f.error]), {id: 'failed-maps'})
                                            : el('p', {class: 'muted', id: 'failed-maps'}, 'No failed maps.'));
  };
  run.addEventListener('click', async () => {
    run.disabled = true;
    runMessage.className = 'muted';
    runMessage.textContent = 'starting…';
    try {
      const operation = await api(mapPath(mapSelect.value) + ':runUpdate', {method: 'POST', body: {}});
      runMessage.textContent = 'started ' + operation.name + ' (' + stageOf(operation) + ')';
      runMessage.dataset.operation = operation.name;
      await refresh();
    } catch (error) {
      runMessage.className = 'error';
      runMessage.textContent = error.message;
    } finally {
      run.disabled = false;
    }
  });

  root.append(
    el('h2', {}, 'Run an update'),
    el('div', {class: 'controls'}, el('label', {}, 'map ', mapSelect), run, runMessage),
    el('p', {class: 'hint'}, 'Needs a write token when fremend has tokens: a read token is refused and the token prompt opens.'),
    el('h2', {}, 'Update operations'), operationsBox,
    el('h2', {}, 'The last job'), lastBox,
    el('h2', {}, 'Failed maps'), failedBox);
  await refresh();
  const timer = setInterval(() => refresh().catch((e) => { runMessage.className = 'error'; runMessage.textContent = e.message; }), REFRESH_MS);
  return () => clearInterval(timer);
}
