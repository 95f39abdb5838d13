// The time control of the grid and generic views: a slider over ±7 days around a center time (the
// route's t=, else now), in 15-minute steps, with the chosen time written beside it, and a play
// button that walks one day forward from the chosen time. onChange(t) is called for every step;
// while playing, the next step waits for the previous onChange to resolve (a frame is drawn before
// the next is asked for).
import {el, formatTime, parseTime} from './format.js';

export const STEP_SECONDS = 15 * 60;
const RANGE_STEPS = 7 * 24 * 4;
const PLAY_STEPS = 24 * 4;
const PLAY_FRAME_MS = 120;

// The center time of a route: its t= (RFC 3339 or seconds), else now rounded down to a step.
export function centerTime(params) {
  const given = parseTime(params.t);
  if (Number.isFinite(given)) return given;
  return Math.floor(Date.now() / 1000 / STEP_SECONDS) * STEP_SECONDS;
}

export function timeSlider(center, onChange) {
  const slider = el('input', {id: 'time-slider', type: 'range', min: -RANGE_STEPS, max: RANGE_STEPS, step: 1, value: 0,
                              'aria-label': 'time'});
  const label = el('span', {id: 'time-label'});
  const play = el('button', {id: 'play-button', type: 'button', title: 'Animate the next 24 hours'}, '▶ play a day');
  const now = el('button', {type: 'button', title: 'Back to the center time'}, 'center');
  let playing = false;
  const time = () => center + Number(slider.value) * STEP_SECONDS;
  const show = () => {
    const offset = Number(slider.value) * STEP_SECONDS / 3600;
    label.textContent = formatTime(time()) + ' (' + (offset >= 0 ? '+' : '') + offset.toFixed(2) + ' h)';
    slider.dataset.time = String(time());
  };
  const changed = () => {
    show();
    return onChange(time());
  };
  slider.addEventListener('input', changed);
  now.addEventListener('click', () => {
    slider.value = 0;
    changed();
  });
  play.addEventListener('click', async () => {
    if (playing) {
      playing = false;
      return;
    }
    playing = true;
    play.textContent = '■ stop';
    const start = Number(slider.value);
    for (let step = 1; step <= PLAY_STEPS && playing && start + step <= RANGE_STEPS; ++step) {
      slider.value = start + step;
      await Promise.all([changed(), new Promise((r) => setTimeout(r, PLAY_FRAME_MS))]);
    }
    playing = false;
    play.textContent = '▶ play a day';
  });
  show();
  return {
    element: el('span', {class: 'time-control'}, el('label', {}, 'time ', slider), ' ', label, ' ', play, ' ', now),
    time,
    stop: () => { playing = false; },
  };
}
