// tessera web UI: jobs, submit, live preview, accuracy-against-time plots.
// Talks only to the public API v1 (docs/design.md §5, proto/openapi.yaml).
import uPlot from 'uplot';
import { decodeExr } from './exr.js';
import { makeTar } from './tar.js';
import 'uplot/dist/uPlot.min.css';
import './style.css';

const $ = (id) => document.getElementById(id);
const query = new URLSearchParams(location.search);
const token = query.get('access_token');
const authHeaders = token ? { Authorization: 'Bearer ' + token } : {};
// URLs the browser fetches by itself (img, EventSource, download links) carry the token as a query.
const withToken = (url) => (token ? url + (url.includes('?') ? '&' : '?') + 'access_token=' + encodeURIComponent(token) : url);

async function api(path, opts = {}) {
  const r = await fetch(path, { ...opts, headers: { ...authHeaders, ...(opts.headers || {}) } });
  let body = null;
  try { body = await r.json(); } catch { /* not JSON */ }
  return { status: r.status, ok: r.ok, body };
}

// ------------------------------------------------------------------ state
const jobs = new Map();      // id -> latest status document
// id -> [{t, err, spp}]: points seen while this page (or an earlier load of it in this tab,
// through sessionStorage) was open; the API reports only the present. spp is the server's
// spp_mean (samples held ÷ pixels, API v1.4), the quantity of the history's points too, so
// the plotted series never runs backwards (a live spp_done after a history tick did).
const history = new Map();
try {
  for (const [id, h] of JSON.parse(sessionStorage.getItem('tessera.history') || '[]')) history.set(id, h);
} catch { /* storage unavailable or damaged: start afresh */ }
let saveTimer = null;
function saveHistory() {
  clearTimeout(saveTimer);
  saveTimer = setTimeout(() => {
    try { sessionStorage.setItem('tessera.history', JSON.stringify([...history].filter(([id]) => jobs.has(id)))); } catch { /* full */ }
  }, 300);
}
let selectedId = null;       // the job in the preview
let compareId = '';          // the job overlaid on the plots
let streams = new Map();     // id -> EventSource (selected and compared jobs)

// Jobs whose whole series came from the server after they finished: nothing is added to it
// (a status poll's elapsed time can lie a little past the history's end point).
const complete = new Set();

function addPoint(id, t, err, spp) {
  if (!(t > 0) || complete.has(id)) return;
  let h = history.get(id);
  if (!h) history.set(id, (h = []));
  const last = h[h.length - 1];
  if (last && last.spp === spp && last.err === err) return;
  if (last && t < last.t) return;
  if (spp > 0 && last && last.spp > spp) return; // an older reading than the last point
  h.push({ t, err: err == null || !(err > 0) ? null : err, spp: spp > 0 ? spp : null });
  saveHistory();
}

// ------------------------------------------------------------------ formatting
function fmtRate(v) {
  if (v == null || !isFinite(v)) return '–';
  if (v >= 1e9) return (v / 1e9).toFixed(2) + ' G';
  if (v >= 1e6) return (v / 1e6).toFixed(2) + ' M';
  if (v >= 1e3) return (v / 1e3).toFixed(1) + ' k';
  return v.toFixed(0);
}
function fmtTime(s) {
  if (s == null || !isFinite(s)) return '–';
  if (s < 60) return s.toFixed(1) + ' s';
  const m = Math.floor(s / 60);
  return m + ' min ' + Math.round(s - 60 * m) + ' s';
}
// Relative errors are shown in percent, as the CLI and the readout say them.
const fmtPct = (e) => (e == null || !isFinite(e) ? 'n/a' : (100 * e).toPrecision(3) + '%');
// The effects a job simulates (its status's identifiers), in words; the identifier is the title.
const EFFECT_TEXT = { delta_lights: 'point and spot lights', area_lights: 'area lights', environment: 'environment light',
  diffuse: 'diffuse', glossy: 'glossy', specular_reflection: 'mirror reflection', specular_transmission: 'refraction',
  fourier: 'Fourier BSDFs', depth_of_field: 'depth of field', indirect: 'indirect light', lobe_choice: 'layered materials',
  media: 'participating media', motion: 'motion blur' };
const effectText = (e) => EFFECT_TEXT[e] || e.replace(/_/g, ' ');
const finished = (st) => st === 'done' || st === 'cancelled' || st === 'failed';
const jobLabel = (j) => (j.name ? j.name + ' ' : '') + '(' + j.id + ')';

// Why a job stopped (its halt_reason), in words.
const HALT_TEXT = { time_limit: 'time limit reached', target_error: 'target error reached', cancelled: 'cancelled',
  spp: 'all samples', restored: 'restored' };
// A running job's progress: the server's fraction of its first halting bound and the ETA.
const progressOf = (j) => Math.round(100 * (j.progress || 0)) + '%' + (j.eta_s != null ? ' · ETA ' + fmtTime(j.eta_s) : '');

// A job's import warnings (API v1.3 `warnings`: what loading its scene mapped or dropped, one
// sentence each with its position, e.g. `scene.pbrt:11:1: Sampler "halton" is mapped …`; the
// server keeps 64 and counts the rest in `warnings_dropped`).
const warningCount = (j) => (Array.isArray(j.warnings) ? j.warnings.length : 0) + (j.warnings_dropped || 0);
const plural = (n, word) => n + ' ' + word + (n === 1 ? '' : 's');

// ------------------------------------------------------------------ jobs list
function el(tag, attrs = {}, ...kids) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === 'class') e.className = v;
    else if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
    else if (v !== undefined && v !== null && v !== false) e.setAttribute(k, v === true ? '' : v);
  }
  for (const k of kids) e.append(k);
  return e;
}

