// A ustar archive of files, written in the browser, so a folder the user picks can be posted
// as a bundle (docs/design.md §5: POST /api/v1/jobs with Content-Type application/x-tar).
// Regular files only, mode 0644, owner 0, time 0: the server ignores all three. Paths up to
// 100 bytes go in the name field; longer ones are split at a '/' into the 155-byte prefix
// and the name, as ustar allows; a path that does not split so is refused with a sentence.
// Also used by tests/browser/ui_test.mjs (in node) to make the bundles it uploads.

const enc = new TextEncoder();

function octal(header, at, width, value) {
  const s = value.toString(8).padStart(width - 1, '0');
  if (s.length > width - 1) throw new Error('a tar field overflows: ' + value);
  header.set(enc.encode(s), at);
  header[at + width - 1] = 0;
}

// The name and prefix fields of a path (UTF-8 bytes).
function splitPath(path) {
  const b = enc.encode(path);
  if (b.length <= 100) return [b, new Uint8Array(0)];
  for (let i = b.length - 1; i > 0; i--) {
    if (b[i] !== 0x2f) continue;
    if (i <= 155 && b.length - i - 1 <= 100 && b.length - i - 1 > 0) return [b.slice(i + 1), b.slice(0, i)];
  }
  throw new Error(`'${path}': a path this long cannot go in a tar (at most 155 bytes of folders and 100 of name)`);
}

// files: [{ path: 'meshes/a.obj', data: Uint8Array }] → Uint8Array of the tar.
export function makeTar(files) {
  const parts = [];
  let size = 0;
  for (const f of files) {
    const [name, prefix] = splitPath(f.path);
    const h = new Uint8Array(512);
    h.set(name, 0);
    octal(h, 100, 8, 0o644);
    octal(h, 108, 8, 0);
    octal(h, 116, 8, 0);
    octal(h, 124, 12, f.data.length);
    octal(h, 136, 12, 0);
    h.fill(0x20, 148, 156); // the checksum counts its own field as spaces
    h[156] = 0x30; // '0': a regular file
    h.set(enc.encode('ustar\u0000'), 257);
    h.set(enc.encode('00'), 263);
    h.set(prefix, 345);
    let sum = 0;
    for (const v of h) sum += v;
    octal(h, 148, 7, sum);
    h[155] = 0x20;
    parts.push(h, f.data);
    const pad = (512 - (f.data.length % 512)) % 512;
    if (pad) parts.push(new Uint8Array(pad));
    size += 512 + f.data.length + pad;
  }
  parts.push(new Uint8Array(1024)); // two zero blocks: the end
  size += 1024;
  const out = new Uint8Array(size);
  let at = 0;
  for (const p of parts) { out.set(p, at); at += p.length; }
  return out;
}
