#!/bin/sh
# bench/adaptive.sh BUILD_DIR [OUT_DIR] — time to 1% relative error with and without adaptive
# sampling (bench_adaptive, bench/adaptive.c) on the Cornell box and every scene of
# ../shared/scenes/pbrt-v3, with pbrt-v3's reference spp and times from its REFERENCES.md:
# the targets table of docs/performance.md. bench/run calls it; BENCH_ADAPTIVE_ARGS adds
# options (e.g. "--seconds 300 --side 4" for a longer, larger measurement).
set -eu
BUILD=${1:-build}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
OUT=${2:-$BUILD/bench}
mkdir -p "$OUT"
SHARED=$ROOT/../shared/scenes/pbrt-v3
set -- "$ROOT/scenes/cornell-box.json"
REFS=""
if [ -f "$SHARED/REFERENCES.md" ]; then
  for f in "$SHARED"/*/*.pbrt; do [ -e "$f" ] && set -- "$@" "$f"; done
  REFS=$(sed -n 's/^- \([A-Za-z0-9_-]*\):.*reference: [^,]*, \([0-9]*\) spp, \([0-9.]*\) s .*/--ref-spp \1=\2 --ref-time \1=\3/p' \
         "$SHARED/REFERENCES.md" | tr '\n' ' ')
else
  echo "bench: $SHARED is absent: the Cornell box only (pbrt-v3 scenes SKIPPED)" >&2
fi
echo "bench: adaptive sampling on $# scene(s): a few minutes each" >&2
# shellcheck disable=SC2086 # word splitting of the options is intended
"$BUILD/bench_adaptive" ${BENCH_ADAPTIVE_ARGS:-} $REFS "$@" > "$OUT/adaptive.md.tmp" 2> "$OUT/adaptive.log"
mv "$OUT/adaptive.md.tmp" "$OUT/adaptive.md"
cat "$OUT/adaptive.md"
echo "bench: wrote $OUT/adaptive.md" >&2