function renderJobs() {
  const tbody = $('jobs').querySelector('tbody');
  const list = [...jobs.values()].sort((a, b) => b.created_at - a.created_at);
  $('jobs-empty').hidden = list.length > 0;
  const rows = list.map((j) => {
    // progress: the server's (0–1 of the first halting bound, moving within a pass); a job
    // halted by its time limit or target error reads as such, not as a partial bar.
    const frac = j.progress != null ? j.progress : j.spp_target > 0 ? Math.min(1, j.spp_done / j.spp_target) : 0;
    const progressText = finished(j.state) ? (HALT_TEXT[j.halt_reason] || j.state) : progressOf(j);
    const row = el('tr', { 'data-id': j.id, class: j.id === selectedId ? 'selected' : '' },
      el('td', { 'data-label': 'Job' }, el('button', { class: 'link', type: 'button', 'aria-label': 'show job ' + jobLabel(j) + ' in the preview',
        'aria-pressed': j.id === selectedId ? 'true' : 'false', onclick: () => select(j.id) }, j.name || j.id),
        // The id under the name (a narrow column beside the preview), with the integrator.
        el('div', { class: 'muted small' }, (j.name ? j.id + ' · ' : '') + (j.integrator || ''))),
      el('td', { 'data-label': 'State' }, el('span', { class: 'state state-' + j.state, title: j.error || j.halt_reason || '' }, j.state),
        j.error ? el('div', { class: 'err small' }, j.error) : '',
        warningCount(j) ? el('div', { class: 'warn small', title: 'listed under the preview when the job is shown' },
          plural(warningCount(j), 'import warning')) : ''),
      el('td', { 'data-label': 'Progress' }, el('progress', { max: '1', value: String(frac), 'aria-label': 'progress of ' + j.id }),
        el('span', { class: 'small progress-text' }, ' ' + progressText)),
      el('td', { 'data-label': 'spp', class: 'num' }, j.spp_done + ' / ' + j.spp_target),
      el('td', { 'data-label': 'Samples/s', class: 'num' }, fmtRate(j.samples_per_s)),
      el('td', { 'data-label': 'Error', class: 'num', title: j.error_estimate == null ? 'not known yet (fewer than 2 samples per pixel)' : '' },
        fmtPct(j.error_estimate)),
      el('td', { 'data-label': 'Elapsed', class: 'num' }, fmtTime(j.elapsed_s)),
      el('td', { 'data-label': 'Effects', class: 'effects small', title: (j.effects || []).join(', ') },
        (j.effects || []).map(effectText).join(', ')),
      el('td', { 'data-label': 'Actions', class: 'actions' },
        finished(j.state)
          ? el('button', { type: 'button', class: 'cancel', 'aria-label': 'delete job ' + j.id,
            onclick: () => removeJob(j.id) }, 'Delete')
          : el('button', { type: 'button', class: 'cancel', 'aria-label': 'cancel job ' + j.id,
            onclick: () => cancel(j.id) }, 'Cancel'),
        el('a', { href: withToken(j.urls.exr), download: j.id + '.exr', 'aria-label': 'download EXR of job ' + j.id }, 'EXR'),
        el('a', { href: withToken(j.urls.png), download: j.id + '.png', 'aria-label': 'download PNG of job ' + j.id }, 'PNG')));
    return row;
  });
  // Keep keyboard focus across the refresh: remember which control had it.
  const active = document.activeElement;
  const activeRow = active && active.closest && active.closest('#jobs tr');
  const focusKey = activeRow ? [activeRow.dataset.id, [...activeRow.querySelectorAll('button,a')].indexOf(active)] : null;
  tbody.replaceChildren(...rows);
  showWarnings(selectedId ? jobs.get(selectedId) : null);
  showFarm(selectedId ? jobs.get(selectedId) : null);
  if (focusKey) {
    const r = tbody.querySelector(`tr[data-id="${focusKey[0]}"]`);
    const c = r && r.querySelectorAll('button,a')[focusKey[1]];
    if (c) c.focus();
  }
  // The overlay choice: other jobs.
  const sel = $('compare');
  const want = ['', ...list.filter((j) => j.id !== selectedId).map((j) => j.id)];
  const have = [...sel.options].map((o) => o.value);
  if (want.join() !== have.join()) {
    sel.replaceChildren(el('option', { value: '' }, '(none)'),
      ...list.filter((j) => j.id !== selectedId).map((j) => el('option', { value: j.id }, jobLabel(j) + ' · ' + (j.integrator || ''))));
    sel.value = want.includes(compareId) ? compareId : '';
    if (sel.value !== compareId) setCompare(sel.value);
  }
}

// The job list comes in pages of 100, newest first (API v1.2): the page lists as many pages
// as asked for (one, plus one per click on "List 100 more"), so a server holding thousands of
// jobs costs each poll one page, not all of them.
let listPages = 1;
async function listJobs() {
  let r = null, all = [], after = null;
  for (let page = 0; page < listPages; page++) {
    r = await api('/api/v1/jobs?limit=100' + (after ? '&after=' + encodeURIComponent(after) : ''));
    if (!r.ok || !r.body) return r;
    all = all.concat(r.body.jobs);
    after = r.body.next;
    if (!after) break;
  }
  $('jobs-more').hidden = !after;
  return { ...r, body: { jobs: all, next: after } };
}

let pollTimer = null;
async function poll() {
  clearTimeout(pollTimer);
  try {
    const r = await listJobs();
    if (r.ok && r.body) {
      $('conn').textContent = 'connected';
      $('conn').className = 'conn ok';
      const seen = new Set();
      for (const j of r.body.jobs) {
        seen.add(j.id);
        jobs.set(j.id, j);
        addPoint(j.id, j.elapsed_s, j.error_estimate, j.spp_mean);
      }
      for (const id of [...jobs.keys()]) if (!seen.has(id)) jobs.delete(id);
      renderJobs();
      if (!selectedId && r.body.jobs.length) {
        const j = r.body.jobs.find((j) => j.state === 'running') || r.body.jobs[0];
        select(j.id);
      }
      updatePlots();
    } else {
      $('conn').textContent = 'server answered ' + r.status + (r.body && r.body.error ? ': ' + r.body.error : '');
      $('conn').className = 'conn bad';
    }
  } catch (e) {
    $('conn').textContent = 'server unreachable, retrying…';
    $('conn').className = 'conn bad';
  }
  pollTimer = setTimeout(poll, 1000);
}

// DELETE of a finished job removes it, its image and its checkpoint on the server (and
// frees its place under --max-jobs); the next poll drops it from the list.
async function removeJob(id) {
  if (!window.confirm('Delete job ' + id + ' and its image? This cannot be undone.')) return;
  const r = await api('/api/v1/jobs/' + encodeURIComponent(id), { method: 'DELETE' });
  if (r.status !== 204 && r.status !== 404) return;
  if (id === selectedId) { closeStream(id); selectedId = null; }
  if (id === compareId) setCompare('');
  jobs.delete(id);
  renderJobs();
  poll();
}

async function cancel(id) {
  const r = await api('/api/v1/jobs/' + encodeURIComponent(id) + '/cancel', {
    method: 'POST',
    headers: { 'Content-Type': 'application/json' }, // without a token the server takes only JSON POSTs
  });
  if (r.ok && r.body) jobs.set(id, r.body);
  renderJobs();
  poll();
}

// ------------------------------------------------------------------ preview
// The canvas holds the film window at its own resolution, one canvas pixel per image pixel;
// the view (fit, 1:1, zoom about the cursor, pan) is a CSS transform of the stage holding
// it, smooth (bilinear) while an image pixel is smaller than a screen pixel and crisp
// (nearest) once it is larger, as in tev. Tiles come as EXR (the real floats: R, G, B, the
// variance of each pixel's mean R.var, G.var, B.var, and its sample count), so the exposure
// works on linear radiance and the readout shows the numbers the API serves; where the EXR
// cannot be read the tile's 8-bit sRGB PNG is used instead (colour only). `base` keeps the
// unscaled pixels, so changing the exposure or the channel repaints without refetching.
const canvas = $('canvas'), overlay = $('overlay'), viewport = $('viewport'), stage = $('stage');
const ctx = canvas.getContext('2d', { willReadFrequently: true });
const octx = overlay.getContext('2d');
// {w, h, rgb: Float32Array linear (w·h·3), vars: Float32Array (w·h·3, NaN when unknown),
//  count: Float32Array (w·h, NaN when unknown), alpha: Uint8Array, maxCount}
let base = null;
let film = null;                 // the selected job's film
let tileSpp = new Map();         // "tx,ty" -> spp painted
let passSpp = 0, jobState = '';
let useExr = typeof DecompressionStream === 'function';

const srgbToLinear = (c) => (c <= 0.04045 ? c / 12.92 : Math.pow((c + 0.055) / 1.055, 2.4));
const linearToSrgb = (c) => (c <= 0.0031308 ? 12.92 * c : 1.055 * Math.pow(c, 1 / 2.4) - 0.055);

