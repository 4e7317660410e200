// farm_server.mjs — `tessera serve --farm slurm` against the one-node Slurm that
// farm_server_test.sh started (SLURM_CONF, T: its temporary folder). Every check is a real
// run: the Slurm commands are Slurm's, the images are compared bit for bit with the CLI's
// (bench_exr_compare: every channel of every pixel as raw float bits).
import { spawn, spawnSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { createRequire } from 'node:module';

const { TS_BINARY, TS_SOURCE_DIR, TS_EXR_COMPARE, TS_BUILD_DIR, T } = process.env;
const t0 = Date.now();
const log = (...a) => console.log(`[${((Date.now() - t0) / 1000).toFixed(1)}s]`, ...a);
let failures = 0;
function assert(cond, msg) { if (!cond) throw new Error(msg); }
async function check(name, fn) {
  const t = Date.now();
  try {
    await fn();
    log(`PASS ${name} (${((Date.now() - t) / 1000).toFixed(1)} s)`);
  } catch (e) {
    failures++;
    log(`FAIL ${name}: ${e && e.stack ? e.stack : e}`);
  }
}
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
async function until(what, fn, seconds = 60) {
  const end = Date.now() + seconds * 1000;
  for (;;) {
    const v = await fn();
    if (v) return v;
    if (Date.now() > end) throw new Error(`timed out after ${seconds} s waiting for ${what}`);
    await sleep(200);
  }
}
const sh = (cmd, args) => {
  const r = spawnSync(cmd, args, { encoding: 'utf8' });
  return { status: r.status, out: r.stdout || '', err: r.stderr || '' };
};

// ---------------------------------------------------------------- scenes
// The Cornell box at 64×64 (2×2 tiles): small enough for a shared two-core machine.
const cornell = JSON.parse(fs.readFileSync(path.join(TS_SOURCE_DIR, 'scenes/cornell-box.json'), 'utf8'));
function scene(spp, farm) {
  const d = structuredClone(cornell);
  d.film.width = d.film.height = 64;
  d.sampler.spp = spp;
  d.job = { ...(d.job || {}) };
  delete d.job.spp;
  if (farm) d.job.farm = farm;
  else delete d.job.farm;
  return d;
}
// The CLI's render of the same scene, seed and spp: the image a farm job must equal.
function reference(spp) {
  const file = path.join(T, `plain-${spp}.json`), out = path.join(T, `cli-${spp}.exr`);
  if (!fs.existsSync(out)) {
    fs.writeFileSync(file, JSON.stringify(scene(spp)));
    const r = sh(TS_BINARY, ['render', file, '--threads', '2', '--quiet', '-o', out]);
    assert(r.status === 0, `tessera render failed: ${r.err}`);
  }
  return out;
}
function sameImage(url, ref, name) {
  return (async () => {
    const file = path.join(T, name + '.exr');
    const resp = await fetch(url);
    assert(resp.status === 200, `GET ${url}: ${resp.status}`);
    fs.writeFileSync(file, Buffer.from(await resp.arrayBuffer()));
    const r = sh(TS_EXR_COMPARE, [file, ref]);
    assert(r.status === 0, `the farm job's image differs from the CLI's: ${r.out}${r.err}`);
    log(`  ${name}: ${r.out.trim()} (against the CLI's render)`);
  })();
}

// ---------------------------------------------------------------- servers
const servers = [];
function serve(args, env = process.env) {
  const srv = spawn(TS_BINARY, ['serve', '--bind', '127.0.0.1', '--port', '0', '--threads', '1', ...args],
    { stdio: ['ignore', 'pipe', 'pipe'], env });
  servers.push(srv);
  srv.stderrText = '';
  srv.stderr.on('data', (d) => { srv.stderrText += d; });
  srv.exited = new Promise((resolve) => srv.on('exit', (code, sig) => resolve({ code, sig })));
  srv.url = new Promise((resolve, reject) => {
    let out = '';
    const timer = setTimeout(() => reject(new Error('tessera serve printed no URL in 15 s: ' + srv.stderrText)), 15000);
    srv.stdout.on('data', (d) => {
      out += d;
      const m = /listening on (http:\/\/[^\s]+)\//.exec(out);
      if (m) { clearTimeout(timer); resolve(m[1]); }
    });
    srv.exited.then(({ code }) => reject(new Error(`tessera serve exited with ${code}: ${srv.stderrText}`)));
  });
  return srv;
}
process.on('exit', () => { for (const s of servers) if (s.exitCode === null) s.kill('SIGKILL'); });
async function post(base, doc, query = '') {
  const r = await fetch(`${base}/api/v1/jobs${query}`, { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(doc) });
  return { status: r.status, body: await r.json() };
}
const status = async (base, id) => (await fetch(`${base}/api/v1/jobs/${id}`)).json();
const ended = (s) => ['done', 'cancelled', 'failed'].includes(s.state);

const farmDir = path.join(T, 'farm'), dataDir = path.join(T, 'data');
const farmArgs = ['--farm', 'slurm', '--farm-dir', farmDir, '--data', dataDir, '--farm-checkpoint-interval', '0.5',
  '--max-shards', '8'];

// ---------------------------------------------------------------- refusals
await check('--farm-dir that cannot be written: serve exits 1 naming it', async () => {
  for (const dir of ['/proc/tessera-farm-test', '/proc/self']) {
    const srv = serve(['--farm', 'slurm', '--farm-dir', dir]);
    srv.url.catch(() => {});
    const { code } = await srv.exited;
    assert(code === 1, `exit status ${code} for --farm-dir ${dir}, expected 1`);
    assert(srv.stderrText.includes(`--farm-dir ${dir}`), `the message does not name ${dir}: ${srv.stderrText}`);
    log('  ' + srv.stderrText.trim().split('\n').pop());
  }
});

await check('a farm job on a server without --farm: 422', async () => {
  const srv = serve([]);
  const base = await srv.url;
  const r = await post(base, scene(16, { shards: 2 }));
  assert(r.status === 422 && /no farm/.test(r.body.error), `got ${r.status} ${JSON.stringify(r.body)}`);
  log('  ' + r.body.error);
  srv.kill('SIGTERM');
  await srv.exited;
});

const main = serve(farmArgs);
let base = await main.url;
log('farm server at', base);

await check('shards not a whole number in 1 … --max-shards: 400', async () => {
  for (const shards of [0, -1, 2.5, 9, '4', null]) {
    const r = await post(base, scene(16, { shards }));
    assert(r.status === 400 && /job\.farm\.shards/.test(r.body.error), `shards ${shards}: ${r.status} ${JSON.stringify(r.body)}`);
  }
  const r = await post(base, scene(4, { shards: 8 }));
  assert(r.status === 400 && /without samples/.test(r.body.error), `8 shards of 4 spp: ${r.status} ${JSON.stringify(r.body)}`);
  // An adaptive job's pixels stop at counts chosen from the whole image: no exact merge.
  const ad = scene(16, { shards: 2 });
  ad.job.adaptive = true;
  const ra = await post(base, ad);
  assert(ra.status === 400 && /job\.adaptive/.test(ra.body.error), `adaptive farm job: ${ra.status} ${JSON.stringify(ra.body)}`);
  log('  ' + ra.body.error);
  const list = await (await fetch(`${base}/api/v1/jobs`)).json();
  assert(list.jobs.length === 0, 'a refused job was listed');
});

await check('sbatch refusing or missing: the job fails with Slurm\'s message', async () => {
  const bad = serve(['--farm', 'slurm', '--farm-dir', path.join(T, 'farm-bad'), '--farm-sbatch-arg=--partition=nosuch']);
  const nopath = serve(['--farm', 'slurm', '--farm-dir', path.join(T, 'farm-nopath')], { ...process.env, PATH: '/nonexistent' });
  for (const [srv, want] of [[bad, /sbatch did not submit.*(partition|nosuch)/i], [nopath, /cannot run sbatch/]]) {
    const b = await srv.url;
    const r = await post(b, scene(16, { shards: 2 }));
    assert(r.status === 201, `POST: ${r.status} ${JSON.stringify(r.body)}`);
    const s = await until('the job to fail', async () => { const s = await status(b, r.body.id); return ended(s) && s; }, 30);
    assert(s.state === 'failed' && want.test(s.error), `state ${s.state}, error ${s.error}`);
    log('  ' + s.error);
    assert((await fetch(`${b}/healthz`)).status === 200, 'the server is not healthy afterwards');
    srv.kill('SIGTERM');
    await srv.exited;
  }
});

// ---------------------------------------------------------------- a 4-shard job
let shardJob = null;
await check('4 shards over HTTP: events, then the EXR equals the CLI\'s bit for bit', async () => {
  const r = await post(base, scene(64, { shards: 4 }));
  assert(r.status === 201, `POST: ${r.status} ${JSON.stringify(r.body)}`);
  shardJob = r.body.id;
  const events = { tile: 0, progress: 0, done: 0 };
  const resp = await fetch(`${base}/api/v1/jobs/${shardJob}/events`);
  assert(resp.status === 200, `events: ${resp.status}`);
  const dec = new TextDecoder();
  let text = '', lastProgress = null;
  const reader = resp.body.getReader();
  for (;;) {
    const { value, done } = await reader.read();
    if (done) break;
    text += dec.decode(value, { stream: true });
    let k;
    while ((k = text.indexOf('\n\n')) >= 0) {
      const frame = text.slice(0, k);
      text = text.slice(k + 2);
      const ev = /^event: (\w+)/m.exec(frame), data = /^data: (.*)$/m.exec(frame);
      if (ev && events[ev[1]] !== undefined) events[ev[1]]++;
      if (ev && ev[1] === 'progress') lastProgress = JSON.parse(data[1]);
    }
  }
  log(`  events: ${JSON.stringify(events)}`);
  assert(events.done === 1 && events.tile >= 4 && events.progress >= 2, `events ${JSON.stringify(events)}`);
  assert(lastProgress && lastProgress.state === 'done' && lastProgress.spp === 64, `last progress ${JSON.stringify(lastProgress)}`);
  const s = await status(base, shardJob);
  assert(s.state === 'done' && s.spp_done === 64 && s.halt_reason === 'spp', `status ${s.state} ${s.spp_done}`);
  assert(/^\d+$/.test(s.farm.slurm_job) && s.farm.shards === 4, `farm ${JSON.stringify(s.farm)}`);
  assert(s.farm.tasks.every((t) => t.state === 'done' && t.spp === 16 && t.spp_target === 16), `tasks ${JSON.stringify(s.farm.tasks)}`);
  const h = await (await fetch(`${base}/api/v1/jobs/${shardJob}/history`)).json();
  assert(h.points.length >= 2 && h.points.at(-1).kind === 'done', `history ${JSON.stringify(h.points)}`);
  const saved = JSON.parse(fs.readFileSync(path.join(dataDir, 'jobs', shardJob, 'farm.json'), 'utf8'));
  assert(saved.slurm_job === s.farm.slurm_job, `farm.json ${JSON.stringify(saved)}`);
  await sameImage(`${base}/api/v1/jobs/${shardJob}/image.exr`, reference(64), 'http-4-shards');
});

// ---------------------------------------------------------------- cancel
await check('cancel mid-run: scancel, squeue empty, the merged image stays', async () => {
  const r = await post(base, scene(16384, { shards: 4 }));
  assert(r.status === 201, `POST: ${r.status}`);
  const id = r.body.id;
  // Two tasks at once on the node's CPUs, both with samples merged.
  const s0 = await until('two tasks running with merged samples', async () => {
    const s = await status(base, id);
    return s.farm.tasks.filter((t) => t.state === 'running' && t.spp > 0).length >= 2 && s;
  }, 60);
  const c = await fetch(`${base}/api/v1/jobs/${id}/cancel`, { method: 'POST', headers: { 'Content-Type': 'application/json' } });
  const cs = await c.json();
  assert(c.status === 200 && ['cancelling', 'cancelled'].includes(cs.state), `cancel: ${c.status} ${cs.state}`);
  const s = await until('cancelled', async () => { const s = await status(base, id); return ended(s) && s; }, 60);
  assert(s.state === 'cancelled' && s.halt_reason === 'cancelled', `state ${s.state}`);
  const q = sh('squeue', ['-h', '-j', s.farm.slurm_job]);
  assert(q.status === 0 && q.out.trim() === '', `squeue still lists: ${q.out}${q.err}`);
  assert(s.spp_done >= s0.spp_done && s.samples > 0, `the pixels went: spp ${s.spp_done}, samples ${s.samples}`);
  const img = await fetch(`${base}/api/v1/jobs/${id}/image.exr`);
  assert(img.status === 200 && (await img.arrayBuffer()).byteLength > 1000, `image.exr ${img.status}`);
  log(`  cancelled at ${s.spp_done} of 16384 spp (${s.farm.tasks.map((t) => t.state + ' ' + t.spp).join(', ')})`);
});

// ---------------------------------------------------------------- a task cancelled behind the server's back
await check('scancel of one task: requeued, resumed, the image still equal', async () => {
  const r = await post(base, scene(1024, { shards: 4 }));
  const id = r.body.id;
  const s0 = await until('task 0 running with merged samples', async () => {
    const s = await status(base, id);
    return s.farm && s.farm.slurm_job && s.farm.tasks[0].state === 'running' && s.farm.tasks[0].spp > 0 && s;
  }, 60);
  const k = sh('scancel', [`${s0.farm.slurm_job}_0`]);
  assert(k.status === 0, `scancel: ${k.err}`);
  const s = await until('done', async () => { const s = await status(base, id); return ended(s) && s; }, 120);
  assert(s.state === 'done', `state ${s.state}: ${s.error}`);
  assert(s.farm.tasks[0].retries === 1 && s.farm.tasks.slice(1).every((t) => t.retries === 0), `retries ${JSON.stringify(s.farm.tasks)}`);
  assert(/farm\.requeued.*CANCELLED/.test(main.stderrText), 'no farm.requeued line naming the cancellation');
  await sameImage(`${base}/api/v1/jobs/${id}/image.exr`, reference(1024), 'requeued-task');
});

// ---------------------------------------------------------------- kill -9 and restart
let restarted = null;
await check('kill -9 of the server mid-run, restart on the same --data: re-attached, submitted once', async () => {
  const r = await post(base, scene(1024, { shards: 4 }));
  const id = r.body.id;
  const s0 = await until('a merged checkpoint', async () => {
    const s = await status(base, id);
    return s.spp_done > 0 && s.farm.tasks.some((t) => t.state !== 'done') && s;
  }, 60);
  main.kill('SIGKILL');
  await main.exited;
  restarted = serve(farmArgs);
  base = await restarted.url;
  const s = await until('done after the restart', async () => { const s = await status(base, id); return ended(s) && s; }, 120);
  assert(s.state === 'done', `state ${s.state}: ${s.error}`);
  assert(s.farm.slurm_job === s0.farm.slurm_job, `Slurm job ${s.farm.slurm_job} after the restart, ${s0.farm.slurm_job} before`);
  const q = sh('squeue', ['-h', '--states=all', `--name=tessera-${id}`, '-o', '%F']);
  const arrays = [...new Set(q.out.split('\n').filter(Boolean))];
  assert(arrays.length === 1 && arrays[0] === s0.farm.slurm_job, `arrays named tessera-${id}: ${JSON.stringify(arrays)}`);
  assert(new RegExp(`re-attached to Slurm array ${s0.farm.slurm_job}`).test(restarted.stderrText), 'no re-attach line');
  assert(!new RegExp(`farm\\.submitted id=${id}`).test(restarted.stderrText), 'the restarted server submitted again');
  log(`  killed at ${s0.spp_done} spp; one array (${arrays[0]}), re-attached, finished`);
  await sameImage(`${base}/api/v1/jobs/${id}/image.exr`, reference(1024), 'after-restart');
});

// ---------------------------------------------------------------- bundles
// A tar of scene.json with the mesh files it names, and of a scene.pbrt (its spp from ?spp=):
// the files reach the nodes through --farm-dir; each equals the CLI's render of the folder.
await check('bundles with ?shards=2 (scene.json with mesh files; scene.pbrt with ?spp=8) equal the CLI\'s', async () => {
  const dir = path.join(T, 'bundle'), pdir = path.join(T, 'bundle-pbrt');
  fs.mkdirSync(path.join(dir, 'meshes'), { recursive: true });
  fs.mkdirSync(path.join(pdir, 'meshes'), { recursive: true });
  const tri = 'v -3 0 -3\nv 3 0 -3\nv 0 0 3\nf 1 3 2\n';
  const quad = 'ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n' +
    'element face 2\nproperty list uchar int vertex_indices\nend_header\n-1 0 -1\n1 0 -1\n1 2 -1\n-1 2 -1\n3 0 1 2\n3 0 2 3\n';
  fs.writeFileSync(path.join(dir, 'meshes/tri.obj'), tri);
  fs.writeFileSync(path.join(dir, 'meshes/quad.ply'), quad);
  fs.writeFileSync(path.join(pdir, 'meshes/quad.ply'), quad);
  fs.writeFileSync(path.join(dir, 'scene.json'), JSON.stringify({
    tessera: 1, camera: { from: [0, 1.5, 5], to: [0, 0.6, 0], fov: 35 },
    film: { width: 32, height: 24, filter: { type: 'box' } }, sampler: { spp: 16 },
    integrator: { type: 'path', max_depth: 3 }, materials: { w: { type: 'diffuse' } },
    shapes: [{ type: 'mesh', file: 'meshes/tri.obj', material: 'w' }, { type: 'mesh', file: 'meshes/quad.ply', material: 'w' }],
    lights: [{ type: 'point', position: [0, 3, 2], intensity: [20, 20, 20] }] }));
  fs.writeFileSync(path.join(pdir, 'scene.pbrt'), 'LookAt 0 1.5 5  0 0.6 0  0 1 0\nCamera "perspective" "float fov" [35]\n' +
    'Film "image" "integer xresolution" [32] "integer yresolution" [24]\nSampler "sobol" "integer pixelsamples" [4]\n' +
    'PixelFilter "box"\nWorldBegin\nLightSource "point" "point from" [0 3 2] "rgb I" [20 20 20]\nMaterial "matte"\n' +
    'Shape "plymesh" "string filename" "meshes/quad.ply"\nWorldEnd\n');
  for (const [d, file, query, cli] of [[dir, 'scene.json', '?shards=2', []], [pdir, 'scene.pbrt', '?shards=2&spp=8', ['--spp', '8']]]) {
    const tar = path.join(T, path.basename(d) + '.tar');
    const t = sh('tar', ['-C', d, '-cf', tar, file, 'meshes']);
    assert(t.status === 0, 'tar: ' + t.err);
    const r = await fetch(`${base}/api/v1/jobs${query}`, { method: 'POST', headers: { 'Content-Type': 'application/x-tar' }, body: fs.readFileSync(tar) });
    const body = await r.json();
    assert(r.status === 201, `POST ${file}${query}: ${r.status} ${JSON.stringify(body)}`);
    const s = await until(`the ${file} bundle done`, async () => { const s = await status(base, body.id); return ended(s) && s; }, 60);
    assert(s.state === 'done' && s.farm.shards === 2, `state ${s.state}: ${s.error}`);
    const ref = path.join(T, path.basename(d) + '-cli.exr');
    const c = sh(TS_BINARY, ['render', path.join(d, file), '--threads', '2', '--quiet', ...cli, '-o', ref]);
    assert(c.status === 0, `tessera render ${file}: ${c.err}`);
    await sameImage(`${base}/api/v1/jobs/${body.id}/image.exr`, ref, 'bundle-' + file);
  }
  const bad = await fetch(`${base}/api/v1/jobs?shards=01`, { method: 'POST', headers: { 'Content-Type': 'application/x-tar' }, body: fs.readFileSync(path.join(T, 'bundle.tar')) });
  assert(bad.status === 400, `?shards=01: ${bad.status}`);
  const json = await fetch(`${base}/api/v1/jobs?shards=2`, { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(scene(16)) });
  assert(json.status === 400, `a JSON POST with ?shards: ${json.status}`);
});

// ---------------------------------------------------------------- out of retries
await check('a task that keeps failing: the job fails naming it and its stderr, the array is cancelled', async () => {
  const srv = serve(['--farm', 'slurm', '--farm-dir', path.join(T, 'farm-noretry'), '--farm-retries', '0',
    '--farm-checkpoint-interval', '0.5']);
  const b = await srv.url;
  const r = await post(b, scene(4096, { shards: 4 }));
  const s0 = await until('task 1 running with merged samples', async () => {
    const s = await status(b, r.body.id);
    return s.farm.slurm_job && s.farm.tasks[1].state === 'running' && s.farm.tasks[1].spp > 0 && s;
  }, 60);
  assert(sh('scancel', [`${s0.farm.slurm_job}_1`]).status === 0, 'scancel failed');
  const s = await until('failed', async () => { const s = await status(b, r.body.id); return ended(s) && s; }, 60);
  assert(s.state === 'failed', `state ${s.state}`);
  assert(new RegExp(`^task 1 of 4 \\(Slurm job ${s0.farm.slurm_job}_1\\) failed after 0 requeues: CANCELLED.*stderr: .*Terminated: saved samples`).test(s.error),
    `error: ${s.error}`);
  assert(s.farm.tasks[1].state === 'failed' && s.spp_done >= 0 && s.samples > 0, `tasks ${JSON.stringify(s.farm.tasks)}`);
  await until('squeue empty', () => sh('squeue', ['-h', '-j', s0.farm.slurm_job]).out.trim() === '', 30);
  log('  ' + s.error.slice(0, 160) + '…');
  srv.kill('SIGTERM');
  await srv.exited;
});

// ---------------------------------------------------------------- the web UI's shard view
await check('the web UI shows each shard\'s state and spp', async () => {
  const CHROMIUM = process.env.TS_CHROMIUM || '/usr/bin/chromium';
  const mods = path.join(TS_BUILD_DIR, 'web/src/node_modules');
  if (!fs.existsSync(CHROMIUM) || !fs.existsSync(path.join(mods, 'playwright-core'))) {
    log(`  NOT RUN: needs chromium at ${CHROMIUM} and playwright-core in ${mods}`);
    return;
  }
  const require = createRequire(path.join(mods, 'x.js'));
  const { chromium } = require('playwright-core');
  const userDir = fs.mkdtempSync(path.join(os.tmpdir(), 'tessera-chromium-'));
  const context = await chromium.launchPersistentContext(userDir, {
    executablePath: CHROMIUM, headless: true, viewport: { width: 1280, height: 800 },
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--no-first-run', '--disable-background-networking'],
  });
  try {
    const page = await context.newPage();
    const errors = [];
    page.on('pageerror', (e) => errors.push(String(e)));
    await page.goto(base + '/', { waitUntil: 'load' });
    // A farm job running now, watched from the start: its tasks move from pending to done.
    const r = await post(base, scene(512, { shards: 4 }));
    const id = r.body.id;
    await page.locator(`#jobs tr[data-id="${id}"] button.link`).click({ timeout: 10000 });
    await until('the shard view of the job', () => page.evaluate((id) => document.getElementById('farm').dataset.job === id, id), 10);
    const heading = await page.textContent('#farm-h');
    assert(/Slurm/.test(heading) && /4 shards/.test(heading), `heading '${heading}'`);
    const rows = () => page.$$eval('#farm-tasks tbody tr', (trs) => trs.map((tr) => [...tr.cells].map((c) => c.textContent.trim())));
    const seen = new Set();
    await until('every shard done in the page', async () => {
      const r = await rows();
      for (const c of r) seen.add(c[1]);
      return r.length === 4 && r.every((c) => c[1] === 'done' && c[2] === '128 / 128') && r;
    }, 60).catch(async (e) => { throw new Error(e.message + ': ' + JSON.stringify(await rows())); });
    log(`  the page showed shard states ${[...seen].join(', ')}`);
    assert(seen.size >= 2, 'the page never showed a shard before it was done');
    await page.screenshot({ path: path.join(T, 'shard-view.png'), fullPage: true });
    const artifacts = path.join(TS_BUILD_DIR, 'test-artifacts/farm');
    fs.mkdirSync(artifacts, { recursive: true });
    fs.copyFileSync(path.join(T, 'shard-view.png'), path.join(artifacts, 'shard-view.png'));
    // A local job has no shard view.
    const local = (await post(base, { ...scene(4) })).body.id;
    await page.locator(`#jobs tr[data-id="${local}"] button.link`).click({ timeout: 10000 });
    await until('the shard view hidden for a local job', () => page.isHidden('#farm'), 10);
    assert(errors.length === 0, 'page errors: ' + errors.join('; '));
  } finally {
    await context.close();
    fs.rmSync(userDir, { recursive: true, force: true });
  }
});

for (const s of servers) if (s.exitCode === null) s.kill('SIGTERM');
await Promise.all(servers.map((s) => s.exited));
log(failures ? `${failures} check(s) failed` : 'farm_server: all checks passed');
process.exit(failures ? 1 : 0);
