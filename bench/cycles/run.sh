#!/bin/sh
# bench/cycles/run.sh BUILD_DIR OUT_DIR — tessera against Blender Cycles on the same scene
# at equal RMSE (the speed target of docs/design.md §8: ≤ 1/2.5 of Cycles' time).
# bench/README.md, "Against Blender Cycles", says how to read the output.
#
# Each renderer is measured against its own converged image (two halves with other seeds,
# cached), so what is compared is how fast each converges to its own answer; the two
# answers are compared separately (agreement line of cycles.md).
#
# Writes into OUT_DIR:
#   cycles.csv        one row per renderer × repetition × spp: time, RMSE (reference noise subtracted), …
#   cycles.md         summary: agreement, ms/spp, slopes, time to equal RMSE and the ratio
#   cycles/           the scene as rendered, the images of the series, the Blender logs
#
# Environment (defaults in brackets):
#   CYCLES_SCENE [scenes/cornell-box.json]  a scene cycles_scene.py can translate
#   CYCLES_WIDTH [128]     film width (height keeps the aspect)
#   CYCLES_MIN_SPP [4], CYCLES_MAX_SPP [512]   the doubling series
#   CYCLES_REF_SPP [4096]  reference spp per renderer (two halves, seeds 1000 and 1001)
#   CYCLES_THREADS [2]     render threads of both renderers
#   CYCLES_REPS [3]        repetitions of the timed series (the pixels are the same each time)
#   CYCLES_CACHE           reference cache [${XDG_CACHE_HOME:-~/.cache}/tessera/cycles]
#   BLENDER [blender]      the Blender binary (Debian's blender package; `make bench` installs it)
# Without Blender the comparison is skipped with a message (exit 0).
set -eu

BUILD=${1:?usage: run.sh BUILD_DIR OUT_DIR}
OUT=${2:?usage: run.sh BUILD_DIR OUT_DIR}
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
case $BUILD in /*) ;; *) BUILD=$(pwd)/$BUILD ;; esac
case $OUT in /*) ;; *) OUT=$(pwd)/$OUT ;; esac
TESSERA=$BUILD/tessera
ERR=$BUILD/bench_image_error
for b in "$TESSERA" "$ERR"; do
  [ -x "$b" ] || { echo "bench: $b is missing; build first" >&2; exit 1; }
done
BLENDER=${BLENDER:-blender}
if ! command -v "$BLENDER" >/dev/null 2>&1; then
  echo "bench: no Blender ($BLENDER); Cycles comparison skipped (make bench-deps installs Debian's blender)" >&2
  exit 0
fi

command -v bc >/dev/null 2>&1 || { echo "bench: bc is needed (Debian's bc; make bench-deps installs it)" >&2; exit 1; }

SCENE=${CYCLES_SCENE:-$ROOT/scenes/cornell-box.json}
WIDTH=${CYCLES_WIDTH:-128}
MIN_SPP=${CYCLES_MIN_SPP:-4}
MAX_SPP=${CYCLES_MAX_SPP:-512}
REF_SPP=${CYCLES_REF_SPP:-4096}
THREADS=${CYCLES_THREADS:-2}
REPS=${CYCLES_REPS:-3}
CACHE=${CYCLES_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/tessera/cycles}
HALF=$((REF_SPP / 2))
WORK=$OUT/cycles
mkdir -p "$WORK" "$CACHE"

# blender_run LOG ARGS… — runs the translation script; its CYCLES_RESULT line goes to LOG.
blender_run() {
  log=$1
  shift
  if ! "$BLENDER" -b --factory-startup -noaudio --python-exit-code 1 -P "$HERE/cycles_scene.py" -- "$@" \
      > "$log" 2>&1; then
    echo "bench: Blender failed; last lines of $log:" >&2
    tail -n 15 "$log" >&2
    exit 1
  fi
}
cycles_seconds() { sed -n 's/^CYCLES_RESULT .*"seconds": \([0-9.e+-]*\).*/\1/p' "$1"; }
field() { tr ' ' '\n' | sed -n "s/^$1=//p"; } # field NAME < "k=v k=v …"
now() { date +%s.%N; }

# ---- 1. does an emitter of radiance L read L? (units, linear EXR, no view transform) ----
blender_run "$WORK/units.log" --check-units --out "$WORK/units.exr" --threads "$THREADS"
units=$("$ERR" "$WORK/units.exr" "$WORK/units.exr")
echo "$units" | awk '{
  for (i = 1; i <= NF; i++) { split($i, kv, "="); v[kv[1]] = kv[2] }
  if ((v["mean_x_R"] - 0.5)^2 + (v["mean_x_G"] - 0.25)^2 + (v["mean_x_B"] - 2)^2 > 1e-10) {
    printf "bench: Cycles units probe reads (%s, %s, %s), expected (0.5, 0.25, 2)\n", v["mean_x_R"], v["mean_x_G"], v["mean_x_B"] > "/dev/stderr"
    exit 1
  }
}'

