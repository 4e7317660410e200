#!/bin/sh
# bench/bundle.sh [BUILD_DIR] [MIB] — what a posted bundle costs (server/bundle.h): a tar of
# scene.json, an OBJ and MIB MiB of incompressible data (default 100), posted to a fresh
# `tessera serve --data` (plain tar, then gzip), each REPS times (default 3). Reports the
# POST's wall time (upload over loopback, unpack, syncfs, scene load, 201) per MiB, and the
# server's peak resident memory (VmHWM) before and after. By hand only, not in bench/run.
set -eu
build=${1:-build} mib=${2:-100} reps=${REPS:-3}
bin=$build/tessera
work=$(mktemp -d "${TMPDIR:-/tmp}/ts_bench_bundle_XXXXXX")
pid=
trap '[ -n "$pid" ] && kill "$pid" 2>/dev/null; rm -rf "$work"' EXIT
mkdir -p "$work/b/meshes" "$work/data"
printf 'v -1 0 -1\nv 1 0 -1\nv 0 0 1\nf 1 2 3\n' >"$work/b/meshes/tri.obj"
printf '{"tessera":1,"camera":{"from":[0,1,5],"to":[0,0,0]},"film":{"width":16,"height":16},"sampler":{"spp":1},"materials":{"w":{"type":"diffuse"}},"shapes":[{"type":"mesh","file":"meshes/tri.obj","material":"w"}]}\n' >"$work/b/scene.json"
head -c $((mib << 20)) /dev/urandom >"$work/b/filler.bin"
tar -C "$work/b" -cf "$work/b.tar" .
tar -C "$work/b" -czf "$work/b.tgz" .
"$bin" serve --port 0 --threads 1 --data "$work/data" >"$work/out" 2>"$work/err" &
pid=$!
for _ in $(seq 50); do grep -q listening "$work/out" && break; sleep 0.1; done
url=$(sed -n 's/.*listening on \(http[^ ]*\)/\1/p' "$work/out")
hwm() { sed -n 's/^VmHWM: *//p' "/proc/$pid/status"; }
echo "bundle of $mib MiB: tar $(stat -c %s "$work/b.tar") bytes, tgz $(stat -c %s "$work/b.tgz") bytes; server VmHWM at start $(hwm)"
for f in b.tar b.tgz; do
  for r in $(seq "$reps"); do
    t=$(curl -s -o "$work/resp" -w '%{http_code} %{time_total}' -H 'Content-Type: application/x-tar' \
        --data-binary "@$work/$f" "${url}api/v1/jobs")
    echo "$f rep $r: HTTP ${t% *}, ${t#* } s ($(echo "scale=1; $mib / ${t#* }" | bc) MiB/s); VmHWM $(hwm)"
  done
done
