// Vite build of the web UI into dist/ (embedded in the tessera binary by CMake). The shipped
// example scenes (../scenes/*.json, or TS_SCENES_DIR) are emitted as dist/scenes/*.json with
// an index, leaving out scenes that reference files (a posted scene may read files only from
// the server's --assets folder, which the UI cannot count on).
import fs from 'node:fs';
import path from 'node:path';

const scenesDir = process.env.TS_SCENES_DIR || path.resolve(import.meta.dirname, '../scenes');

function usesFiles(v) {
  if (Array.isArray(v)) return v.some(usesFiles);
  if (v && typeof v === 'object')
    return Object.entries(v).some(([k, x]) => ((k === 'file' || k === 'map') && typeof x === 'string') || usesFiles(x));
  return false;
}

// [file, title, text] of each example scene an HTTP job can use.
function sceneIndex() {
  const out = [];
  for (const f of fs.readdirSync(scenesDir).filter((f) => f.endsWith('.json')).sort()) {
    const text = fs.readFileSync(path.join(scenesDir, f), 'utf8');
    let doc;
    try { doc = JSON.parse(text); } catch { continue; }
    if (usesFiles(doc)) continue;
    const w = doc.film && doc.film.width, h = doc.film && doc.film.height;
    out.push([f, `${f.replace(/\.json$/, '')} (${(doc.integrator && doc.integrator.type) || 'path'}, ${w}×${h})`, text]);
  }
  return out;
}

function exampleScenes() {
  return {
    name: 'tessera-example-scenes',
    // `npx vite`: the same files, from the scenes folder.
    configureServer(server) {
      server.middlewares.use('/scenes/', (req, res, next) => {
        const f = decodeURIComponent(req.url.split('?')[0]).replace(/^\//, '');
        if (f === 'index.json') return res.end(JSON.stringify(sceneIndex().map(([file, title]) => ({ file, title }))));
        if (!/^[\w.-]+\.json$/.test(f) || !fs.existsSync(path.join(scenesDir, f))) return next();
        res.setHeader('Content-Type', 'application/json');
        res.end(fs.readFileSync(path.join(scenesDir, f)));
      });
    },
    generateBundle() {
      const index = [];
      for (const [file, title, text] of sceneIndex()) {
        index.push({ file, title });
        this.emitFile({ type: 'asset', fileName: 'scenes/' + file, source: text });
      }
      this.emitFile({ type: 'asset', fileName: 'scenes/index.json', source: JSON.stringify(index) });
    },
  };
}

export default {
  base: './',
  build: { outDir: process.env.TS_WEB_OUT || 'dist', emptyOutDir: true, assetsInlineLimit: 0, chunkSizeWarningLimit: 1000 },
  plugins: [exampleScenes()],
  // `npx vite` for live reload while working on the UI: the API of a running tessera serve.
  server: { proxy: { '/api': process.env.TS_SERVER || 'http://127.0.0.1:8080' } },
};
