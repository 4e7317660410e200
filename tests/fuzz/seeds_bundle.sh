#!/bin/sh
# seeds_bundle.sh OUTDIR — writes the seeds of fuzz_bundle (tests/fuzz/README.md) into
# OUTDIR: tar bundles as GNU tar writes them (ustar, pax and GNU formats, plain and gzip),
# a good one and one of every refused kind (symbolic and hard links, a FIFO, '..', an
# absolute path, a duplicate, no scene, a truncated one). tests/fuzz/run.sh runs this into
# a scratch folder, so no binary file is committed. POSIX sh with tar and gzip.
set -eu
out=$1
mkdir -p "$out"
src=$(mktemp -d "${TMPDIR:-/tmp}/ts_bundle_seeds_XXXXXX")
trap 'rm -rf "$src"' EXIT
mkdir -p "$src/b/meshes" "$src/b/textures"
printf '{"tessera":1,"camera":{"from":[0,0,5],"to":[0,0,0]},"materials":{"w":{"type":"diffuse"}},"shapes":[{"type":"mesh","file":"meshes/tri.obj","material":"w"}]}\n' >"$src/b/scene.json"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' >"$src/b/meshes/tri.obj"
printf 'P3\n' >"$src/b/textures/t.pfm"
for f in ustar pax gnu; do
  tar -b 1 --format=$f -cf "$out/good-$f.tar" -C "$src/b" .
done
tar -b 1 --format=pax -czf "$out/good.tgz" -C "$src/b" scene.json meshes
ln -s /etc/passwd "$src/b/link"
tar -b 1 --format=pax -cf "$out/symlink.tar" -C "$src/b" scene.json link
rm "$src/b/link"
ln "$src/b/scene.json" "$src/b/copy.json"
tar -b 1 --format=pax -cf "$out/hardlink.tar" -C "$src/b" scene.json copy.json
rm "$src/b/copy.json"
if mkfifo "$src/b/pipe" 2>/dev/null; then
  tar -b 1 --format=ustar -cf "$out/fifo.tar" -C "$src/b" scene.json pipe
  rm "$src/b/pipe"
fi
(cd "$src/b/meshes" && tar -b 1 -P --format=pax -cf "$out/dotdot.tar" ../scene.json tri.obj)
tar -b 1 -P --format=gnu -cf "$out/absolute.tar" "$src/b/scene.json"
tar -b 1 --format=ustar -cf "$out/duplicate.tar" -C "$src/b" scene.json scene.json
tar -b 1 --format=ustar -cf "$out/noscene.tar" -C "$src/b" meshes
tar -b 1 --format=pax -cf "$out/wrapped.tar" -C "$src" b
head -c 1300 "$out/good-pax.tar" >"$out/truncated.tar"
gzip -c "$out/good-ustar.tar" | head -c 200 >"$out/truncated.tgz"
