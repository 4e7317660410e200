#!/bin/sh
# bench/compare.sh BUILD_DIR [OUT_DIR] — the speed targets in one table
# (`make bench-compare`). bench/README.md, "The speed targets in one table", says how to read it.
#
# For every scenes/*.json (the scene's own integrator only): render rays/s ÷ the raw Embree rays/s
# on the same rays (bench_throughput's efficiency; target ≥ 0.6) at 1 and at 2 threads, our
# accelerator's share of the gap (accel ÷ Embree), and 2 threads ÷ 1 thread in samples/s
# (ideal 2). Where Blender is installed, also tessera ÷ Cycles time at equal RMSE on the
# Cornell box (bench/cycles/run.sh; target ≤ 0.40), with a quicker series than `make bench`.
# Every figure is a median of ratios taken within side-by-side repetitions.
#
# Writes OUT_DIR/compare.md (printed) and keeps the raw throughput.csv and cycles.* beside it.
# Also bench_scaling (Cornell box; COMPARE_SCALING_ARGS [--reps 3 --seconds 2]) and bench_memory
# (COMPARE_MEMORY_ARGS: bench_memory's options, default 1 M and 4 M triangles and 16 instances).
# Environment: COMPARE_THROUGHPUT_ARGS [--reps 3 --seconds 2]; COMPARE_CYCLES [auto: run where
# Blender is found; 0 skips it]; CYCLES_* as in bench/cycles/run.sh, with these defaults here:
# CYCLES_WIDTH 64, CYCLES_MAX_SPP 256, CYCLES_REF_SPP 2048, CYCLES_REPS 3.
set -eu