// False colour: viridis, from its published control points, interpolated into 256 entries.
const LUT = (() => {
  const stops = [[0x44, 0x01, 0x54], [0x48, 0x28, 0x78], [0x3e, 0x4a, 0x89], [0x31, 0x68, 0x8e], [0x26, 0x82, 0x8e],
    [0x1f, 0x9e, 0x89], [0x35, 0xb7, 0x79], [0x6e, 0xce, 0x58], [0xb5, 0xde, 0x2b], [0xfd, 0xe7, 0x25]];
  const lut = new Uint8Array(256 * 3);
  for (let i = 0; i < 256; i++) {
    const t = (i / 255) * (stops.length - 1), k = Math.min(stops.length - 2, Math.floor(t)), f = t - k;
    for (let c = 0; c < 3; c++) lut[i * 3 + c] = Math.round(stops[k][c] * (1 - f) + stops[k + 1][c] * f);
  }
  return lut;
})();
// The error channel: the pixel's relative standard error sqrt(Var[Y] / (Y² + 1e-3)), Y the
// Rec. 709 luminance, Var[Y] the variance of its mean (channel covariances ignored) — the
// per-pixel term of the job's error estimate (proto/error-estimate.md). Shown on a log scale
// from 0.1 % to 100 %. null when unknown (a PNG tile, or fewer than two samples).
const ERR_LO = -3, ERR_HI = 0;
function relError(i) {
  const v = base.vars, c = base.rgb;
  if (!(base.count[i] >= 2)) return null;
  const y = 0.2126 * c[i * 3] + 0.7152 * c[i * 3 + 1] + 0.0722 * c[i * 3 + 2];
  const vy = 0.2126 * 0.2126 * v[i * 3] + 0.7152 * 0.7152 * v[i * 3 + 1] + 0.0722 * 0.0722 * v[i * 3 + 2];
  return vy > 0 ? Math.sqrt(vy / (y * y + 1e-3)) : 0;
}
// A pixel with no signal: samples taken, all black, no variance (the relative error of a
// zero is not a small error; it gets a colour of its own, outside viridis).
function noSignal(i) {
  const v = base.vars, c = base.rgb;
  return base.count[i] >= 1 && c[i * 3] === 0 && c[i * 3 + 1] === 0 && c[i * 3 + 2] === 0 && v[i * 3] === 0 &&
    v[i * 3 + 1] === 0 && v[i * 3 + 2] === 0;
}
const NO_SIGNAL_RGB = [168, 40, 120], UNKNOWN_GREY = 96;
const channelMode = () => $('channel').value;

function paintRegion(x, y, w, h) {
  if (!base || w <= 0 || h <= 0) return;
  const mode = channelMode();
  const k = Math.pow(2, Number($('exposure').value));
  const out = ctx.createImageData(w, h), d = out.data;
  const W = base.w;
  const put = (di, t) => { const j = Math.max(0, Math.min(255, Math.round(255 * t))) * 3; d[di] = LUT[j]; d[di + 1] = LUT[j + 1]; d[di + 2] = LUT[j + 2]; };
  for (let r = 0; r < h; r++) {
    let si = (y + r) * W + x, di = r * w * 4;
    for (let c = 0; c < w; c++, si++, di += 4) {
      d[di + 3] = base.alpha[si];
      if (!base.alpha[si]) continue;
      if (mode === 'rgb') {
        for (let ch = 0; ch < 3; ch++) {
          const v = k * base.rgb[si * 3 + ch];
          d[di + ch] = v > 0 ? Math.round(255 * linearToSrgb(Math.min(1, v))) : 0;
        }
      } else if (mode === 'error') {
        if (noSignal(si)) { [d[di], d[di + 1], d[di + 2]] = NO_SIGNAL_RGB; continue; }
        const e = relError(si);
        if (e === null) { d[di] = d[di + 1] = d[di + 2] = UNKNOWN_GREY; continue; }
        put(di, e > 0 ? (Math.log10(e) - ERR_LO) / (ERR_HI - ERR_LO) : 0);
      } else {
        const n = base.count[si];
        if (!(n >= 0)) { d[di] = d[di + 1] = d[di + 2] = UNKNOWN_GREY; continue; }
        put(di, base.maxCount > 0 ? n / base.maxCount : 0);
      }
    }
  }
  ctx.putImageData(out, x, y);
}
const paintAll = () => { if (base) paintRegion(0, 0, base.w, base.h); };

// Stores a w×h tile at (x, y) of the window: rgb(s, ch) gives sample s's colour channel ch;
// vars ([R.var, G.var, B.var] planes) and count (a plane) may be null (a PNG tile). True
// when the largest sample count grew (the count channel's scale changed).
function storeTile(x, y, w, h, rgb, vars, count) {
  let grew = false;
  for (let r = 0; r < h; r++)
    for (let c = 0; c < w; c++) {
      const i = (y + r) * base.w + x + c, s = r * w + c;
      for (let ch = 0; ch < 3; ch++) {
        base.rgb[i * 3 + ch] = rgb(s, ch);
        base.vars[i * 3 + ch] = vars ? vars[ch][s] : NaN;
      }
      base.count[i] = count ? count[s] : NaN;
      if (count && count[s] > base.maxCount) { base.maxCount = count[s]; grew = true; }
      base.alpha[i] = 255;
    }
  return grew;
}

const scratch = document.createElement('canvas');
const sctx = scratch.getContext('2d', { willReadFrequently: true });
function paintTilePng(t, img) {
  if (!film) return;
  const x = t.x - film.x0, y = t.y - film.y0;
  scratch.width = t.w; scratch.height = t.h;
  sctx.clearRect(0, 0, t.w, t.h);
  sctx.drawImage(img, 0, 0);
  const px = sctx.getImageData(0, 0, t.w, t.h).data;
  storeTile(x, y, t.w, t.h, (s, ch) => srgbToLinear(px[s * 4 + ch] / 255), null, null);
  paintRegion(x, y, t.w, t.h);
}
function paintTileExr(t, im) {
  if (!film) return;
  const x = t.x - film.x0, y = t.y - film.y0;
  if (im.width !== t.w || im.height !== t.h) throw new Error('tile EXR of an unexpected size');
  const c = im.channels, vars = c['R.var'] && c['G.var'] && c['B.var'] ? [c['R.var'], c['G.var'], c['B.var']] : null;
  const grew = storeTile(x, y, t.w, t.h, (s, ch) => { const v = im.rgb[s * 3 + ch]; return isFinite(v) ? v : 0; }, vars, c.count || null);
  if (grew && channelMode() === 'count') paintAll(); // the scale changed
  else paintRegion(x, y, t.w, t.h);
}

