// Browser tests of the web UI: playwright-core drives Debian's chromium headless
// against a real `tessera serve --port 0` on loopback started here. Run by run.sh (ctest
// `browser_ui`), which installs playwright-core into the build folder and skips plainly
// when chromium is missing. Screenshots go to $TS_ARTIFACTS.
//
// Scenarios: submit the Cornell box and see the canvas change as tiles arrive; the plot
// gains points; reload mid-render and see the image at once; overlay two jobs; cancel a
// job and delete it; a job's import warnings under the preview (a bundle, a folder, after a
// restart with --data) and none for a job without; a broken scene's message beside its field; the preview's view (fit, 1:1,
// zoom about the cursor, pan), pixel readout (against the EXR the API serves) and error and
// sample-count channels; layout at 1280×800 and phone width; labelled, keyboard-operable controls.
// Issue #32: the spp plot never runs backwards; the list's error in percent and effects in
// words; the spp field's range is the server's (GET /api/v1/limits) and is checked before
// posting; a bundle takes the form's name and spp and disables the rest, and is named after
// its file; the wheel scrolls the page unless the image has the focus or Ctrl is held; the
// outline past 1:1; the legend under the image, in whole samples; pixels without signal;
// the preview, readout and warnings in the window at 1280×800 and 1920×1080 (screenshots).
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import net from 'node:net';
import os from 'node:os';
import path from 'node:path';
import { createRequire } from 'node:module';

const { TS_BINARY, TS_SOURCE_DIR, TS_ARTIFACTS, TS_WEB_NODE_MODULES } = process.env;
const CHROMIUM = process.env.TS_CHROMIUM || '/usr/bin/chromium';
const require = createRequire(path.join(TS_WEB_NODE_MODULES, 'x.js'));
const { chromium } = require('playwright-core');

fs.mkdirSync(TS_ARTIFACTS, { recursive: true });
const t0 = Date.now();
let failures = 0, passes = 0;
const log = (...a) => console.log(`[${((Date.now() - t0) / 1000).toFixed(1)}s]`, ...a);

async function check(name, fn) {
  const t = Date.now();
  try {
    await fn();
    passes++;
    log(`PASS ${name} (${((Date.now() - t) / 1000).toFixed(1)} s)`);
  } catch (e) {
    failures++;
    log(`FAIL ${name}: ${e && e.stack ? e.stack : e}`);
  }
}
function assert(cond, msg) { if (!cond) throw new Error(msg); }

// ---------------------------------------------------------------- the server
function startServer(extra = []) {
  return new Promise((resolve, reject) => {
    const srv = spawn(TS_BINARY, ['serve', '--bind', '127.0.0.1', '--port', '0', '--threads', '2', ...extra],
      { stdio: ['ignore', 'pipe', 'pipe'] });
    let out = '';
    const timer = setTimeout(() => reject(new Error('tessera serve printed no URL in 10 s: ' + out)), 10000);
    srv.stdout.on('data', (d) => {
      out += d;
      const m = /listening on (http:\/\/[^\s]+)/.exec(out);
      if (m) { clearTimeout(timer); resolve({ srv, url: m[1] }); }
    });
    srv.stderr.on('data', (d) => process.stderr.write('[tessera] ' + d));
    srv.on('exit', (code) => reject(new Error('tessera serve exited with ' + code)));
  });
}

// A Cornell box small enough for a busy two-core machine: 96×96 = 3×3 tiles.
const cornell = JSON.parse(fs.readFileSync(path.join(TS_SOURCE_DIR, 'scenes/cornell-box.json'), 'utf8'));
const small = (over = {}) => JSON.stringify({ ...cornell, film: { ...cornell.film, width: 96, height: 96 }, ...over }, null, 2);

// ---------------------------------------------------------------- helpers in the page
const canvasDigest = (page) => page.evaluate(() => {
  const c = document.getElementById('canvas');
  const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
  let h = 0, lit = 0;
  for (let i = 0; i < d.length; i += 4) {
    h = (h * 31 + d[i] + 7 * d[i + 1] + 13 * d[i + 2]) >>> 0;
    if (d[i + 3] > 0 && d[i] + d[i + 1] + d[i + 2] > 0) lit++;
  }
  return { h, lit, n: d.length / 4 };
});
const jobRow = (page, id) => page.locator(`#jobs tr[data-id="${id}"]`);

async function submit(page, { scene, integrator = '', spp = '', time = '', target = '', maxdepth = '', name = '' }) {
  await page.fill('#f-scene', scene);
  await page.selectOption('#f-integrator', integrator);
  await page.fill('#f-spp', String(spp));
  await page.fill('#f-time', String(time));
  await page.fill('#f-target', String(target));
  await page.fill('#f-maxdepth', String(maxdepth));
  await page.fill('#f-name', name);
  const resp = page.waitForResponse((r) => r.url().endsWith('/api/v1/jobs') && r.request().method() === 'POST');
  await page.click('#f-submit');
  return (await resp).json();
}

// ---------------------------------------------------------------- the run
const { srv, url: serverUrl } = await startServer();
log('server at', serverUrl);
// The browser talks to the server through a loopback TCP relay, so a test can drop its
// connections for real (a network that fails, not a page that closes).
const proxy = await new Promise((resolve) => {
  const target = new URL(serverUrl), sockets = new Set();
  const server = net.createServer((c) => {
    const u = net.connect(Number(target.port), target.hostname);
    for (const [a, b] of [[c, u], [u, c]]) {
      sockets.add(a);
      a.on('error', () => b.destroy());
      a.on('close', () => { sockets.delete(a); b.destroy(); });
      a.pipe(b);
    }
  });
  server.listen(0, '127.0.0.1', () => resolve({
    url: `http://127.0.0.1:${server.address().port}/`,
    drop: () => { for (const s of sockets) s.destroy(); },
    close: () => { for (const s of sockets) s.destroy(); server.close(); },
  }));
});
const url = proxy.url;
const userDir = fs.mkdtempSync(path.join(os.tmpdir(), 'tessera-chromium-'));
process.on('exit', () => { srv.kill('SIGTERM'); fs.rmSync(userDir, { recursive: true, force: true }); });
// A fresh profile per run (--user-data-dir, which Playwright passes for a persistent context).
const context = await chromium.launchPersistentContext(userDir, {
  executablePath: CHROMIUM,
  headless: true,
  viewport: { width: 1280, height: 800 },
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
    '--disable-component-update', '--disable-sync'],
});
const page = await context.newPage();
const pageErrors = [];
page.on('pageerror', (e) => pageErrors.push(String(e)));
// The 400/422 answers the broken-scene check provokes are logged by chromium as failed loads: not script errors.
page.on('console', (m) => { if (m.type() === 'error' && !/Failed to load resource/.test(m.text())) pageErrors.push('console: ' + m.text()); });
const shot = (name, p = page) => p.screenshot({ path: path.join(TS_ARTIFACTS, name + '.png'), fullPage: true });