BUILD=${1:?usage: compare.sh BUILD_DIR [OUT_DIR]}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
case $BUILD in /*) ;; *) BUILD=$(pwd)/$BUILD ;; esac
OUT=${2:-$BUILD/bench}
case $OUT in /*) ;; *) OUT=$(pwd)/$OUT ;; esac
mkdir -p "$OUT"
[ -x "$BUILD/bench_throughput" ] || { echo "bench: $BUILD/bench_throughput is missing; build first" >&2; exit 1; }

set -- "$ROOT"/scenes/*.json
echo "bench-compare: throughput of $# scene(s) at 1 and 2 threads (a minute or two per scene)" >&2
# shellcheck disable=SC2086 # word splitting of the extra arguments is intended
"$BUILD/bench_throughput" --header --threads 2 --integrators scene ${COMPARE_THROUGHPUT_ARGS:---reps 3 --seconds 2} "$@" \
  > "$OUT/compare_throughput.csv.tmp"
mv "$OUT/compare_throughput.csv.tmp" "$OUT/compare_throughput.csv"

echo "bench-compare: thread scaling on the Cornell box (CPU per sample, run-queue wait, idle; about a minute)" >&2
# shellcheck disable=SC2086 # word splitting of the extra arguments is intended
"$BUILD/bench_scaling" ${COMPARE_SCALING_ARGS:---reps 3 --seconds 2} "$ROOT/scenes/cornell-box.json" > "$OUT/compare_scaling.md"
echo "bench-compare: peak memory per triangle (1 M and 4 M triangles; about a minute)" >&2
# shellcheck disable=SC2086 # word splitting of the extra arguments is intended
"$BUILD/bench_memory" --csv "$OUT/compare_memory.csv" ${COMPARE_MEMORY_ARGS:-} > "$OUT/compare_memory.md"

cycles_note="Blender not installed (make bench-deps): no Cycles comparison."
if [ "${COMPARE_CYCLES:-auto}" != 0 ] && command -v "${BLENDER:-blender}" >/dev/null 2>&1; then
  echo "bench-compare: Cornell box against Blender Cycles at equal RMSE (several minutes; the references are cached)" >&2
  if CYCLES_WIDTH=${CYCLES_WIDTH:-64} CYCLES_MAX_SPP=${CYCLES_MAX_SPP:-256} CYCLES_REF_SPP=${CYCLES_REF_SPP:-2048} \
     CYCLES_REPS=${CYCLES_REPS:-3} "$ROOT/bench/cycles/run.sh" "$BUILD" "$OUT" > "$OUT/compare_cycles.log" 2>&1; then
    cycles_note=""
  else
    cycles_note="The Cycles comparison failed: see $OUT/compare_cycles.log."
  fi
elif [ "${COMPARE_CYCLES:-auto}" = 0 ]; then
  cycles_note="Cycles comparison skipped (COMPARE_CYCLES=0)."
fi

{
  echo "# Speed against the targets"
  echo
  rev=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
  dirty=$(git -C "$ROOT" status --porcelain --untracked-files=no 2>/dev/null | head -n 1)
  echo "$(date -u +%Y-%m-%dT%H:%MZ), commit $rev${dirty:+ (+ local changes)}, $(nproc) CPUs, load average" \
       "$(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo unknown) at the end. Medians of per-repetition ratios."
  echo
  echo "| scene | integrator | rays/sample | render ÷ Embree, 1 thread | render ÷ Embree, 2 threads | accel ÷ Embree, 1 thread | 2 threads ÷ 1 thread |"
  echo "|---|---|--:|--:|--:|--:|--:|"
  awk -F, 'NR > 1 {
      key = $1 "," $2; if (!(key in seen)) { seen[key] = 1; order[++n] = key; scene[key] = $1; integ[key] = $2 }
      if ($3 == 1) { e1[key] = $15; a1[key] = $16; rps[key] = $9 } else { e2[key] = $15; sc[key] = $20 }
    }
    END {
      for (i = 1; i <= n; i++) {
        k = order[i]
        printf "| %s | %s | %.2f | %.3f | %s | %.3f | %s |\n", scene[k], integ[k], rps[k], e1[k],
               (k in e2) ? sprintf("%.3f", e2[k]) : "–", a1[k], (k in sc) ? sprintf("%.2f", sc[k]) : "–"
      }
    }' "$OUT/compare_throughput.csv"
  echo
  echo "Targets: render ÷ Embree ≥ 0.6; 2 threads ÷ 1 thread near 2 on a quiet machine (on a busy one"
  echo "it says how much of the second CPU the render got)."
  echo
  echo "Thread scaling on the Cornell box (bench_scaling: CPU per sample and where the threads' wall time went;"
  echo "target 2 threads ÷ 1 thread ≥ 1.9; \"scaling on free CPUs\" leaves out the run-queue wait, the machine's part):"
  echo
  sed -n '/^| scene/,$p' "$OUT/compare_scaling.md"
  echo
  echo "Peak memory per triangle (bench_memory; target: not above pbrt-v3's, whose figure is derived from its"
  echo "data structures, not measured: docs/performance.md, \"Memory per triangle\"):"
  echo
  sed -n '/^| case/,$p' "$OUT/compare_memory.md"
  echo
  awk -F, 'NR > 1 { n++; if ($6 <= $12) met++ } END {
      printf "Memory target: %d of %d cases at or below pbrt-v3'"'"'s least (leaves of 4 primitives) — %s.\n", met, n, (met == n && n > 0) ? "met" : "missed" }' \
    "$OUT/compare_memory.csv"
  echo
  if [ -z "$cycles_note" ] && [ -f "$OUT/cycles.md" ]; then
    echo "Cornell box against Blender Cycles at equal RMSE ($(grep -c '^tessera,' "$OUT/cycles.csv" 2>/dev/null || echo ?)" \
         "tessera renders; bench/cycles/run.sh):"
    echo
    sed -n '/^| target RMSE/,/^Target:/p' "$OUT/cycles.md"
  else
    echo "$cycles_note"
  fi
} > "$OUT/compare.md"
cat "$OUT/compare.md"
echo "bench-compare: wrote $OUT/compare.md" >&2