// ------------------------------------------------------------------ view: fit, 1:1, zoom, pan
// screen = (tx, ty) + s · image, in CSS pixels of the viewport.
const view = { s: 1, tx: 0, ty: 0, mode: 'fit' };
const MAX_SCALE = 64;
const fitScale = () => (base ? Math.min(viewport.clientWidth / base.w, viewport.clientHeight / base.h) : 1);
function applyView() {
  stage.style.transform = `translate(${view.tx}px, ${view.ty}px) scale(${view.s})`;
  const device = view.s * (window.devicePixelRatio || 1);
  // Smooth while zoomed out, crisp pixels once an image pixel covers more than a screen pixel.
  stage.classList.toggle('crisp', device >= 0.999);
  viewport.dataset.scale = String(view.s);
  viewport.dataset.tx = String(view.tx);
  viewport.dataset.ty = String(view.ty);
  viewport.dataset.mode = view.mode;
  $('zoom-level').textContent = (device >= 10 ? Math.round(device * 100) : Number((device * 100).toPrecision(3))) + '%';
  placeHover();
  $('view-fit').setAttribute('aria-pressed', String(view.mode === 'fit'));
  $('view-1to1').setAttribute('aria-pressed', String(view.mode === '1:1'));
}
function fitView() {
  if (!base) return;
  const s = fitScale();
  Object.assign(view, { s, tx: (viewport.clientWidth - base.w * s) / 2, ty: (viewport.clientHeight - base.h * s) / 2, mode: 'fit' });
  applyView();
}
function setScaleAbout(cx, cy, s, mode = 'free') {
  const lo = Math.min(1, fitScale()) / 4;
  s = Math.max(lo, Math.min(MAX_SCALE, s));
  view.tx = cx - ((cx - view.tx) * s) / view.s;
  view.ty = cy - ((cy - view.ty) * s) / view.s;
  view.s = s;
  view.mode = mode;
  applyView();
}
function oneToOne() {
  if (!base) return;
  const dpr = window.devicePixelRatio || 1;
  setScaleAbout(viewport.clientWidth / 2, viewport.clientHeight / 2, 1 / dpr, '1:1');
  // Whole device pixels, so each image pixel is exactly one screen pixel.
  view.tx = Math.round(view.tx * dpr) / dpr;
  view.ty = Math.round(view.ty * dpr) / dpr;
  applyView();
}
const zoomStep = (f) => setScaleAbout(viewport.clientWidth / 2, viewport.clientHeight / 2, view.s * f);
// The viewport takes the image's aspect ratio, at least 200 px high. On a desktop-wide window
// the preview panel is a column of its own and must fit the window whole, image, readout,
// legend and warnings (issue #32.5): the image gets the height the rest leaves; narrower, it
// takes at most 72 % of the window's height.
const desktop = window.matchMedia('(min-width: 1200px)');
function sizeViewport() {
  if (!base) return;
  let room = 0.72 * window.innerHeight;
  if (desktop.matches) {
    const panel = viewport.closest('.panel');
    // Where the panel starts on the unscrolled page (it is sticky: its own box moves).
    const layout = panel.parentElement;
    const top = layout.getBoundingClientRect().top + window.scrollY + parseFloat(getComputedStyle(layout).paddingTop);
    const rest = panel.offsetHeight - viewport.offsetHeight; // its other parts and padding
    room = window.innerHeight - top - rest - 12;
  }
  const h = Math.round(Math.max(200, Math.min(viewport.clientWidth * (base.h / base.w), room)));
  if (viewport.style.height !== h + 'px') viewport.style.height = h + 'px';
}
desktop.addEventListener('change', () => { sizeViewport(); if (view.mode === 'fit') fitView(); });

// The wheel scrolls the page, as everywhere else; it zooms with Ctrl (or ⌘; a trackpad's pinch
// comes as a wheel with Ctrl) or once the image has the focus (clicked, or tabbed to).
viewport.addEventListener('wheel', (e) => {
  if (!base) return;
  if (!(e.ctrlKey || e.metaKey || document.activeElement === viewport)) return;
  e.preventDefault();
  const r = viewport.getBoundingClientRect();
  const dy = e.deltaMode === 1 ? 16 * e.deltaY : e.deltaMode === 2 ? 400 * e.deltaY : e.deltaY;
  setScaleAbout(e.clientX - r.left, e.clientY - r.top, view.s * Math.pow(2, -dy / 240));
}, { passive: false });
let drag = null;
viewport.addEventListener('pointerdown', (e) => {
  if (e.button !== 0 || !base) return;
  viewport.focus({ preventScroll: true });
  drag = { x: e.clientX, y: e.clientY, tx: view.tx, ty: view.ty, id: e.pointerId };
  viewport.setPointerCapture(e.pointerId);
  viewport.classList.add('dragging');
});
viewport.addEventListener('pointermove', (e) => {
  if (drag && e.pointerId === drag.id) {
    view.tx = drag.tx + e.clientX - drag.x;
    view.ty = drag.ty + e.clientY - drag.y;
    view.mode = 'free';
    applyView();
  }
  const r = viewport.getBoundingClientRect();
  showReadout(Math.floor((e.clientX - r.left - view.tx) / view.s), Math.floor((e.clientY - r.top - view.ty) / view.s));
});
const endDrag = (e) => { if (drag && e.pointerId === drag.id) { drag = null; viewport.classList.remove('dragging'); } };
viewport.addEventListener('pointerup', endDrag);
viewport.addEventListener('pointercancel', endDrag);
viewport.addEventListener('keydown', (e) => {
  const pan = 48, keys = {
    f: fitView, F: fitView, 1: oneToOne, '+': () => zoomStep(Math.SQRT2), '=': () => zoomStep(Math.SQRT2), '-': () => zoomStep(Math.SQRT1_2),
    ArrowLeft: () => { view.tx += pan; }, ArrowRight: () => { view.tx -= pan; }, ArrowUp: () => { view.ty += pan; }, ArrowDown: () => { view.ty -= pan; },
  };
  const k = keys[e.key];
  if (!k || e.ctrlKey || e.metaKey || e.altKey) return;
  e.preventDefault();
  k();
  if (e.key.startsWith('Arrow')) { view.mode = 'free'; applyView(); }
});
$('jobs-more-btn').addEventListener('click', () => { listPages++; poll(); });
$('view-fit').addEventListener('click', fitView);
$('view-1to1').addEventListener('click', oneToOne);
$('zoom-in').addEventListener('click', () => zoomStep(Math.SQRT2));
$('zoom-out').addEventListener('click', () => zoomStep(Math.SQRT1_2));
new ResizeObserver(() => {
  if (!base) return;
  const cx = viewport.clientWidth, cy = viewport.clientHeight;
  sizeViewport();
  if (view.mode === 'fit') fitView();
  else if (cx !== viewport.clientWidth || cy !== viewport.clientHeight) applyView();
}).observe(viewport.parentElement);