# ---- 2. the scene both render: the film resized, written once ----
blender_run "$WORK/scene.log" --scene "$SCENE" --width "$WIDTH" --write-scene "$WORK/scene.json"
BLENDER_VERSION=$("$BLENDER" -b --factory-startup -noaudio --version 2>/dev/null | sed -n 's/^Blender \([0-9.]*\).*/\1/p' | head -n 1)
# Cache keys: the scene as rendered (+ the translation script for Cycles' references).
tkey=$(sha256sum < "$WORK/scene.json" | cut -c1-12)
ckey=$(cat "$WORK/scene.json" "$HERE/cycles_scene.py" | sha256sum | cut -c1-12)
TREF=$CACHE/tessera-$tkey-$HALF
CREF=$CACHE/cycles-$BLENDER_VERSION-$ckey-$HALF
echo "bench: tessera against Blender $BLENDER_VERSION Cycles, $(basename "$SCENE") at ${WIDTH}px, $THREADS threads," \
     "$MIN_SPP…$MAX_SPP spp, references 2×$HALF spp (cache $CACHE)" >&2

# ---- 3. references: each renderer's own, two halves with seeds 1000 and 1001 ----
for half in a b; do
  seed=1000; [ $half = a ] || seed=1001
  if [ ! -s "$TREF-$half.exr" ]; then
    echo "bench: rendering the tessera reference ($half, $HALF spp)" >&2
    "$TESSERA" render "$WORK/scene.json" --spp "$HALF" --seed "$seed" --threads "$THREADS" --quiet \
      -o "$TREF-$half.exr.tmp.exr"
    mv "$TREF-$half.exr.tmp.exr" "$TREF-$half.exr"
    t=$("$ERR" "$TREF-$half.exr" "$TREF-$half.exr" | field render_time_s)
    echo "tessera reference: $HALF spp, seed $seed, ${WIDTH}px, $t s render time, $(date -u +%Y-%m-%d)" > "$TREF-$half.txt"
  fi
  if [ ! -s "$CREF-$half.exr" ]; then
    echo "bench: rendering the Cycles reference ($half, $HALF spp)" >&2
    blender_run "$WORK/ref-$half.log" --scene "$WORK/scene.json" --spp "$HALF" --seed "$seed" \
      --threads "$THREADS" --out "$CREF-$half.tmp.exr"
    mv "$CREF-$half.tmp.exr" "$CREF-$half.exr"
    echo "Cycles reference: $HALF spp, seed $seed, ${WIDTH}px, $(cycles_seconds "$WORK/ref-$half.log") s render time," \
         "Blender $BLENDER_VERSION, $(date -u +%Y-%m-%d)" > "$CREF-$half.txt"
  fi
done
# How far apart are the two converged answers? (Cycles' reference against tessera's.)
AGREE=$("$ERR" "$CREF-a.exr" "$TREF-a.exr" "$TREF-b.exr")
AGREE_SELF=$("$ERR" "$CREF-a.exr" "$CREF-b.exr") # Cycles half against half: the noise level

# ---- 4. the series, side by side: at each spp both renderers, order alternating; REPS times ----
CSV=$OUT/cycles.csv
echo "renderer,rep,spp,seconds,process_s,rmse,rmse_raw,ref_rmse,relmse" > "$CSV.tmp"
# append_row RENDERER REP SPP SECONDS WALL < "bench_image_error output"
append_row() {
  awk -v r="$1" -v rep="$2" -v spp="$3" -v s="$4" -v wall="$5" '{
    for (i = 1; i <= NF; i++) { split($i, kv, "="); v[kv[1]] = kv[2] }
    printf "%s,%d,%d,%.6f,%.4f,%s,%s,%s,%s\n", r, rep, spp, s, wall, v["rmse"], v["rmse_raw"], v["ref_rmse"], v["relmse"]
  }' >> "$CSV.tmp"
}
run_tessera() { # REP SPP
  img=$WORK/tessera-$2.exr
  t0=$(now)
  "$TESSERA" render "$WORK/scene.json" --spp "$2" --seed 0 --threads "$THREADS" --quiet -o "$img"
  t1=$(now)
  line=$("$ERR" "$img" "$TREF-a.exr" "$TREF-b.exr")
  echo "$line" | append_row tessera "$1" "$2" "$(echo "$line" | field render_time_s)" "$(echo "$t1 - $t0" | bc -l)"
}
run_cycles() { # REP SPP
  img=$WORK/cycles-$2.exr
  t0=$(now)
  blender_run "$WORK/cycles-$2.log" --scene "$WORK/scene.json" --spp "$2" --seed 0 --threads "$THREADS" \
    --warmup --out "$img"
  t1=$(now)
  "$ERR" "$img" "$CREF-a.exr" "$CREF-b.exr" |
    append_row cycles "$1" "$2" "$(cycles_seconds "$WORK/cycles-$2.log")" "$(echo "$t1 - $t0" | bc -l)"
}
t_start=$(date +%s)
step=0
rep=1
while [ "$rep" -le "$REPS" ]; do
  spp=$MIN_SPP
  while [ "$spp" -le "$MAX_SPP" ]; do
    echo "bench: repetition $rep of $REPS, $spp spp" >&2
    if [ $((step % 2)) -eq 0 ]; then run_tessera "$rep" "$spp"; run_cycles "$rep" "$spp"
    else run_cycles "$rep" "$spp"; run_tessera "$rep" "$spp"; fi
    spp=$((spp * 2))
    step=$((step + 1))
  done
  rep=$((rep + 1))
