#!/bin/sh
# bench/pbrt3.sh — tessera against pbrt-v3 on the shared pbrt-v3 scenes (docs/design.md §4c):
# for each scene one tessera render at pbrt-v3's reference spp on 2 threads, timed, and the
# table: scene, tessera ÷ pbrt-v3 image mean per channel, spp, tessera's seconds, pbrt-v3's
# (REFERENCES.md, also 2 threads) and their ratio. The worst-block figures (in σ) are the
# pbrt3_corpus test's (ctest -R pbrt3_corpus -V), printed first. Reported, never pass/fail.
#   bench/pbrt3.sh [BUILD_DIR]   (default: build)
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
dir=$root/../shared/scenes/pbrt-v3
if [ ! -f "$dir/REFERENCES.md" ]; then
    echo "SKIPPED: $dir is absent"
    exit 0
fi
echo "# the comparison (K = 8 renders per scene; worst block t and its p against the Bonferroni bound)"
"$build/pbrt3_corpus" "$dir" || true
echo
echo "# equal spp: tessera vs pbrt-v3 time"
"$build/pbrt3_corpus" "$dir" --bench