// ------------------------------------------------------------------ pixel readout
// The pixel under the cursor is outlined past 1:1 (an image pixel over more than one screen
// pixel), where pixels are drawn crisp.
let hover = null;
function placeHover() {
  const hv = $('hover'), big = view.s * (window.devicePixelRatio || 1) > 1 + 1e-9;
  hv.hidden = !hover || !big;
  if (hv.hidden) return;
  Object.assign(hv.style, { left: view.tx + hover[0] * view.s + 'px', top: view.ty + hover[1] * view.s + 'px', width: view.s + 'px', height: view.s + 'px' });
}
viewport.addEventListener('pointerleave', () => { hover = null; placeHover(); });
const fmtVal = (v) => (v == null || Number.isNaN(v) ? '–' : v === 0 ? '0' : Math.abs(v) >= 1e4 || Math.abs(v) < 1e-3 ? v.toExponential(3) : v.toPrecision(4));
function showReadout(x, y) {
  const ro = $('readout');
  if (!base || x < 0 || y < 0 || x >= base.w || y >= base.h) { hover = null; placeHover(); return; }
  hover = [x, y];
  placeHover();
  const i = y * base.w + x;
  // Full-image coordinates (the film window may be a crop of it), as the EXR's data window.
  const fx = x + film.x0, fy = y + film.y0;
  const d = { x: fx, y: fy };
  if (!base.alpha[i]) {
    ro.replaceChildren(el('span', { class: 'kv' }, el('b', {}, 'x '), String(fx)), el('span', { class: 'kv' }, el('b', {}, 'y '), String(fy)),
      el('span', { class: 'muted' }, 'not rendered yet'));
    Object.assign(ro.dataset, { x: fx, y: fy, r: '', g: '', b: '', spp: '', vr: '', vg: '', vb: '', err: '' });
    return;
  }
  const rgb = [0, 1, 2].map((c) => base.rgb[i * 3 + c]), vars = [0, 1, 2].map((c) => base.vars[i * 3 + c]);
  const dark = noSignal(i), e = dark ? null : relError(i), n = base.count[i];
  Object.assign(d, { r: rgb[0], g: rgb[1], b: rgb[2], spp: n, vr: vars[0], vg: vars[1], vb: vars[2], err: e });
  for (const [k, v] of Object.entries(d)) ro.dataset[k] = v == null || Number.isNaN(v) ? '' : String(v);
  ro.dataset.signal = dark ? 'none' : 'some';
  const kv = (k, v, cls = '') => el('span', { class: 'kv ' + cls }, el('b', {}, k + ' '), v);
  ro.replaceChildren(
    kv('x', String(fx)), kv('y', String(fy)),
    kv('R', fmtVal(rgb[0]), 'r'), kv('G', fmtVal(rgb[1]), 'g'), kv('B', fmtVal(rgb[2]), 'b'),
    kv('spp', Number.isNaN(n) ? '–' : String(n)),
    kv('var', vars.map(fmtVal).join(' / ')),
    kv('rel. error', dark ? 'no signal' : e == null ? '–' : (100 * e).toPrecision(3) + '%'));
}

// ------------------------------------------------------------------ legend
// Sample counts are whole numbers ("32", not "32.00"); a half of an odd count keeps its .5.
const fmtCount = (n) => (Number.isInteger(n) ? String(n) : n.toFixed(1));
function drawLegend() {
  const mode = channelMode(), lg = $('legend');
  lg.hidden = mode === 'rgb' || !base;
  if (lg.hidden) return;
  const bar = $('legend-bar'), bctx = bar.getContext('2d'), img = bctx.createImageData(256, 1);
  for (let i = 0; i < 256; i++) for (let c = 0; c < 3; c++) img.data[i * 4 + c] = LUT[i * 3 + c], img.data[i * 4 + 3] = 255;
  for (let r = 0; r < bar.height; r++) bctx.putImageData(img, 0, r);
  const ticks = mode === 'error'
    ? ['0.1%', '1%', '10%', '≥100%'].map((t, k) => [k / 3, t])
    : [[0, '0'], [0.5, fmtCount(base.maxCount / 2)], [1, fmtCount(base.maxCount)]];
  $('legend-ticks').replaceChildren(...ticks.map(([p, t]) => el('span', { style: `left: ${100 * p}%` }, t)));
  $('legend-title').textContent = mode === 'error' ? 'relative error √Var[Y] / Y, log scale' : 'samples per pixel';
  const key = (rgb, text) => el('span', {}, el('span', { class: 'sw', style: `background: rgb(${rgb.join(',')})` }), text);
  const grey = [UNKNOWN_GREY, UNKNOWN_GREY, UNKNOWN_GREY];
  $('legend-keys').replaceChildren(...(mode === 'error'
    ? [key(NO_SIGNAL_RGB, 'no signal (black, no variance)'), key(grey, 'not known (< 2 samples)')] : [key(grey, 'not known')]));
  lg.dataset.mode = mode;
}
$('channel').addEventListener('change', () => { paintAll(); drawLegend(); canvas.dataset.channel = channelMode(); });

function drawOutlines() {
  octx.clearRect(0, 0, overlay.width, overlay.height);
  if (!film || !$('outline').checked || finished(jobState)) return;
  // Tiles of the pass under way that have not reported it yet are the ones being worked on.
  octx.lineWidth = 1;
  octx.strokeStyle = 'rgba(255, 190, 40, 0.95)';
  octx.setLineDash([3, 2]);
  let n = 0;
  for (let ty = 0; ty < film.tiles_y; ty++)
    for (let tx = 0; tx < film.tiles_x; tx++) {
      const s = tileSpp.get(tx + ',' + ty) || 0;
      if (jobState === 'running' && s < passSpp) {
        const x = tx * film.tile_size, y = ty * film.tile_size;
        const w = Math.min(film.tile_size, film.crop_width - x), h = Math.min(film.tile_size, film.crop_height - y);
        octx.strokeRect(x + 0.5, y + 0.5, w - 1, h - 1);
        n++;
      }
    }
  overlay.dataset.outlined = String(n);
}

function setPreviewStatus(p) {
  jobState = p.state;
  if (p.pass_spp) passSpp = p.pass_spp;
  $('preview-status').textContent = `${p.state} · ${p.spp} / ${p.spp_target} spp · ${fmtTime(p.elapsed_s)} · ` +
    `error ${fmtPct(p.error_estimate)} · ${fmtRate(p.samples_per_s)} samples/s` +
    (finished(p.state) ? (HALT_TEXT[p.halt_reason] ? ' · ' + HALT_TEXT[p.halt_reason] : '') : ' · ' + progressOf(p));
  canvas.dataset.state = p.state;
  drawOutlines();
}

function onProgress(id, p, isDone) {
  addPoint(id, p.elapsed_s, p.error_estimate, p.spp_mean);
  const j = jobs.get(id);
  if (j) {
    Object.assign(j, { state: p.state, spp_done: p.spp, spp_target: p.spp_target, pass_spp: p.pass_spp, elapsed_s: p.elapsed_s,
      samples: p.samples, samples_per_s: p.samples_per_s, error_estimate: p.error_estimate, halt_reason: p.halt_reason,
      progress: p.progress, eta_s: p.eta_s });
  }
  if (id === selectedId) setPreviewStatus(p);
  scheduleRender();
  if (isDone) closeStream(id);
}

let renderQueued = false;
function scheduleRender() {
  if (renderQueued) return;
  renderQueued = true;
  requestAnimationFrame(() => { renderQueued = false; renderJobs(); updatePlots(); });
}

function closeStream(id) {
  const es = streams.get(id);
  if (es) { es.close(); streams.delete(id); }
}