done
mv "$CSV.tmp" "$CSV"
elapsed=$(( $(date +%s) - t_start ))

# ---- 5. summary: fits, time to equal RMSE, ratio ----
FILM_W=$(sed -n 's/.*"width": \([0-9]*\).*/\1/p' "$WORK/scene.json" | head -n 1)
FILM_H=$(sed -n 's/.*"height": \([0-9]*\).*/\1/p' "$WORK/scene.json" | head -n 1)
{
  echo "# tessera against Blender Cycles at equal RMSE"
  echo
  cpu=$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo 2>/dev/null | head -n 1)
  rev=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
  dirty=$(git -C "$ROOT" status --porcelain --untracked-files=no 2>/dev/null | head -n 1)
  echo "$(date -u +%Y-%m-%dT%H:%MZ), commit $rev${dirty:+ (+ local changes)}, Blender $BLENDER_VERSION, ${cpu:-unknown CPU}," \
       "$(nproc) CPUs, load average $(cut -d' ' -f1-3 /proc/loadavg) at the end; the series took ${elapsed} s."
  echo "Scene $(basename "$SCENE") at ${FILM_W}×${FILM_H} px, $THREADS threads each, $MIN_SPP…$MAX_SPP spp, $REPS repetitions;"
  echo "each renderer's RMSE is against its own reference (2×$HALF spp, reference noise subtracted)."
  echo "Time = the render call: tessera's own render time (sampling passes), Cycles' bpy.ops.render.render"
  echo "(sync, BVH, sampling, read-out) after a warm-up; per spp the fastest of the repetitions."
  echo
  echo "$AGREE" | awk -v self="$AGREE_SELF" '{
    for (i = 1; i <= NF; i++) { split($i, kv, "="); v[kv[1]] = kv[2] }
    n = split(self, s, " "); for (i = 1; i <= n; i++) { split(s[i], kv, "="); w[kv[1]] = kv[2] }
    printf "**Converged images agree:** Cycles ÷ tessera − 1 of the image means: R %+.2f%%, G %+.2f%%, B %+.2f%%; ", \
      100 * v["ratio_R"], 100 * v["ratio_G"], 100 * v["ratio_B"]
    printf "mean |Δ|/(ref + 0.01) %.4f per pixel and channel (Cycles half against half: %.4f, the noise level).\n", \
      v["mean_abs_rel"], w["mean_abs_rel"]
  }'
  echo
  awk -F, -v max_spp="$MAX_SPP" -v reps="$REPS" -v pixels=$((FILM_W * FILM_H)) '
    NR == 1 { next }
    {
      r = $1; q = $2
      if (!((r, $3) in idx)) { idx[r, $3] = ++n[r]; spp[r, n[r]] = $3; e[r, n[r]] = $6 }
      k = idx[r, $3]; tr[r, q, k] = $4
      if (!((r, k) in t) || $4 < t[r, k]) t[r, k] = $4   # fastest repetition
      if (!(r in seen)) { seen[r] = 1; order[++nr] = r }
    }
    function fit(r, mode,   i, x, y, sx, sy, sxx, sxy, m) {   # slope of log RMSE vs log spp (0) / log t (1)
      m = 0; sx = sy = sxx = sxy = 0
      for (i = 1; i <= n[r]; i++) {
        if (e[r, i] <= 0 || t[r, i] <= 0) continue
        x = log(mode ? t[r, i] : spp[r, i]); y = log(e[r, i])
        sx += x; sy += y; sxx += x * x; sxy += x * y; m++
      }
      return m > 1 ? (m * sxy - sx * sy) / (m * sxx - sx * sx) : 0
    }
    function lin(r,   i, sx, sy, sxx, sxy, m) {   # seconds = a + b·spp through the fastest times; returns b
      sx = sy = sxx = sxy = 0; m = n[r]
      for (i = 1; i <= m; i++) { sx += spp[r, i]; sy += t[r, i]; sxx += spp[r, i]^2; sxy += spp[r, i] * t[r, i] }
      return (m * sxy - sx * sy) / (m * sxx - sx * sx)
    }
    # Where the RMSE series crosses target: index i and fraction f between counts i and i+1 (log-log).
    function cross(r, target,   i) {
      for (i = 1; i < n[r]; i++)
        if (e[r, i] >= target && e[r, i + 1] <= target && e[r, i + 1] > 0) {
          CI = i; CF = log(target / e[r, i]) / log(e[r, i + 1] / e[r, i]); return 1
        }
      return 0
    }
    function interp(a, b) { return exp(log(a) + CF * (log(b) - log(a))) }
    function median(a, m,   i, j, x) {   # of a[1..m]
      for (i = 2; i <= m; i++) { x = a[i]; for (j = i - 1; j >= 1 && a[j] > x; j--) a[j + 1] = a[j]; a[j + 1] = x }
      return m % 2 ? a[(m + 1) / 2] : (a[m / 2] + a[m / 2 + 1]) / 2
    }
    END {
      print "| renderer | ms/spp (fit) | Msamples/s | s @ " spp["tessera", 1] " spp | s @ " max_spp " spp | RMSE @ " max_spp " spp | RMSE slope /spp | /time |"
      print "|---|--:|--:|--:|--:|--:|--:|--:|"
      for (j = 1; j <= nr; j++) {
        r = order[j]; b = lin(r)
        printf "| %s | %.3g | %.3g | %.3g | %.3g | %.3g | %.2f | %.2f |\n", r, 1000 * b, \
          (b > 0 ? pixels / b / 1e6 : 0), t[r, 1], t[r, n[r]], e[r, n[r]], fit(r, 0), fit(r, 1)
      }
      print ""
      # Targets: three RMSE levels inside the range both renderers measured (interpolation only).
      hi = 1e30; lo = 0
      for (j = 1; j <= nr; j++) { r = order[j]; if (e[r, 1] < hi) hi = e[r, 1]; if (e[r, n[r]] > lo) lo = e[r, n[r]] }
      print "| target RMSE | tessera spp | tessera s | Cycles spp | Cycles s | **tessera ÷ Cycles time** | per-repetition ratios: median (min–max) | spp ratio |"
      print "|--:|--:|--:|--:|--:|--:|--:|--:|"
      if (lo >= hi) { print "| (the two RMSE ranges do not overlap) | | | | | | | |"; exit }
      for (k = 0; k < 3; k++) {
        target = exp(log(hi) + (k + 0.5) / 3 * (log(lo) - log(hi)))
        if (!cross("tessera", target)) { printf "| %.3g | (not crossed monotonically) | | | | | | |\n", target; continue }
        it = CI; ft = CF
        st = interp(spp["tessera", it], spp["tessera", it + 1]); tt = interp(t["tessera", it], t["tessera", it + 1])
        if (!cross("cycles", target)) { printf "| %.3g | (not crossed monotonically) | | | | | | |\n", target; continue }
        ic = CI; fc = CF
        sc = interp(spp["cycles", ic], spp["cycles", ic + 1]); tc = interp(t["cycles", ic], t["cycles", ic + 1])
        m = 0; rmin = 1e30; rmax = 0
        for (q = 1; q <= reps; q++) {
          CF = ft; a = interp(tr["tessera", q, it], tr["tessera", q, it + 1])
          CF = fc; c = interp(tr["cycles", q, ic], tr["cycles", q, ic + 1])
          ratio[++m] = a / c; if (a / c < rmin) rmin = a / c; if (a / c > rmax) rmax = a / c
        }
        printf "| %.3g | %.0f | %.3g | %.0f | %.3g | **%.2f** | %.2f (%.2f–%.2f) | %.2f |\n", target, st, tt, sc, tc, \
          tt / tc, median(ratio, m), rmin, rmax, st / sc
      }
      print ""
      print "Target: tessera ÷ Cycles time ≤ 0.40. Raw rows: cycles.csv; bench/README.md explains the columns."
    }' "$CSV"
} > "$OUT/cycles.md"
cat "$OUT/cycles.md"
echo "bench: wrote $OUT/cycles.csv and $OUT/cycles.md" >&2
