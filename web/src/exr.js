// A small reader of the EXR files tessera serves (renderer/image/exr.c): single-part scan-line
// images with NONE, ZIPS or ZIP compression and HALF/FLOAT channels. It returns the R, G, B
// channels as linear floats, so the preview's exposure works on the real radiance rather
// than on an 8-bit sRGB PNG, and every channel by name (tessera's tiles also hold R.var,
// G.var, B.var — the variance of each pixel's mean — and count, its samples). Anything
// else throws (the caller then uses the PNG).

const MAGIC = 20000630;

function halfToFloat(h) {
  const s = h & 0x8000 ? -1 : 1, e = (h >> 10) & 0x1f, m = h & 0x3ff;
  if (e === 0) return s * m * 2 ** -24;
  if (e === 31) return m ? NaN : s * Infinity;
  return s * (1 + m / 1024) * 2 ** (e - 15);
}

async function inflate(bytes) {
  const ds = new DecompressionStream('deflate'); // zlib-wrapped, as EXR's ZIP is
  const out = await new Response(new Blob([bytes]).stream().pipeThrough(ds)).arrayBuffer();
  return new Uint8Array(out);
}

// EXR ZIP: bytes were split into even/odd halves and delta-coded before deflate.
function unpredict(t) {
  for (let i = 1; i < t.length; i++) t[i] = (t[i - 1] + t[i] - 128) & 0xff;
  const out = new Uint8Array(t.length), half = (t.length + 1) >> 1;
  for (let i = 0, a = 0, b = half; i < t.length; i++) out[i] = i & 1 ? t[b++] : t[a++];
  return out;
}

/** Decodes an EXR ArrayBuffer into {width, height, x0, y0, rgb: Float32Array (w*h*3),
 *  channels: {name: Float32Array (w*h)}}; values are exactly the file's (HALF widened). */
export async function decodeExr(buf) {
  const dv = new DataView(buf);
  const u8 = new Uint8Array(buf);
  if (dv.getUint32(0, true) !== MAGIC) throw new Error('not an EXR file');
  if (dv.getUint32(4, true) & 0x1e00) throw new Error('tiled, deep or multi-part EXR');
  let p = 8;
  const cstr = () => { let e = p; while (u8[e]) e++; const s = new TextDecoder().decode(u8.subarray(p, e)); p = e + 1; return s; };
  let channels = null, win = null, compression = 0;
  for (;;) {
    const name = cstr();
    if (!name) break;
    cstr(); // type
    const size = dv.getInt32(p, true); p += 4;
    const end = p + size;
    if (name === 'channels') {
      channels = [];
      for (;;) {
        const cn = cstr();
        if (!cn) break;
        channels.push({ name: cn, type: dv.getInt32(p, true) });
        p += 16;
      }
    } else if (name === 'dataWindow') {
      win = [0, 4, 8, 12].map((o) => dv.getInt32(p + o, true));
    } else if (name === 'compression') {
      compression = u8[p];
    }
    p = end;
  }
  if (!channels || !win) throw new Error('EXR header without channels or dataWindow');
  const lines = { 0: 1, 2: 1, 3: 16 }[compression];
  if (!lines) throw new Error('EXR compression ' + compression + ' is not supported here');
  const w = win[2] - win[0] + 1, h = win[3] - win[1] + 1;
  const chunks = Math.ceil(h / lines);
  const bytesPer = channels.map((c) => (c.type === 1 ? 2 : 4));
  const lineBytes = bytesPer.reduce((a, b) => a + b * w, 0);
  const want = { R: 0, G: 1, B: 2 };
  const rgb = new Float32Array(w * h * 3);
  const planes = channels.map(() => new Float32Array(w * h));
  let table = p;
  for (let c = 0; c < chunks; c++) {
    const off = Number(dv.getBigUint64(table + 8 * c, true));
    const y = dv.getInt32(off, true), size = dv.getInt32(off + 4, true);
    const n = Math.min(lines, win[3] - y + 1);
    let data = u8.subarray(off + 8, off + 8 + size);
    if (compression !== 0 && size < n * lineBytes) data = unpredict(await inflate(data));
    const ddv = new DataView(data.buffer, data.byteOffset, data.byteLength);
    let q = 0;
    for (let r = 0; r < n; r++) {
      const row = y - win[1] + r;
      channels.forEach((ch, k) => {
        const dst = want[ch.name], plane = planes[k];
        for (let x = 0; x < w; x++) {
          const v = ch.type === 1 ? halfToFloat(ddv.getUint16(q, true)) : ch.type === 2 ? ddv.getFloat32(q, true) : ddv.getUint32(q, true);
          plane[row * w + x] = v;
          if (dst !== undefined) rgb[(row * w + x) * 3 + dst] = v;
          q += bytesPer[k];
        }
      });
    }
  }
  return { width: w, height: h, x0: win[0], y0: win[1], rgb, channels: Object.fromEntries(channels.map((c, k) => [c.name, planes[k]])) };
}