// One EventSource per watched job. EventSource reconnects by itself after a dropped
// connection; the server then sends every rendered tile's current state first, so the
// canvas is whole again at once.
function openStream(id) {
  if (streams.has(id)) return;
  const j = jobs.get(id);
  if (!j) return;
  const es = new EventSource(withToken(j.urls.events));
  streams.set(id, es);
  es.addEventListener('tile', (ev) => {
    if (id !== selectedId) return;
    const t = JSON.parse(ev.data);
    const key = t.tx + ',' + t.ty;
    if ((tileSpp.get(key) || 0) > t.spp) return; // an older state than what is painted
    if (t.spp > passSpp) passSpp = t.spp;
    const painted = () => {
      tileSpp.set(key, t.spp);
      canvas.dataset.tiles = String(Number(canvas.dataset.tiles || 0) + 1);
      canvas.dataset.painted = String(tileSpp.size); // distinct tiles on the canvas
      drawOutlines();
    };
    const stale = () => id !== selectedId || (tileSpp.get(key) || 0) > t.spp;
    const viaPng = () => {
      const img = new Image();
      img.onload = () => { if (!stale()) { paintTilePng(t, img); painted(); } };
      img.src = withToken(t.png + '?spp=' + t.spp);
    };
    if (!useExr) return viaPng();
    fetch(withToken(t.exr + '?spp=' + t.spp), { headers: authHeaders })
      .then((r) => { if (!r.ok) throw new Error('HTTP ' + r.status); return r.arrayBuffer(); })
      .then(decodeExr)
      .then((im) => { if (!stale()) { paintTileExr(t, im); painted(); canvas.dataset.source = 'exr'; } })
      .catch((e) => { console.warn('tile EXR unreadable, using PNG tiles:', e); useExr = false; canvas.dataset.source = 'png'; viaPng(); });
  });
  es.addEventListener('progress', (ev) => onProgress(id, JSON.parse(ev.data), false));
  es.addEventListener('done', (ev) => onProgress(id, JSON.parse(ev.data), true));
  es.addEventListener('open', () => {
    if (id !== selectedId) return;
    canvas.dataset.opens = String(Number(canvas.dataset.opens || 0) + 1);
    $('preview-job').classList.remove('stale');
  });
  es.addEventListener('error', () => {
    // EventSource retries by itself; say so meanwhile.
    if (id === selectedId && es.readyState !== EventSource.CLOSED) {
      $('preview-status').textContent = 'connection lost, reconnecting…';
      $('preview-job').classList.add('stale');
    }
  });
}

function select(id) {
  const j = jobs.get(id);
  if (!j) return;
  if (selectedId && selectedId !== id && selectedId !== compareId) closeStream(selectedId);
  closeStream(id); // reopen, so the late-connect state arrives for this canvas
  selectedId = id;
  film = j.film;
  tileSpp = new Map();
  passSpp = j.pass_spp || 0;
  jobState = j.state;
  for (const c of [canvas, overlay]) { c.width = film.crop_width; c.height = film.crop_height; }
  stage.style.width = film.crop_width + 'px';
  stage.style.height = film.crop_height + 'px';
  canvas.dataset.tiles = '0';
  canvas.dataset.painted = '0';
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  const n = film.crop_width * film.crop_height;
  base = { w: film.crop_width, h: film.crop_height, rgb: new Float32Array(n * 3), vars: new Float32Array(n * 3).fill(NaN),
    count: new Float32Array(n).fill(NaN), alpha: new Uint8Array(n), maxCount: 0 };
  sizeViewport();
  fitView();
  drawLegend();
  $('readout').textContent = 'Point at the image for pixel values.';
  hover = null;
  placeHover();
  $('preview-job').textContent = '— ' + jobLabel(j);
  loadHistory(id);
  $('preview-status').textContent = j.state;
  showWarnings(j);
  openStream(id);
  renderJobs();
  updatePlots(true);
}

$('exposure').addEventListener('input', () => {
  $('exposure-out').textContent = Number($('exposure').value).toFixed(1) + ' EV';
  if (channelMode() === 'rgb') paintAll();
});
$('outline').addEventListener('change', drawOutlines);

// The shown job's import warnings, under its status line: their count and every sentence,
// from the job's status document (the list poll or the POST's answer; they never change
// after the job is made). data-job and data-count say whose and how many are on the page.
function showWarnings(j) {
  const box = $('preview-warnings'), n = j ? warningCount(j) : 0;
  const key = j ? j.id + ':' + n : '';
  if (box.dataset.key === key) return; // unchanged: keep the reader's scroll position
  Object.assign(box.dataset, { key, job: j ? j.id : '', count: String(n) });
  box.hidden = n === 0;
  $('warnings-h').textContent = plural(n, 'import warning') + ': what loading the scene mapped or dropped';
  const kept = j && Array.isArray(j.warnings) ? j.warnings : [];
  $('warnings-list').replaceChildren(...kept.map((w) => el('li', {}, w)),
    ...(j && j.warnings_dropped ? [el('li', { class: 'muted' }, `and ${j.warnings_dropped} more (the server keeps the first ${kept.length})`)] : []));
}

// A farm job's shards (API v1.4, the status's `farm`): each Slurm task's state, the samples
// per pixel merged from it of its share, and its requeues; refreshed with the job list,
// hidden for a job rendered on the server itself.
function showFarm(j) {
  const box = $('farm'), f = j && j.farm;
  box.hidden = !f;
  box.dataset.job = f ? j.id : '';
  if (!f) return;
  $('farm-h').textContent = `Slurm array ${f.slurm_job == null ? '(being submitted)' : f.slurm_job} · ${plural(f.shards, 'shard')}`;
  $('farm-tasks').querySelector('tbody').replaceChildren(...f.tasks.map((t) => el('tr', { 'data-state': t.state },
    el('td', { class: 'num' }, String(t.index)),
    el('td', {}, el('span', { class: 'state state-' + t.state }, t.state)),
    el('td', { class: 'num' }, `${t.spp} / ${t.spp_target}`),
    el('td', { class: 'num' }, String(t.retries)))));
}

// ------------------------------------------------------------------ plots
// The job's whole convergence series from the server (GET …/history, kept across restarts
// with --data), so a new tab or a reload shows the whole curve, finished jobs included.
async function loadHistory(id) {
  const r = await api('/api/v1/jobs/' + encodeURIComponent(id) + '/history');
  if (!r.ok || !r.body || !Array.isArray(r.body.points)) return;
  // The server's series replaces what this page saw (a status poll or a progress event
  // may already have put the job's latest point here, which would hide every older one);
  // points seen here after the server's last are kept. Log axes: elapsed 0 cannot be drawn.
  const pts = r.body.points.filter((p) => p.elapsed_s > 0).map((p) => ({ t: p.elapsed_s,
    err: p.error_estimate == null || !(p.error_estimate > 0) ? null : p.error_estimate, spp: p.spp > 0 ? p.spp : null }));
  const last = pts.length ? pts[pts.length - 1].t : 0;
  const j = jobs.get(id);
  if (j && finished(j.state)) {
    // A finished job's history is whole: it is the series, with nothing seen here after it.
    complete.add(id);
    history.set(id, pts);
  } else {
    history.set(id, [...pts, ...(history.get(id) || []).filter((p) => p.t > last)]);
  }
  saveHistory();
  updatePlots(true);
}

function setCompare(id) {
  if (compareId && compareId !== selectedId) closeStream(compareId);
  compareId = id;
  if (id) {
    const j = jobs.get(id);
    if (j && !finished(j.state)) openStream(id);
    loadHistory(id);
  }
  updatePlots(true);
}
$('compare').addEventListener('change', (e) => setCompare(e.target.value));