let first = null, second = null, warnedId = null;
try {
  await page.goto(url, { waitUntil: 'load' });

  await check('the page loads from the binary with the example scenes', async () => {
    await page.waitForSelector('#f-example option[value="cornell-box.json"]', { state: 'attached', timeout: 5000 });
    await page.selectOption('#f-example', 'cornell-box.json');
    await page.waitForFunction(() => document.getElementById('f-scene').value.includes('"tessera"'));
    const doc = JSON.parse(await page.inputValue('#f-scene'));
    assert(doc.film.width === 512, 'the example is the shipped Cornell box');
  });

  await check('submit the Cornell box; the canvas changes as tiles arrive', async () => {
    first = await submit(page, { scene: small(), spp: 1024, time: 20, name: 'cornell-path' });
    assert(first.id, 'POST answered ' + JSON.stringify(first));
    await jobRow(page, first.id).waitFor({ timeout: 5000 });
    await page.waitForFunction(() => Number(document.getElementById('canvas').dataset.tiles) > 0, null, { timeout: 15000 });
    const a = await canvasDigest(page);
    assert(a.n === 96 * 96, 'the canvas is the film size, got ' + a.n + ' pixels');
    await page.waitForFunction((n) => Number(document.getElementById('canvas').dataset.tiles) >= n + 9, 
      Number(await page.getAttribute('#canvas', 'data-tiles')), { timeout: 15000 });
    // The tiles of the pass under way are outlined while the job runs.
    await page.waitForFunction(() => Number(document.getElementById('overlay').dataset.outlined) > 0, null, { timeout: 10000 });
    const b = await canvasDigest(page);
    assert(b.h !== a.h, 'the canvas did not change');
    assert(await page.getAttribute('#canvas', 'data-source') === 'exr', 'tiles are read as EXR (linear floats)');
    assert(b.lit > 0.5 * b.n, 'most of the canvas is painted, lit ' + b.lit);
    // While it runs: the server's progress (within a pass) and an ETA, in the list and the preview.
    await page.waitForFunction((id) => /^ \d+% · ETA \d/.test(document.querySelector(`#jobs tr[data-id="${id}"] .progress-text`).textContent) &&
      / · \d+% · ETA \d/.test(document.getElementById('preview-status').textContent), first.id, { timeout: 10000 });
    const bar = Number(await jobRow(page, first.id).locator('progress').getAttribute('value'));
    assert(bar > 0 && bar < 1, 'the progress bar is part-way, value ' + bar);
    await shot('01-live-preview');
  });

  await check('the error and spp plots gain points; the list says the error in percent and the effects in words', async () => {
    await page.waitForFunction((id) => /^\d[\d.]*%$/.test(document.querySelector(`#jobs tr[data-id="${id}"] td[data-label="Error"]`).textContent),
      first.id, { timeout: 15000 }).catch(async () => {
      throw new Error('the error column reads ' + await page.textContent(`#jobs tr[data-id="${first.id}"] td[data-label="Error"]`));
    });
    const fx = await page.textContent(`#jobs tr[data-id="${first.id}"] td[data-label="Effects"]`);
    assert(fx.includes('indirect light') && fx.includes('area lights') && !fx.includes('_'), 'effects in words (issue #32.7): ' + fx);
    const before = Number(await page.getAttribute('#plot-spp', 'data-points'));
    await page.waitForFunction((n) => Number(document.getElementById('plot-spp').dataset.points) > n && 
      Number(document.getElementById('plot-error').dataset.points) >= 2, before, { timeout: 15000 });
    assert(await page.locator('#plot-error canvas').count() > 0, 'uPlot drew the error plot');
    await shot('02-plot');
  });

  await check('reload mid-render: the current image is there at once', async () => {
    const st = await (await page.request.get(url + 'api/v1/jobs/' + first.id)).json();
    assert(st.state === 'running', 'the job should still be running, is ' + st.state);
    const t = Date.now();
    await page.reload({ waitUntil: 'load' });
    // Every one of the 9 tiles painted (tile events can repeat a tile: a replayed state and a
    // newer pass's state of the same tile both count in data-tiles, so count distinct ones).
    await page.waitForFunction(() => { const c = document.getElementById('canvas'); return Number(c.dataset.painted) >= 9; },
      null, { timeout: 5000 });
    const d = await canvasDigest(page);
    const ms = Date.now() - t;
    assert(d.lit > 0.9 * d.n, 'after reload the canvas is whole, lit ' + d.lit + ' of ' + d.n);
    log(`  image back ${ms} ms after the reload`);
    await shot('03-after-reload');
    // The spp plot, the server's history then live points, never runs backwards: one quantity
    // (spp_mean) in both (issue #32.2: history ticks carried the fractional spp, live points the
    // last finished pass, …25.3, 25.7, 16, 32).
    const n0 = Number(await page.getAttribute('#plot-spp', 'data-points'));
    await page.waitForFunction((n) => Number(document.getElementById('plot-spp').dataset.points) >= n + 3, n0, { timeout: 15000 });
    const series = (await page.getAttribute('#plot-spp', 'data-spp-values')).split(',').map(Number);
    const back = series.findIndex((v, i) => i > 0 && v < series[i - 1]);
    assert(back < 0, `the spp series runs backwards at point ${back}: ${series.join(', ')}`);
    log(`  spp series after the reload: ${series.length} points, ${series[0]} … ${series[series.length - 1]}`);
  });

  await check('a dropped connection: the stream comes back and repaints the current image', async () => {
    const opens = Number(await page.getAttribute('#canvas', 'data-opens'));
    proxy.drop();
    await page.waitForFunction(() => /reconnecting/.test(document.getElementById('preview-status').textContent), null,
      { timeout: 5000 });
    await shot('03b-connection-lost');
    const before = Number(await page.getAttribute('#canvas', 'data-tiles'));
    // EventSource reconnects by itself; the server replays every rendered tile first.
    await page.waitForFunction((n) => Number(document.getElementById('canvas').dataset.opens) > n, opens, { timeout: 15000 });
    await page.waitForFunction((n) => Number(document.getElementById('canvas').dataset.tiles) >= n + 9, before,
      { timeout: 15000 });
  });

  await check('upload a scene file', async () => {
    await page.setInputFiles('#f-file', { name: 'uploaded.json', mimeType: 'application/json', buffer: Buffer.from(small()) });
    await page.waitForFunction(() => JSON.parse(document.getElementById('f-scene').value || '{}').film?.width === 96);
  });

  await check('overlay two jobs of the same scene (path and direct)', async () => {
    second = await submit(page, { scene: small(), integrator: 'direct', spp: 1024, time: 5, name: 'cornell-direct' });
    assert(second.id && second.integrator === 'direct', 'POST answered ' + JSON.stringify(second));
    await page.waitForFunction((id) => [...document.querySelectorAll('#compare option')].some((o) => o.value === id),
      first.id, { timeout: 5000 });
    await page.selectOption('#compare', first.id);
    await page.waitForFunction(() => document.getElementById('plot-error').dataset.series === '2' &&
      document.querySelectorAll('#plot-error .u-legend .u-series').length >= 2, null,
      { timeout: 5000 });
    // Both series hold points: the compared job's history was gathered while it ran.
    await page.waitForFunction(() => (document.getElementById('plot-error').dataset.seriesPoints || '').split(',')
      .filter((n) => Number(n) >= 2).length === 2, null, { timeout: 20000 });
    await shot('04-overlay');
  });

  await check('a finished job opened fresh, and after a reload, plots its whole history; halt reasons are said', async () => {
    // Two jobs that end by a bound other than spp: a time limit, and a target error.
    const post = async (job) => (await page.request.post(url + 'api/v1/jobs', { headers: { 'Content-Type': 'application/json' },
      data: small({ job }) })).json();
    const timed = await post({ name: 'timed', spp: 65536, time_limit_s: 3 });
    const target = await post({ name: 'targeted', spp: 65536, target_error: 0.1 });
    assert(timed.id && target.id, 'POSTs answered ' + JSON.stringify([timed, target]));
    for (const id of [first.id, timed.id, target.id])
      for (let t = Date.now(); ; ) {
        const st = await (await page.request.get(url + 'api/v1/jobs/' + id)).json();
        if (st.state === 'done') break;
        assert(Date.now() - t < 40000, 'job ' + id + ' did not finish in 40 s: ' + st.state);
        await new Promise((r) => setTimeout(r, 250));
      }
    // The plot shows every point of GET …/history a log axis can draw (elapsed > 0; the error
    // plot only where the estimate is known).
    // At least 2 drawable points either way: a tick a second while a job runs and its end;
    // error points need 2 spp (the target-error job renders at least 4 before it may stop:
    // its passes at 2 and 4 spp and its end).
    const expectPlotted = async (p, id, needErr) => {
      const pts = (await (await p.request.get(url + 'api/v1/jobs/' + id + '/history')).json()).points;
      const nSpp = pts.filter((q) => q.elapsed_s > 0 && q.spp > 0).length;
      const nErr = pts.filter((q) => q.elapsed_s > 0 && q.error_estimate > 0).length;
      assert(nSpp > 1 && (!needErr || nErr > 1), `history of ${id}: ${pts.length} points, ${nSpp} drawable, ${nErr} with an error: ${JSON.stringify(pts)}`);
      await p.waitForFunction(([a, b]) => document.getElementById('plot-spp').dataset.points === String(a) &&
        document.getElementById('plot-error').dataset.seriesPoints === String(b), [nSpp, nErr], { timeout: 5000 })
        .catch(async () => {
          const got = await p.evaluate(() => [document.getElementById('plot-spp').dataset.points, document.getElementById('plot-error').dataset.seriesPoints]);
          throw new Error(`job ${id}: plotted ${got[0]} spp and ${got[1]} error points, its history has ${nSpp} and ${nErr} (of ${pts.length})`);
        });
      return pts.length;
    };
    // A new tab (no sessionStorage): what it plots comes from the server alone.
    const fresh = await context.newPage();
    fresh.on('pageerror', (e) => pageErrors.push('fresh page: ' + e));
    try {
    await fresh.goto(url, { waitUntil: 'load' });
    const open = async (p, j) => {
      await p.getByRole('button', { name: 'show job ' + j.name + ' (' + j.id + ') in the preview' }).click();
      await p.waitForFunction((id) => document.querySelector(`#jobs tr[data-id="${id}"]`)?.classList.contains('selected') &&
        // 'done · …' is the job's full status; a bare 'done' is what selecting shows until it
        // arrives (a fresh-machine run read the preview in between).
        document.getElementById('preview-status').textContent.startsWith('done · '), j.id, { timeout: 10000 });
    };
    await open(fresh, timed);
    const n = await expectPlotted(fresh, timed.id, false);
    log(`  the time-limited job's ${n} history points plotted in a fresh tab`);
    const why = async (p, id) => [await p.textContent(`#jobs tr[data-id="${id}"] .progress-text`), await p.textContent('#preview-status')];
    let [rowText, status] = await why(fresh, timed.id);
    assert(rowText.trim() === 'time limit reached' && status.endsWith(' · time limit reached'),
      `the time-limited job says why it stopped: list "${rowText}", preview "${status}"`);
    assert(Number(await fresh.locator(`#jobs tr[data-id="${timed.id}"] progress`).getAttribute('value')) === 1, 'a halted job\'s bar is full');
    await fresh.reload({ waitUntil: 'load' });
    await open(fresh, timed);
    await expectPlotted(fresh, timed.id, false);
    await open(fresh, first);
    const m = await expectPlotted(fresh, first.id, true);
    log(`  the first job's ${m} history points plotted after a reload`);
    // Log axes are labelled at 1, 2 and 5 × 10^k where there is room: more than one label on
    // the time axis of a job that ran for ~20 s (its first point well under 2 s).
    const labels = await fresh.evaluate(() => ['xLabels', 'yLabels'].map((k) => document.getElementById('plot-spp').dataset[k].split(' ')));
    assert(labels[0].length >= 3 && labels[1].length >= 3, 'the axes have labels ' + JSON.stringify(labels));
    log('  axis labels: elapsed ' + labels[0].join(', ') + '; spp ' + labels[1].join(', '));
    await shot('16-reloaded-finished-job-plots', fresh);
    await open(fresh, target);
    await expectPlotted(fresh, target.id, true);
    [rowText, status] = await why(fresh, target.id);
    assert(rowText.trim() === 'target error reached' && status.endsWith(' · target error reached'),
      `the target-error job says why it stopped: list "${rowText}", preview "${status}"`);
    await shot('17-halted-by-target-error', fresh);
    } finally {
      await fresh.close();
    }
  });

  await check('a bundle file and a folder upload: a scene that carries its mesh; a bad entry is named', async () => {
    const { makeTar } = await import(path.join(TS_SOURCE_DIR, 'web/src/tar.js'));
    const doc = JSON.parse(small({ job: { spp: 4, name: 'bundled' } }));
    doc.shapes.push({ type: 'mesh', file: 'meshes/tri.obj', material: Object.keys(doc.materials)[0] });
    const obj = 'v 100 100 100\nv 101 100 100\nv 100 101 100\nf 1 2 3\n';
    const text = (s) => new TextEncoder().encode(s);
    const waitJob = async (p, name) => {
      const r = await p.waitForResponse((x) => new URL(x.url()).pathname === '/api/v1/jobs' && x.request().method() === 'POST');
      const body = await r.json();
      assert(r.status() === 201 && body.id, name + ': POST answered ' + r.status() + ' ' + JSON.stringify(body));
      assert(r.request().headers()['content-type'] === 'application/x-tar', name + ' is posted as a tar');
      await jobRow(page, body.id).locator('.state-done').waitFor({ timeout: 30000 });
      return body;
    };
    // The form's name and spp apply to a bundle (?name=, ?spp=): empty here, the scene's own.
    await page.fill('#f-name', '');
    await page.fill('#f-spp', '');
    // A .tar file (made by the page's own tar writer, checked by the server's libarchive).
    await page.setInputFiles('#f-bundle', { name: 'box.tar', mimeType: 'application/x-tar',
      buffer: Buffer.from(makeTar([{ path: 'scene.json', data: text(JSON.stringify(doc)) }, { path: 'meshes/tri.obj', data: text(obj) }])) });
    assert(/Posting box\.tar/.test(await page.textContent('#bundle-info')), 'the bundle is announced');
    let resp = waitJob(page, 'the .tar');
    await page.click('#f-submit');
    await resp;
    // A folder: the page makes the tar (its files relative to the folder).
    const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'tessera-bundle-'));
    try {
      fs.mkdirSync(path.join(dir, 'meshes'));
      fs.writeFileSync(path.join(dir, 'scene.json'), JSON.stringify({ ...doc, job: { spp: 4, name: 'folder' } }));
      fs.writeFileSync(path.join(dir, 'meshes', 'tri.obj'), obj);
      await page.setInputFiles('#f-folder', dir);
      await page.waitForFunction(() => /Posting folder tessera-bundle-\S+ \(2 files/.test(document.getElementById('bundle-info').textContent),
        null, { timeout: 5000 });
      resp = waitJob(page, 'the folder');
      await page.click('#f-submit');
      await resp;
      await shot('18-bundle-folder');
    } finally {
      fs.rmSync(dir, { recursive: true, force: true });
    }
    // A bad entry: the server's sentence, beside the bundle field.
    await page.setInputFiles('#f-bundle', { name: 'bad.tar', mimeType: 'application/x-tar',
      buffer: Buffer.from(makeTar([{ path: 'scene.json', data: text(JSON.stringify(doc)) }, { path: '../tri.obj', data: text(obj) }])) });
    await page.click('#f-submit');
    await page.waitForFunction(() => document.getElementById('err-bundle').textContent.includes("'../tri.obj' is refused"), null, { timeout: 10000 });
    assert(await page.getAttribute('#f-bundle', 'aria-invalid') === 'true', 'the bundle field is marked invalid');
    await shot('19-bundle-refused');
    await page.click('#f-bundle-clear');
    assert(await page.isHidden('#bundle-row'), 'back to the JSON scene');
  });

  await check('a job\'s import warnings are listed under the preview and counted in the list: a bundle, a folder, after a restart with --data; none for a job without', async () => {
    const { makeTar } = await import(path.join(TS_SOURCE_DIR, 'web/src/tar.js'));
    const text = (s) => new TextEncoder().encode(s);
    // Line 4 (halton) and line 5 (bdpt) each give one warning; sobol and path give none.
    const pbrt = (sampler, integ) => 'LookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective" "float fov" [30]\n' +
      'Film "image" "integer xresolution" [32] "integer yresolution" [24]\n' +
      `Sampler "${sampler}" "integer pixelsamples" [4]\nIntegrator "${integ}"\n` +
      'WorldBegin\nLightSource "infinite" "rgb L" [1 1 1]\nMaterial "matte"\nShape "sphere" "float radius" [1]\nWorldEnd\n';
    const halton = 'scene.pbrt:4:1: Sampler "halton" is mapped to tessera\'s Owen-scrambled Sobol sampler with its pixelsamples (4)';
    const warnTar = makeTar([{ path: 'scene.pbrt', data: text(pbrt('halton', 'bdpt')) }]);
    const cleanTar = makeTar([{ path: 'scene.pbrt', data: text(pbrt('sobol', 'path')) }]);
    // Posts what setFiles puts in a bundle field through the form; waits until the job is done.
    const postViaForm = async (p, setFiles) => {
      await setFiles();
      const resp = p.waitForResponse((x) => new URL(x.url()).pathname === '/api/v1/jobs' && x.request().method() === 'POST');
      await p.click('#f-submit');
      const r = await resp, body = await r.json();
      assert(r.status() === 201 && body.id, 'POST answered ' + r.status() + ' ' + JSON.stringify(body));
      await jobRow(p, body.id).locator('.state-done').waitFor({ timeout: 30000 });
      return body;
    };
    // Opens a job and reads its warnings off the page once its full status is shown (selecting
    // shows the bare state first) and the warnings box is this job's.
    const shown = async (p, id) => {
      await jobRow(p, id).locator('button.link').click();
      await p.waitForFunction((id) => document.querySelector(`#jobs tr[data-id="${id}"]`)?.classList.contains('selected') &&
        document.getElementById('preview-status').textContent.startsWith('done · ') &&
        document.getElementById('preview-warnings').dataset.job === id, id, { timeout: 10000 });
      return p.evaluate((id) => {
        const box = document.getElementById('preview-warnings'), cell = document.querySelector(`#jobs tr[data-id="${id}"] .warn`);
        const r = box.getBoundingClientRect();
        return { count: Number(box.dataset.count), visible: !box.hidden && r.width > 0 && r.height > 0,
          heading: document.getElementById('warnings-h').textContent, items: [...box.querySelectorAll('li')].map((li) => li.textContent),
          row: cell ? cell.textContent : '' };
      }, id);
    };
    // What the API says, against what the page shows: every sentence, in order, readable.
    const expectShown = (w, status, what) => {
      const want = status.warnings;
      assert(want.length === 2 && want[0] === halton && /^scene\.pbrt:5:1: .*"bdpt"/.test(want[1]),
        what + ': the API lists the two warnings, got ' + JSON.stringify(want));
      assert(w.visible && w.count === 2 && w.heading.startsWith('2 import warnings') && w.row === '2 import warnings',
        what + ': count shown under the preview and in the list: ' + JSON.stringify(w));
      assert(JSON.stringify(w.items) === JSON.stringify(want), what + ': the sentences shown ' + JSON.stringify(w.items));
    };
    const expectNone = (w, what) => assert(!w.visible && w.count === 0 && w.items.length === 0 && w.row === '',
      what + ': no warnings shown, got ' + JSON.stringify(w));

    // Whatever fails, the form goes back to the JSON scene for the checks after this one.
    try {
    // While a bundle is chosen, the fields the API takes beside it (the name: ?name=, the spp:
    // ?spp=) apply and the JSON scene's are disabled (issue #32.4); the job is named after the
    // bundle's file, not "scene".
    const warned = await postViaForm(page, async () => {
      await page.setInputFiles('#f-bundle', { name: 'warns.tar', mimeType: 'application/x-tar', buffer: Buffer.from(warnTar) });
      const form = await page.evaluate(() => Object.fromEntries(['f-scene', 'f-priority', 'f-integrator', 'f-maxdepth', 'f-time', 'f-target',
        'f-name', 'f-spp'].map((id) => [id, document.getElementById(id).disabled])));
      assert(!form['f-name'] && !form['f-spp'] && Object.entries(form).every(([id, off]) => off === !['f-name', 'f-spp'].includes(id)),
        'a bundle disables what it ignores: ' + JSON.stringify(form));
      assert(await page.getAttribute('#f-name', 'placeholder') === 'warns', 'the name defaults to the bundle\'s');
      await page.fill('#f-name', '');
      await page.fill('#f-spp', '2');
    });
    assert(warned.name === 'warns' && warned.spp_target === 2, 'the bundle job is named warns with 2 spp: ' + JSON.stringify([warned.name, warned.spp_target]));
    await page.fill('#f-spp', '');
    warnedId = warned.id;
    expectShown(await shown(page, warned.id), warned, 'a .tar bundle');
    await shot('20-import-warnings');
    const clean = await postViaForm(page, () => page.setInputFiles('#f-bundle', { name: 'clean.tar', mimeType: 'application/x-tar', buffer: Buffer.from(cleanTar) }));
    assert(Array.isArray(clean.warnings) && clean.warnings.length === 0, 'sobol and path warn of nothing: ' + JSON.stringify(clean.warnings));
    expectNone(await shown(page, clean.id), 'a bundle without warnings');
    expectNone(await shown(page, first.id), 'a JSON job');
    const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'tessera-warn-folder-'));
    try {
      fs.writeFileSync(path.join(dir, 'scene.pbrt'), pbrt('halton', 'bdpt'));
      const folder = await postViaForm(page, async () => {
        await page.setInputFiles('#f-folder', dir);
        await page.waitForFunction(() => /Posting folder tessera-warn-folder-\S+ \(1 files/.test(document.getElementById('bundle-info').textContent),
          null, { timeout: 5000 });
      });
      expectShown(await shown(page, folder.id), folder, 'a folder upload');
    } finally {
      fs.rmSync(dir, { recursive: true, force: true });
    }
    } finally {
      if (await page.isVisible('#bundle-row')) await page.click('#f-bundle-clear');
    }
    assert(!(await page.isDisabled('#f-priority')), 'back to the JSON scene: its fields are enabled again');
    // A server with --data, restarted: the restored job (its scene.pbrt loaded again) still lists them.
    const data = fs.mkdtempSync(path.join(os.tmpdir(), 'tessera-warn-data-'));
    let s1 = null, s2 = null;
    const p = await context.newPage();
    p.on('pageerror', (e) => pageErrors.push('restart page: ' + e));
    try {
      s1 = await startServer(['--data', data]);
      const r = await p.request.post(s1.url + 'api/v1/jobs', { headers: { 'Content-Type': 'application/x-tar' }, data: Buffer.from(warnTar) });
      const before = await r.json();
      assert(r.status() === 201 && before.warnings.length === 2, 'POST to the --data server: ' + r.status() + ' ' + JSON.stringify(before));
      for (let t = Date.now(); (await (await p.request.get(s1.url + 'api/v1/jobs/' + before.id)).json()).state !== 'done'; ) {
        assert(Date.now() - t < 30000, 'the job on the --data server did not finish in 30 s');
        await new Promise((res) => setTimeout(res, 200));
      }
      const exited = new Promise((res) => s1.srv.once('exit', res));
      s1.srv.kill('SIGTERM');
      await exited;
      s1 = null;
      s2 = await startServer(['--data', data]);
      await p.goto(s2.url, { waitUntil: 'load' });
      await jobRow(p, before.id).waitFor({ timeout: 5000 });
      const after = await (await p.request.get(s2.url + 'api/v1/jobs/' + before.id)).json();
      assert(JSON.stringify(after.warnings) === JSON.stringify(before.warnings), 'restored warnings ' + JSON.stringify(after.warnings));
      expectShown(await shown(p, before.id), after, 'after a restart with --data');
      await shot('21-import-warnings-restored', p);
    } finally {
      await p.close();
      for (const s of [s1, s2]) if (s && s.srv.exitCode === null) { const e = new Promise((res) => s.srv.once('exit', res)); s.srv.kill('SIGTERM'); await e; }
      fs.rmSync(data, { recursive: true, force: true });
    }
  });

  await check('cancel a job from the list, then delete it', async () => {
    const long = await submit(page, { scene: small(), spp: 65536, name: 'to-cancel' });
    assert(long.id, 'POST answered ' + JSON.stringify(long));
    const row = jobRow(page, long.id);
    await row.waitFor({ timeout: 5000 });
    await row.getByRole('button', { name: 'cancel job ' + long.id }).click();
    await row.locator('.state-cancelled').waitFor({ timeout: 15000 });
    assert(await row.getByRole('button', { name: 'cancel job ' + long.id }).count() === 0, 'no Cancel once cancelled');
    await shot('05-cancelled');
    // A finished job can be deleted (after a confirmation): it leaves the list and the server.
    page.once('dialog', (d) => d.accept());
    await row.getByRole('button', { name: 'delete job ' + long.id }).click();
    await row.waitFor({ state: 'detached', timeout: 5000 });
    const gone = await page.request.get(url + 'api/v1/jobs/' + long.id);
    assert(gone.status() === 404, 'the deleted job answers 404, got ' + gone.status());
  });

  await check('EXR and PNG downloads', async () => {
    const row = jobRow(page, first.id);
    const png = await page.request.get(new URL(await row.getByRole('link', { name: 'download PNG of job ' + first.id }).getAttribute('href'), url).href);
    assert(png.status() === 200 && png.headers()['content-type'] === 'image/png', 'PNG link');
    const exr = await page.request.get(new URL(await row.getByRole('link', { name: 'download EXR of job ' + first.id }).getAttribute('href'), url).href);
    const b = await exr.body();
    assert(exr.status() === 200 && b.readUInt32LE(0) === 20000630, 'EXR link gives an OpenEXR file');
  });

  await check('a broken scene: the message is beside the field its JSON path names', async () => {
    const r1 = await submit(page, { scene: small(), maxdepth: -1 });
    assert(/^integrator\.max_depth/.test(r1.error), 'server error ' + JSON.stringify(r1));
    await page.waitForFunction(() => document.getElementById('err-maxdepth').textContent.includes('integrator.max_depth'));
    assert(await page.getAttribute('#f-maxdepth', 'aria-invalid') === 'true', 'max depth is marked invalid');
    assert(await page.evaluate(() => document.activeElement.id) === 'f-maxdepth', 'focus moves to the field');
    await shot('06-error-maxdepth');
    const bad = JSON.parse(small());
    bad.shapes.push({ type: 'sphere', center: [0, 1, 0], radius: -1, material: Object.keys(bad.materials)[0] });
    const r2 = await submit(page, { scene: JSON.stringify(bad, null, 2) });
    assert(/^shapes\[\d+\]\.radius/.test(r2.error), 'server error ' + JSON.stringify(r2));
    await page.waitForFunction(() => document.getElementById('err-scene').textContent.includes('.radius'));
    assert(await page.textContent('#err-maxdepth') === '', 'the old message is gone');
    // The spp range is this server's (GET /api/v1/limits: --max-spp 65536), said by the field
    // and checked before posting — not the loader's [1, 16777216] (issue #32.7).
    assert(await page.getAttribute('#f-spp', 'max') === '65536' && (await page.textContent('#spp-range')).includes('1–65536'),
      'the spp field states the server\'s range: max ' + await page.getAttribute('#f-spp', 'max'));
    let posts = 0;
    const countPosts = (rq) => { if (rq.method() === 'POST' && rq.url().endsWith('/api/v1/jobs')) posts++; };
    page.on('request', countPosts);
    for (const spp of ['100000', '0']) {
      await page.fill('#f-scene', small());
      await page.fill('#f-spp', spp);
      await page.click('#f-submit');
      await page.waitForFunction(() => document.getElementById('err-spp').textContent.includes('job.spp'), null, { timeout: 5000 });
      const msg = await page.textContent('#err-spp');
      assert(msg.includes('from 1 to 65536') && !msg.includes('16777216'), `spp ${spp}: the message says the server's range: ${msg}`);
    }
    await new Promise((res) => setTimeout(res, 300));
    page.off('request', countPosts);
    assert(posts === 0, 'an spp out of the server\'s range is not posted, posts: ' + posts);
    await page.fill('#f-spp', '');
    await page.fill('#f-scene', '{"tessera": 1,');
    await page.click('#f-submit');
    await page.waitForFunction(() => document.getElementById('err-scene').textContent.includes('not valid JSON'));
    await shot('07-error-scene');
  });

  await check('preview: fit, 1:1, zoom about the cursor, pan, pixel readout against the EXR, error and sample-count channels', async () => {
    // A finished job, so the EXR the API serves is the image on the canvas.
    const W = 160, H = 120;
    const job = await submit(page, { scene: small({ film: { ...cornell.film, width: W, height: H } }), spp: 16, name: 'preview-tools' });
    assert(job.id, 'POST answered ' + JSON.stringify(job));
    await jobRow(page, job.id).locator('.state-done').waitFor({ timeout: 30000 });
    await page.getByRole('button', { name: 'show job preview-tools (' + job.id + ') in the preview' }).click();
    // Every tile at its final 16 spp (5×4 tiles of 32 px).
    await page.waitForFunction(() => Number(document.getElementById('canvas').dataset.painted) >= 20, null, { timeout: 10000 });
    await page.waitForFunction((id) => document.getElementById('preview-status').textContent.startsWith('done'), job.id, { timeout: 10000 });
    const vp = page.locator('#viewport'), stage = page.locator('#stage');
    const viewState = () => page.evaluate(() => { const d = document.getElementById('viewport').dataset; return { s: Number(d.scale), tx: Number(d.tx), ty: Number(d.ty), mode: d.mode }; });
    const rendering = () => page.evaluate(() => getComputedStyle(document.getElementById('canvas')).imageRendering);

    // Fit: the whole image, as large as the view allows, centred.
    let vb = await vp.boundingBox(), sb = await stage.boundingBox(), v = await viewState();
    assert(v.mode === 'fit', 'a new job opens fitted, mode ' + v.mode);
    assert(sb.x >= vb.x - 0.5 && sb.y >= vb.y - 0.5 && sb.x + sb.width <= vb.x + vb.width + 0.5 && sb.y + sb.height <= vb.y + vb.height + 0.5,
      'fit: the image lies inside the view');
    assert(Math.abs(sb.width - vb.width) < 1 || Math.abs(sb.height - vb.height) < 1, 'fit: the image fills the view along one axis');
    assert(v.s > 2 && (await rendering()) === 'pixelated', 'a small film fitted is magnified with crisp pixels, scale ' + v.s);
    await shot('11-preview-fit');

    // 1:1: one image pixel per screen pixel.
    await page.click('#view-1to1');
    v = await viewState(); sb = await stage.boundingBox();
    assert(v.mode === '1:1' && v.s === 1 && Math.abs(sb.width - W) < 0.01 && Math.abs(sb.height - H) < 0.01, '1:1: the stage is ' + sb.width + '×' + sb.height);
    assert(Number.isInteger(v.tx) && Number.isInteger(v.ty), '1:1 sits on whole pixels');
    // The pixel under the cursor is outlined past 1:1 (README), not from 6 screen pixels on (issue #32.7).
    const overImage = async () => { const b = await stage.boundingBox(); await page.mouse.move(b.x + b.width / 2 + 0.3, b.y + b.height / 2 + 0.3); };
    await overImage();
    assert(await page.isHidden('#hover'), 'at 1:1 no pixel is outlined');
    await page.click('#zoom-in');
    await page.click('#zoom-in'); // √2 · √2: two screen pixels per image pixel
    assert(Math.abs((await viewState()).s - 2) < 1e-9, 'two zoom steps from 1:1 are 2×');
    await overImage();
    assert(await page.isVisible('#hover'), 'at 2× the pixel under the cursor is outlined');
    await page.click('#view-1to1');

    // The wheel over the image scrolls the page unless the image has the focus or Ctrl is held
    // (issue #32.5: it zoomed, and the page under it could not be scrolled).
    await page.evaluate(() => { document.activeElement && document.activeElement.blur(); window.scrollTo(0, 0); });
    await overImage();
    const s0 = (await viewState()).s;
    await page.mouse.wheel(0, 240);
    await page.waitForFunction(() => window.scrollY > 0, null, { timeout: 3000 }).catch(() => {});
    const scrolled = await page.evaluate(() => window.scrollY);
    assert((await viewState()).s === s0 && scrolled > 0, `the wheel scrolled the page (by ${scrolled}) and left the zoom (${(await viewState()).s} from ${s0})`);
    await page.evaluate(() => window.scrollTo(0, 0));
    await overImage();
    await page.keyboard.down('Control');
    await page.mouse.wheel(0, -240);
    await page.keyboard.up('Control');
    await page.waitForFunction((a) => Number(document.getElementById('viewport').dataset.scale) > a * 1.9, s0, { timeout: 3000 });
    await page.click('#view-1to1');
    await page.focus('#viewport'); // the wheel alone zooms once the image has the focus

    // Zoom about the cursor: the image point under the cursor stays put; the view and the picture change.
    const shotBefore = await vp.screenshot(); // (scrolls the view into the window first)
    vb = await vp.boundingBox();
    // Whole pixels: a wheel event's clientX/Y are rounded.
    const cx = Math.round(vb.x + vb.width / 2 + 23), cy = Math.round(vb.y + Math.min(vb.height, 800 - vb.y) / 2 - 11);
    await page.mouse.move(cx, cy);
    // The image point under the cursor, from the view transform and where the view is on the page.
    const under = async () => {
      const st = await viewState(), r = await page.evaluate(() => { const b = document.getElementById('viewport').getBoundingClientRect(); return [b.left, b.top]; });
      return { st, u: (cx - r[0] - st.tx) / st.s, v: (cy - r[1] - st.ty) / st.s };
    };
    const before = await under();
    await page.mouse.wheel(0, -480); // 2 × 240: ×4
    await page.waitForFunction((s0) => Number(document.getElementById('viewport').dataset.scale) > s0 * 3.9, before.st.s, { timeout: 3000 });
    const after = await under(), shotAfter = await vp.screenshot();
    assert(Math.abs(after.st.s / before.st.s - 4) < 1e-9, 'the wheel zoomed ×4, got ×' + after.st.s / before.st.s);
    assert(Math.abs(before.u - after.u) < 1e-6 && Math.abs(before.v - after.v) < 1e-6,
      `the point under the cursor moved: (${before.u}, ${before.v}) → (${after.u}, ${after.v})`);
    assert(!shotBefore.equals(shotAfter), 'zooming changed the picture');
    assert((await rendering()) === 'pixelated', 'zoomed in past 1:1: crisp pixels');
    await page.mouse.wheel(0, -480); // ×4 again: 16 screen pixels per image pixel
    await page.waitForFunction(() => Number(document.getElementById('viewport').dataset.scale) > 15.9, null, { timeout: 3000 });
    assert(await page.isVisible('#hover'), 'the pixel under the cursor is outlined when zoomed in');
    await shot('12-preview-zoomed');
    // Zoomed out below 1:1: smooth scaling.
    await page.mouse.wheel(0, 1440); // ÷64: 0.25
    v = await viewState();
    assert(Math.abs(v.s - 0.25) < 1e-9 && (await rendering()) === 'auto', 'zoomed out to ' + v.s + ': smooth, got ' + (await rendering()));
    // Pan by dragging.
    await page.click('#view-fit');
    const p0 = await viewState();
    await page.mouse.move(cx, cy);
    await page.mouse.down();
    await page.mouse.move(cx + 40, cy + 25, { steps: 4 });
    await page.mouse.up();
    const p1 = await viewState();
    assert(Math.abs(p1.tx - p0.tx - 40) < 1e-6 && Math.abs(p1.ty - p0.ty - 25) < 1e-6 && p1.mode === 'free', 'drag panned by (40, 25)');
    await page.click('#view-fit');

    // Pixel readout under the cursor, compared with the EXR the API serves.
    const { decodeExr } = await import(path.join(TS_SOURCE_DIR, 'web/src/exr.js'));
    const exrBuf = await (await page.request.get(url + 'api/v1/jobs/' + job.id + '/image.exr')).body();
    const exr = await decodeExr(exrBuf.buffer.slice(exrBuf.byteOffset, exrBuf.byteOffset + exrBuf.byteLength));
    assert(exr.width === W && exr.height === H && exr.channels['R.var'] && exr.channels.count, 'image.exr holds colour, variance and count');
    const pointAt = async (x, y) => {
      const st = await viewState(), b = await vp.boundingBox();
      await page.mouse.move(b.x + st.tx + (x + 0.5) * st.s, b.y + st.ty + (y + 0.5) * st.s);
      return page.evaluate(() => ({ ...document.getElementById('readout').dataset, text: document.getElementById('readout').textContent }));
    };
    for (const [x, y] of [[80, 5], [37, 90], [W - 1, H - 1]]) { // the light, the left wall, the last pixel
      const ro = await pointAt(x, y), i = y * W + x, c = exr.channels;
      assert(Number(ro.x) === x && Number(ro.y) === y, `readout at (${ro.x}, ${ro.y}), expected (${x}, ${y})`);
      const want = { r: c.R[i], g: c.G[i], b: c.B[i], vr: c['R.var'][i], vg: c['G.var'][i], vb: c['B.var'][i], spp: c.count[i] };
      for (const [k, w] of Object.entries(want)) assert(Number(ro[k]) === w, `readout ${k} at (${x}, ${y}): ${ro[k]}, the EXR has ${w}`);
      const Y = 0.2126 * want.r + 0.7152 * want.g + 0.0722 * want.b;
      const vy = 0.2126 ** 2 * want.vr + 0.7152 ** 2 * want.vg + 0.0722 ** 2 * want.vb;
      const e = Math.sqrt(vy / (Y * Y + 1e-3));
      assert(Math.abs(Number(ro.err) - e) <= 1e-12 * e, `relative error at (${x}, ${y}): ${ro.err}, expected ${e}`);
      assert(ro.text.includes('spp ' + want.spp) && /rel\. error/.test(ro.text), 'the readout text shows spp and error: ' + ro.text);
    }
    // Zoomed in on the light's brightest pixel, for the picture.
    let best = 0;
    for (let i = 1; i < W * H; i++) if (exr.channels.R[i] + exr.channels.G[i] > exr.channels.R[best] + exr.channels.G[best]) best = i;
    const bx = best % W, by = Math.floor(best / W);
    await pointAt(bx, by);
    await page.focus('#viewport'); // (the Fit button had it)
    await page.mouse.wheel(0, -480);
    await page.waitForFunction(() => document.getElementById('viewport').dataset.mode === 'free', null, { timeout: 3000 });
    const ro = await pointAt(bx, by);
    assert(Number(ro.x) === bx && Number(ro.y) === by && Number(ro.r) === exr.channels.R[best], 'readout on the light, zoomed in');
    await shot('13-preview-readout');
    await page.click('#view-fit');

    // The error channel: false colour with a legend; brighter where the error is larger.
    const rgbDigest = await canvasDigest(page);
    await page.selectOption('#channel', 'error');
    assert(await page.isVisible('#legend') && (await page.textContent('#legend')).includes('10%'), 'the error legend is shown');
    // The legend is under the image, never over it (issue #32.6).
    const lb = await page.locator('#legend').boundingBox(), vpb = await vp.boundingBox();
    assert(lb.y >= vpb.y + vpb.height - 0.5 || lb.y + lb.height <= vpb.y + 0.5 || lb.x >= vpb.x + vpb.width || lb.x + lb.width <= vpb.x,
      'the legend does not cover the image: legend ' + JSON.stringify(lb) + ', view ' + JSON.stringify(vpb));
    assert((await page.textContent('#legend-keys')).includes('no signal'), 'the legend names the no-signal colour');
    const errDigest = await canvasDigest(page);
    assert(errDigest.h !== rgbDigest.h && errDigest.lit > 0.9 * errDigest.n, 'the error channel repainted the canvas');
    const corr = await page.evaluate((exrErr) => {
      const c = document.getElementById('canvas'), d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      const pairs = exrErr.map((e, i) => [e, 0.2126 * d[i * 4] + 0.7152 * d[i * 4 + 1] + 0.0722 * d[i * 4 + 2]]).filter(([e]) => e > 0);
      pairs.sort((a, b) => a[0] - b[0]);
      const half = Math.floor(pairs.length / 2), mean = (a) => a.reduce((s, p) => s + p[1], 0) / a.length;
      return { low: mean(pairs.slice(0, half)), high: mean(pairs.slice(half)) };
    }, Array.from({ length: W * H }, (_, i) => {
      const c = exr.channels, Y = 0.2126 * c.R[i] + 0.7152 * c.G[i] + 0.0722 * c.B[i];
      return Math.sqrt((0.2126 ** 2 * c['R.var'][i] + 0.7152 ** 2 * c['G.var'][i] + 0.0722 ** 2 * c['B.var'][i]) / (Y * Y + 1e-3));
    }));
    assert(corr.high > corr.low + 20, `noisier half brighter in false colour: ${corr.low.toFixed(1)} vs ${corr.high.toFixed(1)}`);
    await shot('14-preview-error-channel');
    await page.selectOption('#channel', 'count');
    assert((await page.textContent('#legend')).includes('samples per pixel'), 'the count legend is shown');
    const ticks = await page.evaluate(() => [...document.querySelectorAll('#legend-ticks span')].map((e) => e.textContent).join(' '));
    assert(ticks === '0 8 16', 'the count legend is in whole samples (issue #32.7: it read "16.00"): ' + ticks);
    assert((await canvasDigest(page)).h !== errDigest.h, 'the count channel repainted the canvas');
    await shot('15-preview-sample-count');
    await page.selectOption('#channel', 'rgb');
    assert(await page.isHidden('#legend'), 'no legend for RGB');
  });

  await check('the error channel shows pixels without signal as such, not as 0% error', async () => {
    // A wide view of the box: past its walls the camera sees nothing (no environment light):
    // black pixels with no variance (issue #32.6: "rel. error 0.00%" in the best colour).
    const job = await submit(page, { scene: small({ camera: { ...cornell.camera, fov: 100 } }), spp: 4, name: 'no-signal' });
    assert(job.id, 'POST answered ' + JSON.stringify(job));
    await jobRow(page, job.id).locator('.state-done').waitFor({ timeout: 30000 });
    await page.getByRole('button', { name: 'show job no-signal (' + job.id + ') in the preview' }).click();
    await page.waitForFunction(() => Number(document.getElementById('canvas').dataset.painted) >= 9 &&
      document.getElementById('preview-status').textContent.startsWith('done'), null, { timeout: 10000 });
    await page.selectOption('#channel', 'error');
    await page.waitForTimeout(300); // the legend takes its place under the image; the view refits
    await page.click('#view-fit');
    const st = await page.evaluate(() => { const d = document.getElementById('viewport').dataset; return { s: Number(d.scale), tx: Number(d.tx), ty: Number(d.ty) }; });
    const b = await page.locator('#viewport').boundingBox();
    await page.mouse.move(b.x + st.tx + 0.5 * st.s, b.y + st.ty + 0.5 * st.s); // pixel (0, 0), outside the box
    const ro = await page.evaluate(() => ({ ...document.getElementById('readout').dataset, text: document.getElementById('readout').textContent }));
    assert(ro.x === '0' && ro.y === '0' && ro.signal === 'none' && /rel\. error no signal/.test(ro.text) && Number(ro.r) === 0,
      'the readout of a black pixel says no signal: ' + JSON.stringify(ro));
    const px = await page.evaluate(() => Array.from(document.getElementById('canvas').getContext('2d').getImageData(0, 0, 1, 1).data.slice(0, 3)));
    assert(px.join() === '168,40,120', 'a pixel without signal has its own colour, got ' + px);
    await page.mouse.move(b.x + st.tx + 48.5 * st.s, b.y + st.ty + 60.5 * st.s); // inside the box: lit
    const lit = await page.evaluate(() => document.getElementById('readout').dataset);
    assert(lit.signal === 'some' && Number(lit.err) > 0, 'a lit pixel has its relative error: ' + JSON.stringify(lit));
    await shot('14b-error-channel-no-signal');
    await page.selectOption('#channel', 'rgb');
  });

  await check('controls are labelled and keyboard-operable', async () => {
    const unlabelled = await page.evaluate(() => [...document.querySelectorAll('input, select, textarea, button')]
      .filter((e) => !(e.labels && e.labels.length) && !e.getAttribute('aria-label') && !e.textContent.trim())
      .map((e) => e.id || e.outerHTML.slice(0, 60)));
    assert(unlabelled.length === 0, 'unlabelled controls: ' + unlabelled.join(', '));
    // Pick the first job for the preview with the keyboard: its button, then Enter.
    await page.getByRole('button', { name: 'show job cornell-path (' + first.id + ') in the preview' }).focus();
    await page.keyboard.press('Enter');
    await page.waitForFunction(() => Number(document.getElementById('canvas').dataset.tiles) >= 9, null, { timeout: 5000 });
    await page.focus('#exposure');
    await page.keyboard.press('ArrowRight');
    await page.keyboard.press('ArrowRight');
    assert((await page.textContent('#exposure-out')).startsWith('0.2'), 'exposure moved by the keyboard');
    const before = await canvasDigest(page);
    await page.keyboard.press('End');
    const after = await canvasDigest(page);
    assert(after.h !== before.h, 'exposure repaints the canvas');
    // At -4 EV the light is no longer clipped white: its warm colour (radiance 17, 12, 4)
    // is still there, which an 8-bit PNG (clipped at 1 before scaling) could not show.
    await page.keyboard.press('Home');
    assert((await page.textContent('#exposure-out')).startsWith('-4.0'), 'Home sets -4 EV');
    const light = await page.evaluate(() => {
      const c = document.getElementById('canvas'), d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      let best = [0, 0, 0];
      for (let i = 0; i < d.length; i += 4) if (d[i] + d[i + 1] + d[i + 2] > best[0] + best[1] + best[2]) best = [d[i], d[i + 1], d[i + 2]];
      return best;
    });
    assert(light[0] - light[2] > 60, 'the light keeps its colour at -4 EV, brightest pixel ' + light);
    await shot('08b-exposure-minus-4');
    // Tab reaches the submit form's controls in order.
    await page.focus('#f-name');
    await page.keyboard.press('Tab');
    assert(await page.evaluate(() => document.activeElement.id) === 'f-priority', 'Tab goes to the priority');
    await page.keyboard.press('Home');
    await page.focus('#exposure');
    await page.keyboard.press('Home');
    await page.fill('#exposure', '0');
    await page.dispatchEvent('#exposure', 'input');
  });

  await check('layout at 1280×800 and at phone width', async () => {
    await page.waitForFunction((id) => document.querySelector(`#jobs tr[data-id="${id}"] .state`).textContent !== 'running',
      second.id, { timeout: 20000 });
    // The preview (the image fitted, its readout, its import warnings) in view at the top of the
    // page, with several jobs in the list, at both desktop sizes (issue #32.5: at 1280×800 Fit
    // spilled past the window and the readout and warnings were below it).
    assert(await page.locator('#jobs tbody tr').count() >= 4, 'several jobs are listed');
    await jobRow(page, warnedId).locator('button.link').click();
    await page.waitForFunction((id) => document.getElementById('preview-warnings').dataset.job === id &&
      document.getElementById('preview-status').textContent.startsWith('done · '), warnedId, { timeout: 10000 });
    for (const [w, h] of [[1280, 800], [1920, 1080]]) {
      await page.setViewportSize({ width: w, height: h });
      await page.evaluate(() => window.scrollTo(0, 0));
      await page.click('#view-fit');
      await page.waitForTimeout(300); // the resize observer settles the view's height
      await page.click('#view-fit');
      const boxes = await page.evaluate(() => Object.fromEntries(['viewport', 'stage', 'readout', 'preview-warnings', 'exposure'].map((id) => {
        const r = document.getElementById(id).getBoundingClientRect();
        return [id, { top: r.top, bottom: r.bottom, left: r.left, right: r.right, h: r.height }];
      })));
      for (const [id, b] of Object.entries(boxes))
        assert(b.h > 0 && b.top >= 0 && b.bottom <= h + 0.5 && b.left >= 0 && b.right <= w + 0.5,
          `${w}×${h}: #${id} is not wholly in the window: ${JSON.stringify(b)}`);
      const zoom = await page.textContent('#zoom-level');
      log(`  ${w}×${h}: view ${Math.round(boxes.viewport.h)} px high, fit at ${zoom}, warnings end at ${Math.round(boxes['preview-warnings'].bottom)}`);
      await page.screenshot({ path: path.join(TS_ARTIFACTS, `08-desktop-${w}x${h}.png`) });
      const overflow = await page.evaluate(() => document.documentElement.scrollWidth - window.innerWidth);
      assert(overflow <= 0, `no horizontal scrolling at ${w} px, overflow ${overflow}`);
    }
    await page.setViewportSize({ width: 1280, height: 800 });
    const phone = await context.newPage();
    await phone.setViewportSize({ width: 390, height: 844 });
    await phone.goto(url, { waitUntil: 'load' });
    await phone.getByRole('button', { name: 'show job ' + 'cornell-path (' + first.id + ') in the preview' }).click();
    await phone.waitForFunction(() => Number(document.getElementById('canvas').dataset.tiles) >= 9, null, { timeout: 5000 });
    const o = await phone.evaluate(() => document.documentElement.scrollWidth - window.innerWidth);
    const wide = o <= 0 ? [] : await phone.evaluate(() => [...document.querySelectorAll('body *')].filter((e) => e.getBoundingClientRect().right > window.innerWidth + 0.5 &&
      !e.closest('.table-wrap thead')).slice(0, 8).map((e) => `${e.tagName.toLowerCase()}#${e.id}.${e.className} ${e.textContent.slice(0, 40)}`));
    assert(o <= 0, 'no horizontal scrolling at phone width, overflow ' + o + ': ' + wide.join(' | '));
    const box = await phone.locator('#canvas').boundingBox();
    assert(box && box.width <= 390 && box.width > 200, 'the canvas fits the phone, width ' + (box && box.width));
    await shot('09-phone-390', phone);
    await phone.close();
  });

  await check('a server with --token: the page works from /?access_token=', async () => {
    const tok = await startServer(['--token', 's3cret']);
    try {
      const p = await context.newPage();
      p.on('pageerror', (e) => pageErrors.push('token page: ' + e));
      const noToken = await p.request.get(tok.url + 'api/v1/jobs');
      assert(noToken.status() === 401, 'the API needs the token, got ' + noToken.status());
      await p.goto(tok.url + '?access_token=s3cret', { waitUntil: 'load' });
      await p.waitForFunction(() => document.getElementById('conn').textContent === 'connected', null, { timeout: 5000 });
      await p.fill('#f-scene', small());
      await p.fill('#f-spp', '4');
      await p.click('#f-submit');
      await p.waitForFunction(() => Number(document.getElementById('canvas').dataset.tiles) >= 9, null, { timeout: 15000 });
      await p.locator('#jobs .state-done').waitFor({ timeout: 15000 });
      await shot('10-token', p);
      await p.close();
    } finally {
      tok.srv.kill('SIGTERM');
    }
  });

  await check('no script errors in the page', async () => {
    assert(pageErrors.length === 0, pageErrors.join('\n'));
  });
} finally {
  await context.close();
  proxy.close();
}
log(`${passes} passed, ${failures} failed; screenshots in ${TS_ARTIFACTS}`);
process.exit(failures ? 1 : 0);
