#!/bin/sh
# bench/http.sh BUILD_DIR OUT_DIR — time from job submission to the first tile on screen, and
# the same job through HTTP against the CLI, as a ratio (docs/design.md §8).
#
# Starts `tessera serve` on loopback, then REPS times (alternating which goes first):
#   - HTTP: POST the Cornell box (BENCH_HTTP_SIZE² pixels, BENCH_HTTP_SPP spp), open its event
#     stream at once and note when the first `tile` event and the `done` event arrive;
#   - CLI: `tessera render` of the same document with the same spp and threads.
# Reports medians and the median of per-repetition ratios HTTP ÷ CLI into OUT_DIR/http.md.
# Needs curl (installed from Debian here if missing). Loopback only; bounded in count and time.
set -eu
BUILD=$1 OUT=$2
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SIZE=${BENCH_HTTP_SIZE:-256} SPP=${BENCH_HTTP_SPP:-16} REPS=${BENCH_HTTP_REPS:-5}
PORT=${BENCH_HTTP_PORT:-18480} THREADS=${BENCH_HTTP_THREADS:-$(nproc)}
command -v curl >/dev/null || { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq curl >/dev/null; }
work=$(mktemp -d "${TMPDIR:-/tmp}/ts_bench_http_XXXXXX")
server=
cleanup() { [ -n "$server" ] && kill "$server" 2>/dev/null; rm -rf "$work"; }
trap cleanup EXIT INT TERM

# The Cornell box at SIZE² with SPP spp (the scene file's own settings otherwise).
sed -e "s/\"width\": 512/\"width\": $SIZE/; s/\"height\": 512/\"height\": $SIZE/; s/\"spp\": 64/\"spp\": $SPP/" \
  "$ROOT/scenes/cornell-box.json" > "$work/scene.json"
grep -q "\"width\": $SIZE" "$work/scene.json" || { echo "bench http: could not resize the scene" >&2; exit 1; }

"$BUILD/tessera" serve --bind 127.0.0.1 --port "$PORT" --threads "$THREADS" > "$work/server.log" 2>&1 &
server=$!
i=0
until curl -sf "http://127.0.0.1:$PORT/healthz" >/dev/null; do
  i=$((i + 1)); [ $i -lt 100 ] || { echo "bench http: server did not start" >&2; cat "$work/server.log" >&2; exit 1; }
  sleep 0.1
done

now() { date +%s.%N; }
http_run() {
  t0=$(now)
  id=$(curl -sf -X POST -H "Content-Type: application/json" --data-binary @"$work/scene.json" "http://127.0.0.1:$PORT/api/v1/jobs" |
       sed -n 's/^{"id":"\([0-9a-f]*\)".*/\1/p')
  [ -n "$id" ] || { echo "bench http: submission failed" >&2; exit 1; }
  # Read the event stream until `done`, stamping the first tile; at most 10 minutes.
  curl -sN --max-time 600 "http://127.0.0.1:$PORT/api/v1/jobs/$id/events" | while IFS= read -r line; do
    case $line in
      "event: tile"*) [ -f "$work/first" ] || now > "$work/first" ;;
      "event: done"*) now > "$work/done"; break ;;
    esac
  done
  first=$(cat "$work/first") done_t=$(cat "$work/done")
  rm -f "$work/first" "$work/done"
  echo "$(echo "$first - $t0" | bc -l) $(echo "$done_t - $t0" | bc -l)"
}
cli_run() {
  t0=$(now)
  "$BUILD/tessera" render "$work/scene.json" --spp "$SPP" --threads "$THREADS" -o "$work/cli.exr" --quiet
  echo "$(now) - $t0" | bc -l
}
command -v bc >/dev/null || { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq bc >/dev/null; }

: > "$work/rows"
r=0
while [ $r -lt "$REPS" ]; do
  if [ $((r % 2)) -eq 0 ]; then h=$(http_run); c=$(cli_run); else c=$(cli_run); h=$(http_run); fi
  set -- $h
  echo "$1 $2 $c $(echo "$2 / $c" | bc -l)" >> "$work/rows"
  r=$((r + 1))
done
median() { sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }
first=$(cut -d' ' -f1 "$work/rows" | median)
http=$(cut -d' ' -f2 "$work/rows" | median)
cli=$(cut -d' ' -f3 "$work/rows" | median)
ratio=$(cut -d' ' -f4 "$work/rows" | median)
{
  echo "# HTTP against the CLI"
  echo
  echo "Cornell box ${SIZE}×${SIZE}, $SPP spp, $THREADS threads, median of $REPS alternating repetitions;"
  echo "load average $(cut -d' ' -f1-3 /proc/loadavg) at the end."
  echo
  echo "| submission → first tile event | HTTP job, submission → done | CLI render (process start → exit) | HTTP ÷ CLI |"
  echo "|--:|--:|--:|--:|"
  printf '| %.3f s | %.3f s | %.3f s | %.3f |\n' "$first" "$http" "$cli" "$ratio"
} > "$OUT/http.md"
cat "$OUT/http.md"