let plots = null, plotKey = '';
const PLOT_H = 190;
function plotWidth() {
  return Math.max(240, Math.min(640, $('plot-error').clientWidth));
}
const LOG_INCRS = [1, 2, 5].flatMap((m) => [-6, -5, -4, -3, -2, -1, 0, 1, 2, 3, 4, 5, 6].map((e) => m * 10 ** e)).sort((a, b) => a - b);
function logTicks(u, splits) {
  return splits.map((v) => {
    if (v == null) return '';
    const lead = v / 10 ** Math.floor(Math.log10(v) + 1e-9);
    if (![1, 2, 5].some((m) => Math.abs(lead - m) < 1e-6)) return '';
    return v >= 1e4 || v < 1e-3 ? v.toExponential(0) : String(Number(v.toPrecision(3)));
  });
}
// Which of those ticks get a label: 1, 2 and 5 where 5 and 10 lie `space` pixels apart, else
// 1 of every decade (or of every k-th where decades are narrower than `space`). uPlot's own
// filter measures 9 → 10 as a y axis does, so on an x axis it keeps only the 1s.
function logFilter(u, splits, axisIdx) {
  const ax = u.axes[axisIdx], space = ax._space || 30;
  const decade = Math.abs(u.valToPos(10, ax.scale) - u.valToPos(1, ax.scale));
  const all = decade * Math.log10(2) >= space, step = decade >= space ? 1 : Math.ceil(space / decade);
  return splits.map((v) => {
    if (v == null || !(v > 0)) return null;
    const e = Math.floor(Math.log10(v) + 1e-9), lead = v / 10 ** e;
    if (Math.abs(lead - 1) < 1e-6) return e % step === 0 ? v : null;
    return all && (Math.abs(lead - 2) < 1e-6 || Math.abs(lead - 5) < 1e-6) ? v : null;
  });
}
function makePlot(target, title, ylabel, names) {
  const colors = ['#2f7ed8', '#e4572e'];
  return new uPlot({
    title, width: plotWidth(), height: PLOT_H, padding: [8, 18, 0, 0],
    scales: { x: { time: false, distr: 3 }, y: { distr: 3 } },
    // Log axes with a label at every 1, 2, 5 × 10^k, so a curve can be read off.
    axes: [{ label: 'elapsed (s)', space: 36, incrs: LOG_INCRS, values: logTicks, filter: logFilter },
      { label: ylabel, size: 64, space: 22, incrs: LOG_INCRS, values: logTicks, filter: logFilter }],
    series: [{ label: 'elapsed (s)' }, ...names.map((n, i) => ({ label: n, stroke: colors[i], width: 2, spanGaps: true,
      points: { show: true, size: 5 } }))],
    legend: { show: true, live: false },
    // The labels drawn (on the canvas), for tests and curious readers of the DOM.
    hooks: { draw: [(u) => { target.dataset.xLabels = (u.axes[0]._values || []).filter(Boolean).join(' ');
      target.dataset.yLabels = (u.axes[1]._values || []).filter(Boolean).join(' '); }] },
  }, [[], ...names.map(() => [])], target);
}
function seriesData(field) {
  const ids = [selectedId, compareId].filter(Boolean);
  const tables = ids.map((id) => {
    const h = (history.get(id) || []).filter((p) => p[field] != null);
    return [h.map((p) => p.t), h.map((p) => p[field])];
  });
  if (!tables.length) return [[]];
  return uPlot.join(tables);
}
function updatePlots(rebuild) {
  const ids = [selectedId, compareId].filter(Boolean);
  const key = ids.join('|');
  if (rebuild || !plots || key !== plotKey) {
    if (plots) { plots.err.destroy(); plots.spp.destroy(); }
    const names = ids.map((id) => { const j = jobs.get(id); return j ? jobLabel(j) + ' ' + (j.integrator || '') : id; });
    $('plot-error').replaceChildren();
    $('plot-spp').replaceChildren();
    plots = { err: makePlot($('plot-error'), 'Relative error estimate', 'error', names),
      spp: makePlot($('plot-spp'), 'Samples per pixel', 'spp', names) };
    plotKey = key;
  }
  if (!ids.length) return;
  const e = seriesData('err'), s = seriesData('spp');
  plots.err.setData(e);
  plots.spp.setData(s);
  // The shown job's spp series, in time order (for tests: it never decreases).
  $('plot-spp').dataset.sppValues = (s[1] || []).filter((v) => v != null).join(',');
  $('plot-error').dataset.series = $('plot-spp').dataset.series = String(ids.length);
  // Points per series (for tests and curious readers of the DOM), e.g. "5,3".
  $('plot-error').dataset.seriesPoints = e.slice(1).map((y) => y.filter((v) => v != null).length).join(',');
  $('plot-error').dataset.points = String(e[0].length);
  $('plot-spp').dataset.points = String(s[0].length);
}
window.addEventListener('resize', () => {
  if (!plots) return;
  const w = plotWidth();
  plots.err.setSize({ width: w, height: PLOT_H });
  plots.spp.setSize({ width: w, height: PLOT_H });
});

// ------------------------------------------------------------------ submit
// A server error starts with the JSON path it is about; it is shown next to that field.
const FIELD_OF_PATH = [
  [/^job\.spp\b|^sampler\.spp\b/, 'spp'],
  [/^job\.time_limit_s\b/, 'time'],
  [/^job\.target_error\b/, 'target'],
  [/^job\.name\b/, 'name'],
  [/^job\.priority\b/, 'priority'],
  [/^integrator\.max_depth\b/, 'maxdepth'],
  [/^integrator(\.type)?\b/, 'integrator'],
];
const FIELDS = ['scene', 'name', 'priority', 'integrator', 'maxdepth', 'spp', 'time', 'target', 'form', 'bundle'];
const inputOf = { scene: 'f-scene', name: 'f-name', priority: 'f-priority', integrator: 'f-integrator', maxdepth: 'f-maxdepth', spp: 'f-spp',
  time: 'f-time', target: 'f-target', form: 'f-submit', bundle: 'f-bundle' };
function clearErrors() {
  for (const f of FIELDS) {
    $('err-' + f).textContent = '';
    $(inputOf[f]).removeAttribute('aria-invalid');
  }
}
function showError(field, msg) {
  $('err-' + field).textContent = msg;
  if (field !== 'form') $(inputOf[field]).setAttribute('aria-invalid', 'true');
}
function fieldForError(msg) {
  const m = /^([A-Za-z_][\w.\[\]-]*):\s/.exec(msg);
  if (!m) return /spp/.test(msg) ? 'spp' : /JSON|line \d+/.test(msg) ? 'scene' : 'form';
  for (const [re, f] of FIELD_OF_PATH) if (re.test(m[1])) return f;
  return 'scene';
}

function numberOrNull(id) {
  const v = $(id).value.trim();
  return v === '' ? null : Number(v);
}

