#!/bin/sh
# bench/accuracy/run.sh BUILD_DIR OUT_DIR — accuracy against time (docs/design.md §8): runs
# bench_accuracy on the benchmark scenes, then plots and tabulates (bench/README.md).
#
# Writes into OUT_DIR:
#   accuracy.csv            relMSE and RMSE per scene × configuration × spp, with wall time
#   accuracy_summary.csv    slopes, time to 1% and 0.1% relMSE, ratios to `base`
#   accuracy.md             the summary as markdown tables
#   accuracy-SCENE.png/.svg relMSE against seconds and against spp, one line per configuration
#
# Environment (defaults in brackets):
#   ACCURACY_WIDTH [96]      film width in pixels (height keeps the scene's aspect)
#   ACCURACY_MAX_SPP [128]    last sample count of the doubling series 1, 2, 4, …
#   ACCURACY_REF_SPP [1024]  reference spp (two halves; cached)
#   ACCURACY_THREADS [all]   render threads
#   ACCURACY_SCENES          scene files [scenes/{cornell-box,cornell-box-direct,veach-mis,glass-caustic,environment}.json]
#   ACCURACY_CONFIGS         comma-separated subset of bench_accuracy's configurations [all]
#   ACCURACY_CACHE           reference cache [${XDG_CACHE_HOME:-~/.cache}/tessera/accuracy]
# gnuplot (Debian's gnuplot-nox) is installed when missing; without it the plots are skipped.
set -eu

BUILD=${1:?usage: run.sh BUILD_DIR OUT_DIR}
OUT=${2:?usage: run.sh BUILD_DIR OUT_DIR}
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
mkdir -p "$OUT"
BIN=$BUILD/bench_accuracy
[ -x "$BIN" ] || { echo "bench: $BIN is missing; build first" >&2; exit 1; }

WIDTH=${ACCURACY_WIDTH:-96}
MAX_SPP=${ACCURACY_MAX_SPP:-128}
REF_SPP=${ACCURACY_REF_SPP:-1024}
THREADS=${ACCURACY_THREADS:-$(nproc)}
CACHE=${ACCURACY_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/tessera/accuracy}
SCENES=${ACCURACY_SCENES:-}
if [ -z "$SCENES" ]; then
  for s in cornell-box cornell-box-direct veach-mis glass-caustic environment; do
    SCENES="$SCENES $ROOT/scenes/$s.json"
  done
fi

if ! command -v gnuplot >/dev/null 2>&1; then
  echo "bench: installing gnuplot-nox from Debian for the accuracy plots" >&2
  SUDO=; [ "$(id -u)" = 0 ] || SUDO=sudo
  { $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends gnuplot-nox; } >/dev/null 2>&1 ||
    echo "bench: could not install gnuplot; accuracy plots skipped" >&2
fi

echo "bench: accuracy against time, ${WIDTH}px wide, 1…$MAX_SPP spp, references $REF_SPP spp (cache $CACHE)" >&2
t0=$(date +%s)
# shellcheck disable=SC2086 # SCENES is a list
"$BIN" --header --width "$WIDTH" --max-spp "$MAX_SPP" --ref-spp "$REF_SPP" --threads "$THREADS" \
  --cache "$CACHE" ${ACCURACY_CONFIGS:+--configs "$ACCURACY_CONFIGS"} \
  --summary "$OUT/accuracy_summary.csv.tmp" $SCENES > "$OUT/accuracy.csv.tmp"
mv "$OUT/accuracy.csv.tmp" "$OUT/accuracy.csv"
mv "$OUT/accuracy_summary.csv.tmp" "$OUT/accuracy_summary.csv"
elapsed=$(( $(date +%s) - t0 ))

"$(dirname "$0")/report.sh" "$OUT" "$elapsed"