// A bundle to post instead of the JSON scene: a tar the user chose, or one made here from a
// folder (tar.js). It is posted as it is: the form's other fields belong to the JSON scene.
// Its scene file's settings apply, with what the API takes beside a bundle (?name=, ?spp=): the
// job name (the bundle's file or folder name when left empty) and the samples per pixel; the
// fields of a JSON scene are disabled meanwhile.
let bundle = null; // { blob, label, stem }
let jsonNameHint = ''; // the name placeholder of the JSON scene (its file's or example's name)
const JSON_ONLY = ['f-example', 'f-file', 'f-scene', 'f-priority', 'f-integrator', 'f-maxdepth', 'f-time', 'f-target'];
function setBundle(b) {
  bundle = b;
  $('bundle-row').hidden = !b;
  $('bundle-info').textContent = b ? `Posting ${b.label} as a bundle: its scene file's settings apply, with the job name and ` +
    'samples per pixel given here; the other fields are for a JSON scene.' : '';
  $('err-bundle').textContent = '';
  for (const id of JSON_ONLY) $(id).disabled = !!b;
  $('f-name').placeholder = b ? b.stem : jsonNameHint;
  if (!b) { $('f-bundle').value = ''; $('f-folder').value = ''; }
}
const stemOf = (file) => file.replace(/\.(tar\.gz|tgz|tar|gz)$/i, '') || file;
// The samples per pixel of the form, checked against this server's limit (GET /api/v1/limits)
// before posting: undefined when the field is bad (its error is shown), null when empty.
function sppOfForm() {
  const spp = numberOrNull('f-spp'), max = limits ? limits.max_spp : 16777216;
  if (spp !== null && !(Number.isInteger(spp) && spp >= 1 && spp <= max)) {
    showError('spp', `job.spp: expected a whole number of samples per pixel from 1 to ${max} (this server's --max-spp)`);
    $('f-spp').focus();
    return undefined;
  }
  return spp;
}
$('f-bundle').addEventListener('change', (e) => {
  const f = e.target.files && e.target.files[0];
  $('f-folder').value = '';
  setBundle(f ? { blob: f, label: `${f.name} (${fmtBytes(f.size)})`, stem: stemOf(f.name) } : null);
});
$('f-folder').addEventListener('change', async (e) => {
  const list = [...(e.target.files || [])];
  $('f-bundle').value = '';
  if (!list.length) { setBundle(null); return; }
  // webkitRelativePath is "FOLDER/sub/file": the bundle's root is the folder itself.
  const rel = (f) => (f.webkitRelativePath || f.name).split('/').slice(1).join('/') || f.name;
  try {
    if (!list.some((f) => ['scene.json', 'scene.pbrt'].includes(rel(f))))
      throw new Error('the folder holds no scene.json or scene.pbrt at its top');
    const files = [];
    for (const f of list) files.push({ path: rel(f), data: new Uint8Array(await f.arrayBuffer()) });
    const tar = makeTar(files);
    const top = (list[0].webkitRelativePath || '').split('/')[0] || 'folder';
    setBundle({ blob: new Blob([tar], { type: 'application/x-tar' }), label: `folder ${top} (${files.length} files, ${fmtBytes(tar.length)})`, stem: top });
  } catch (err) {
    setBundle(null);
    $('bundle-row').hidden = false;
    showError('bundle', err.message);
  }
});
$('f-bundle-clear').addEventListener('click', () => setBundle(null));
function fmtBytes(n) {
  return n >= 1 << 20 ? (n / (1 << 20)).toFixed(1) + ' MiB' : n >= 1024 ? (n / 1024).toFixed(1) + ' KiB' : n + ' B';
}

function queued(r) {
  jobs.set(r.body.id, r.body);
  $('err-form').className = 'ok';
  $('err-form').textContent = 'queued as ' + r.body.id;
  select(r.body.id);
  poll();
}

$('submit-form').addEventListener('submit', async (e) => {
  e.preventDefault();
  clearErrors();
  const formSpp = sppOfForm();
  if (formSpp === undefined) return;
  if (bundle) {
    const q = new URLSearchParams();
    if (formSpp !== null) q.set('spp', String(formSpp));
    q.set('name', $('f-name').value.trim() || bundle.stem);
    $('f-submit').disabled = true;
    try {
      const r = await api('/api/v1/jobs?' + q.toString().replace(/\+/g, '%20'), { method: 'POST',
        headers: { 'Content-Type': 'application/x-tar' }, body: bundle.blob });
      if (r.status === 201 && r.body) queued(r);
      else {
        $('err-form').className = 'err';
        showError('bundle', (r.body && r.body.error) || 'the server answered ' + r.status);
        $('f-bundle').focus();
      }
    } catch (err) {
      showError('form', 'could not reach the server: ' + err.message);
    } finally {
      $('f-submit').disabled = false;
    }
    return;
  }
  let doc;
  try {
    doc = JSON.parse($('f-scene').value);
    if (!doc || typeof doc !== 'object' || Array.isArray(doc)) throw new Error('a scene is a JSON object');
  } catch (err) {
    showError('scene', 'not valid JSON: ' + err.message);
    $('f-scene').focus();
    return;
  }
  const integ = $('f-integrator').value, depth = numberOrNull('f-maxdepth');
  if (integ && (!doc.integrator || doc.integrator.type !== integ)) doc.integrator = { type: integ };
  if (depth !== null) doc.integrator = { ...(doc.integrator || { type: 'path' }), max_depth: depth };
  const job = { ...(doc.job || {}) };
  const name = $('f-name').value.trim();
  if (name) job.name = name;
  else if (!doc.name && jsonNameHint) doc.name = jsonNameHint; // named after its file, as render names it
  const prio = numberOrNull('f-priority');
  if (prio !== null) job.priority = prio;
  const spp = formSpp, tl = numberOrNull('f-time'), te = numberOrNull('f-target');
  if (spp !== null) job.spp = spp;
  if (tl !== null) job.time_limit_s = tl;
  if (te !== null) job.target_error = te;
  if (Object.keys(job).length) doc.job = job;
  $('f-submit').disabled = true;
  try {
    const r = await api('/api/v1/jobs', { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(doc) });
    if (r.status === 201 && r.body) queued(r);
    else {
      const msg = (r.body && r.body.error) || 'the server answered ' + r.status;
      const f = fieldForError(msg);
      $('err-form').className = 'err';
      showError(f, msg);
      if (f !== 'form') $(inputOf[f]).focus();
      else $('err-form').textContent = msg;
    }
  } catch (err) {
    showError('form', 'could not reach the server: ' + err.message);
  } finally {
    $('f-submit').disabled = false;
  }
});

function loadSceneText(text, name) {
  $('f-scene').value = text;
  clearErrors();
  try {
    const d = JSON.parse(text);
    $('f-spp').placeholder = d.sampler && d.sampler.spp ? 'scene: ' + d.sampler.spp : '';
    $('f-maxdepth').placeholder = d.integrator && d.integrator.max_depth != null ? 'scene: ' + d.integrator.max_depth : '';
    $('f-integrator').options[0].textContent = '(scene\'s: ' + ((d.integrator && d.integrator.type) || 'path') + ')';
    jsonNameHint = d.name ? '' : name || '';
    $('f-name').placeholder = bundle ? bundle.stem : jsonNameHint;
  } catch { /* shown on submit */ }
}

// Text typed or pasted has no file name to name the job after.
$('f-scene').addEventListener('input', () => { jsonNameHint = ''; if (!bundle) $('f-name').placeholder = ''; });
$('f-example').addEventListener('change', async (e) => {
  if (!e.target.value) return;
  const r = await fetch('scenes/' + e.target.value);
  loadSceneText(await r.text(), e.target.value.replace(/\.json$/, ''));
});
$('f-file').addEventListener('change', async (e) => {
  const f = e.target.files && e.target.files[0];
  if (f) loadSceneText(await f.text(), f.name.replace(/\.json$/, ''));
});

async function loadExamples() {
  try {
    const r = await fetch('scenes/index.json');
    const list = await r.json();
    const sel = $('f-example');
    for (const s of list) sel.append(el('option', { value: s.file }, s.title || s.file));
  } catch { /* no examples shipped */ }
}

// The limits this server checks a job against (API v1.4), said beside the fields they bound.
let limits = null;
async function loadLimits() {
  try {
    const r = await api('/api/v1/limits');
    if (!r.ok || !r.body) return;
    limits = r.body;
    $('f-spp').max = String(limits.max_spp);
    $('spp-range').textContent = `(1–${limits.max_spp} on this server)`;
  } catch { /* an older server: the form says nothing */ }
}

loadExamples();
loadLimits();
poll();
