#!/bin/sh
# bench/load/run.sh [--light] BUILD_DIR [OUT_DIR] — `tessera serve` under HTTP load while two
# jobs render (docs/design.md §8). `make bench` runs the full version through bench/run;
# ctest `load_light` runs --light, which also decides pass or fail.
#
# One server on loopback (port 0), then, with the same two jobs each time (the Cornell box
# with the path integrator and with the direct one, LOAD_SIZE² pixels, LOAD_SPP spp):
#   1. unloaded: submit both, wait until both are done;
#   2. loaded: submit both again and, until both are done, drive the server with
#      - wrk (Debian's HTTP load tool), LOAD_CONNS connections split evenly over four
#        closed-loop groups: job status, job list, /metrics, images and tiles (PNG and EXR);
#      - LOAD_SSE event-stream subscribers (curl -N), half on each job, each to `done`;
#      - a stream of bad requests (wrk, LOAD_BAD_CONNS connections, LOAD_BAD_DELAY_MS
#        between requests per connection; load.lua lists them);
#   3. (full version) unloaded again, so the baseline brackets the loaded run.
# Render throughput of a phase = the two jobs' samples ÷ the span from the first submission
# to the last job done, as the server reports them (created_at + queued_s + elapsed_s); the
# ratio loaded ÷ unloaded is taken within this run. Loopback only; bounded: the load stops
# when both jobs are done or after LOAD_MAX_SECONDS, every client has a time limit.
#
# Checks (exit 1 when one fails; the report is written first): no 5xx anywhere (wrk, the
# server's own /metrics counters), no failed connections (wrk connect/read/write/timeout
# errors = 0), every good request answered 2xx and every bad one 4xx, every subscriber saw
# `done`, both jobs done with all their samples in every phase and their EXRs bit-identical
# to `tessera render` of the same documents, the server still healthy at the end and shutting
# down on SIGTERM with status 0 within 10 s.
# Writes OUT_DIR/load.md (report), load.csv (one row per load group) and load_summary.csv.
# Exit 77 (skipped) in --light mode when wrk or curl is missing (`make deps` installs them).
set -eu

LIGHT=0
if [ "${1:-}" = --light ]; then LIGHT=1; shift; fi
[ $# -ge 1 ] || { echo "usage: bench/load/run.sh [--light] BUILD_DIR [OUT_DIR]" >&2; exit 2; }
BUILD=$1
case $BUILD in /*) ;; *) BUILD=$(pwd)/$BUILD ;; esac
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
if [ $LIGHT = 1 ]; then
  OUT=${2:-$BUILD/test-artifacts/load}
  CONNS=${LOAD_CONNS:-40} SSE=${LOAD_SSE:-10} BAD_CONNS=${LOAD_BAD_CONNS:-2} SIZE=${LOAD_SIZE:-96}
  SPP=${LOAD_SPP:-32} MAX_SECONDS=${LOAD_MAX_SECONDS:-20} AFTER=${LOAD_AFTER:-0}
else
  OUT=${2:-$BUILD/bench}
  CONNS=${LOAD_CONNS:-200} SSE=${LOAD_SSE:-50} BAD_CONNS=${LOAD_BAD_CONNS:-4} SIZE=${LOAD_SIZE:-192}
  SPP=${LOAD_SPP:-64} MAX_SECONDS=${LOAD_MAX_SECONDS:-120} AFTER=${LOAD_AFTER:-1}
fi
BAD_DELAY_MS=${LOAD_BAD_DELAY_MS:-20} THREADS=${LOAD_THREADS:-$(nproc)}
MAX_BODY=262144 # the server's --max-body here, so an oversized request costs 256 KiB, not 16 MiB
GOOD="status list metrics image"
PER_GROUP=$((CONNS / 4))
[ "$PER_GROUP" -ge 1 ] || { echo "bench load: LOAD_CONNS must be at least 4" >&2; exit 2; }

for tool in wrk curl; do
  command -v $tool >/dev/null && continue
  if [ $LIGHT = 1 ]; then
    echo "SKIPPED: the load test needs $tool (Debian package $tool; make deps installs it)" >&2
    exit 77
  fi
  echo "bench load: $tool is missing (Debian package $tool; make deps installs it)" >&2
  exit 1
done
for f in "$BUILD/tessera" "$BUILD/bench_exr_compare"; do
  [ -x "$f" ] || { echo "bench load: $f is missing; build first" >&2; exit 1; }
done
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)

work=$(mktemp -d "${TMPDIR:-/tmp}/ts_load_XXXXXX")
server='' pids=''
cleanup() {
  for p in $pids; do kill "$p" 2>/dev/null || true; done
  [ -n "$server" ] && kill "$server" 2>/dev/null
  wait 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT
trap 'exit 130' INT TERM
cd "$work" # nothing stray lands in the caller's folder

log() { echo "bench load: $*" >&2; }
now() { date +%s.%N; }
failures=0
check() { # check CONDITION_TEXT OK(0|1): record a pass/fail line for the report
  if [ "$2" = 1 ]; then echo "- pass: $1" >> "$work/checks"
  else echo "- **FAIL**: $1" >> "$work/checks"; failures=$((failures + 1)); log "FAIL: $1"; fi
}
: > "$work/checks"

# ---- the two jobs, and what `tessera render` makes of them ----
for s in cornell-box cornell-box-direct; do
  sed -e "s/\"width\": 512/\"width\": $SIZE/; s/\"height\": 512/\"height\": $SIZE/; s/\"spp\": 64/\"spp\": $SPP/" \
    "$ROOT/scenes/$s.json" > "$work/$s.json"
  if ! grep -q "\"width\": $SIZE" "$work/$s.json" || ! grep -q "\"spp\": $SPP" "$work/$s.json"; then
    log "could not resize scenes/$s.json"; exit 1
  fi
  "$BUILD/tessera" render "$work/$s.json" --threads "$THREADS" -o "$work/$s.cli.exr" --quiet
done
log "CLI references rendered (${SIZE}², $SPP spp)"

# ---- the server ----
: > "$work/server.log" # exists before the background job opens it, for the polling below
"$BUILD/tessera" serve --bind 127.0.0.1 --port 0 --threads "$THREADS" --max-body $MAX_BODY \
  > "$work/server.log" 2>&1 &
server=$!
i=0
port=
while [ -z "$port" ]; do
  port=$(sed -n 's|.*listening on http://127\.0\.0\.1:\([0-9]*\)/.*|\1|p' "$work/server.log")
  i=$((i + 1))
  if [ $i -ge 100 ] || ! kill -0 "$server" 2>/dev/null; then
    log "the server did not start"; cat "$work/server.log" >&2; exit 1
  fi
  [ -n "$port" ] || sleep 0.1
done
URL=http://127.0.0.1:$port

json_field() { # json_field FILE NAME: the first top-level scalar NAME in a one-line JSON document
  sed -n "s/.*\"$2\":\"\{0,1\}\([^,\"}]*\).*/\1/p" "$1" | head -n 1
}

submit() { # submit SCENE: prints the new job's id
  curl -sS --max-time 30 -X POST -H 'Content-Type: application/json' --data-binary @"$work/$1.json" \
    "$URL/api/v1/jobs" > "$work/post.json"
  id=$(json_field "$work/post.json" id)
  [ -n "$id" ] || { log "submitting $1 failed: $(cat "$work/post.json")"; exit 1; }
  echo "$id"
}

metric_sum() { # metric_sum FILE REGEX: sum of the http request counters whose labels match
  awk -v re="$2" '/^tessera_http_requests_total/ && $0 ~ re {s += $NF} END {printf "%d\n", s}' "$1"
}

# finish_phase NAME ID_A ID_B SERVER_CPU_S: checks both jobs are done with all their samples
# and images equal to the CLI's; appends "NAME span_s samples server_cpu_s" to $work/phases.
finish_phase() {
  name=$1 phase_cpu=$4
  first='' last='' samples=0
  for pair in "cornell-box $2" "cornell-box-direct $3"; do
    # shellcheck disable=SC2086 # two words: scene and id
    set -- $pair
    curl -sS --max-time 30 "$URL/api/v1/jobs/$2" > "$work/status.json" || true
    state=$(json_field "$work/status.json" state) spp=$(json_field "$work/status.json" spp_done)
    check "$name: job $1 ($2) is done with $SPP spp (state $state, $spp spp)" \
      "$([ "$state" = "done" ] && [ "$spp" = "$SPP" ] && echo 1 || echo 0)"
    curl -sS --max-time 60 -o "$work/$1.$name.exr" "$URL/api/v1/jobs/$2/image.exr" || true
    if "$BUILD/bench_exr_compare" "$work/$1.cli.exr" "$work/$1.$name.exr" > "$work/cmp.txt" 2>&1; then ok=1; else ok=0; fi
    check "$name: job $1's EXR equals tessera render's ($(cat "$work/cmp.txt"))" $ok
    c=$(json_field "$work/status.json" created_at) q=$(json_field "$work/status.json" queued_s)
    e=$(json_field "$work/status.json" elapsed_s) n=$(json_field "$work/status.json" samples)
    end=$(awk -v c="$c" -v q="$q" -v e="$e" 'BEGIN {printf "%.6f", c + q + e}')
    first=$(awk -v a="${first:-$c}" -v b="$c" 'BEGIN {printf "%.6f", (a < b) ? a : b}')
    last=$(awk -v a="${last:-$end}" -v b="$end" 'BEGIN {printf "%.6f", (a > b) ? a : b}')
    samples=$(awk -v a="$samples" -v b="$n" 'BEGIN {printf "%.0f", a + b}')
  done
  span=$(awk -v a="$first" -v b="$last" 'BEGIN {printf "%.3f", b - a}')
  echo "$name $span $samples $phase_cpu" >> "$work/phases"
  log "$name: both jobs done in $span s ($samples samples)"
}

wait_done() { # wait_done ID: follows the job's event stream to `done` (bounded)
  curl -sS -N --max-time $((MAX_SECONDS + 60)) "$URL/api/v1/jobs/$1/events" > "$work/watch.$1" 2>&1 || true
}

HZ=$(getconf CLK_TCK)
cpu_s() { # cpu_s PID...: CPU seconds (user + system) the processes have used so far
  for p in "$@"; do cat "/proc/$p/stat" 2>/dev/null || true; done |
    awk -v hz="$HZ" '{t += $14 + $15} END {printf "%.2f\n", t / hz}'
}
minus() { awk -v a="$1" -v b="$2" 'BEGIN {printf "%.2f", a - b}'; }

unloaded_phase() {
  cpu0=$(cpu_s "$server")
  a=$(submit cornell-box) b=$(submit cornell-box-direct)
  wait_done "$a"
  wait_done "$b"
  finish_phase "$1" "$a" "$b" "$(minus "$(cpu_s "$server")" "$cpu0")"
}

: > "$work/phases"
unloaded_phase unloaded

# ---- under load ----
curl -sS --max-time 30 "$URL/metrics" > "$work/metrics.before"
cpu0=$(cpu_s "$server")
a=$(submit cornell-box) b=$(submit cornell-box-direct)
load_t0=$(now)
s=0 sse_pids=''
while [ $s -lt "$SSE" ]; do
  if [ $((s % 2)) = 0 ]; then id=$a; else id=$b; fi
  curl -sS -N --max-time $((MAX_SECONDS + 60)) -o "$work/sse.$s" "$URL/api/v1/jobs/$id/events" 2> "$work/sse.$s.err" &
  sse_pids="$sse_pids $!"
  s=$((s + 1))
done
pids="$sse_pids"
tiles_x=$(json_field "$work/post.json" tiles_x) tiles_y=$(json_field "$work/post.json" tiles_y)
wrk_pids=
for g in $GOOD bad; do
  if [ "$g" = bad ]; then c=$BAD_CONNS d=$BAD_DELAY_MS; else c=$PER_GROUP d=0; fi
  wrk -t1 -c"$c" -d"${MAX_SECONDS}s" --timeout 10s -s "$ROOT/bench/load/load.lua" "$URL/" -- \
    "$g" "$work/wrk.$g" "$a" "$b" "$tiles_x" "$tiles_y" $MAX_BODY "$d" > "$work/wrk.$g.log" 2>&1 &
  wrk_pids="$wrk_pids $!"
done
pids="$pids $wrk_pids"
log "loaded: $CONNS connections (status, list, metrics, image: $PER_GROUP each), $SSE subscribers," \
    "$BAD_CONNS bad-request connections; until both jobs are done (at most $MAX_SECONDS s)"
s=0
for p in $sse_pids; do # each subscriber's exit status, in order
  if wait "$p"; then echo 0; else echo $?; fi > "$work/sse.$s.rc"
  s=$((s + 1))
done
load_t1=$(now)
cpu1=$(cpu_s "$server")
# shellcheck disable=SC2086 # one PID per word
wrk_cpu=$(cpu_s $wrk_pids)
for p in $wrk_pids; do kill -INT "$p" 2>/dev/null || true; done
for p in $wrk_pids; do wait "$p" || true; done
pids=
curl -sS --max-time 30 "$URL/metrics" > "$work/metrics.after" || true
finish_phase loaded "$a" "$b" "$(minus "$cpu1" "$cpu0")"
load_s=$(awk -v a="$load_t0" -v b="$load_t1" 'BEGIN {printf "%.1f", b - a}')
[ "$(awk -v s="$load_s" -v m="$MAX_SECONDS" 'BEGIN {print ((s < m) ? 1 : 0)}')" = 1 ] ||
  log "warning: the load stopped (after $MAX_SECONDS s) before the jobs were done; the ratio understates the loss"

if [ "$AFTER" = 1 ] && kill -0 "$server" 2>/dev/null; then unloaded_phase unloaded-after; fi

# ---- the server afterwards ----
code=$(curl -s -o /dev/null -w '%{http_code}' --max-time 10 "$URL/healthz" || true)
check "the server is alive and answers /healthz with 200 after the load (got $code)" \
  "$([ "$code" = 200 ] && kill -0 "$server" 2>/dev/null && echo 1 || echo 0)"
rss_mib=$(awk '/^VmHWM/ {printf "%.0f", $2 / 1024}' "/proc/$server/status" 2>/dev/null || echo "?")
# A clean shutdown within 10 s (a hang or, under ASan, a leak shows here as a failure).
kill "$server" 2>/dev/null || true
( sleep 10 && kill -KILL "$server" ) < /dev/null > /dev/null 2>&1 &
watchdog=$!
if wait "$server"; then code=0; else code=$?; fi
kill "$watchdog" 2>/dev/null || true
server=''
check "the server shut down on SIGTERM within 10 s with exit status 0 (got $code; 137: killed)" \
  "$([ "$code" = 0 ] && echo 1 || echo 0)"

# ---- the numbers ----
val() { tr ' ' '\n' < "$1" | sed -n "s/^$2=//p"; }
ms() { awk -v us="$1" 'BEGIN {printf "%.2f", us / 1e3}'; }
echo "group,connections,requests,duration_s,requests_per_s,p50_ms,p90_ms,p99_ms,max_ms,non_2xx,c2xx,c4xx,c5xx,connect_errors,read_errors,write_errors,timeouts" \
  > "$OUT/load.csv"
: > "$work/hist.all"
: > "$work/rows.md"
all_conns=0 all_req=0 all_rate=0 all_non2xx=0 all_sock=0 all_max=0
for g in $GOOD bad; do
  f=$work/wrk.$g
  if [ ! -s "$f" ]; then
    check "wrk group $g reported its results ($(tail -n 3 "$f.log" 2>/dev/null | tr '\n' ' '))" 0
    continue
  fi
  if [ "$g" = bad ]; then c=$BAD_CONNS; else c=$PER_GROUP; cat "$f.hist" >> "$work/hist.all"; fi
  req=$(val "$f" requests) dur=$(val "$f" duration_us) non2xx=$(val "$f" non2xx)
  c2=$(val "$f" c2xx) c4=$(val "$f" c4xx) c5=$(val "$f" c5xx)
  ec=$(val "$f" connect) er=$(val "$f" read) ew=$(val "$f" write) et=$(val "$f" timeout)
  rate=$(awk -v n="$req" -v d="$dur" 'BEGIN {printf "%.1f", (d > 0) ? n / (d / 1e6) : 0}')
  p50=$(ms "$(val "$f" p50_us)") p90=$(ms "$(val "$f" p90_us)") p99=$(ms "$(val "$f" p99_us)") mx=$(ms "$(val "$f" max_us)")
  if [ "$g" != bad ]; then
    # wrk counts answers outside 2xx/3xx; the good groups expect 200 only (the server's
    # split by status is below, from /metrics).
    c2=$((req - non2xx)) c4=- c5=-
    all_conns=$((all_conns + c)) all_req=$((all_req + req)) all_non2xx=$((all_non2xx + non2xx))
    all_sock=$((all_sock + ec + er + ew + et))
    all_rate=$(awk -v a="$all_rate" -v b="$rate" 'BEGIN {printf "%.1f", a + b}')
    all_max=$(awk -v a="$all_max" -v b="$mx" 'BEGIN {print ((b > a) ? b : a)}')
  fi
  echo "$g,$c,$req,$(awk -v d="$dur" 'BEGIN {printf "%.2f", d / 1e6}'),$rate,$p50,$p90,$p99,$mx,$non2xx,$c2,$c4,$c5,$ec,$er,$ew,$et" \
    >> "$OUT/load.csv"
  if [ "$g" = bad ]; then label="bad requests ($BAD_DELAY_MS ms apart per connection)"; else label=$g; fi
  echo "| $label | $c | $req | $rate | $p50 | $p90 | $p99 | $mx | $c2 | $([ "$g" = bad ] && echo "$c4 | $c5" || echo "$non2xx non-2xx |") | $ec/$er/$ew/$et |" \
    >> "$work/rows.md"
  check "$g: no failed connections (connect $ec, read $er, write $ew, timeout $et)" \
    "$([ "$ec" = 0 ] && [ "$er" = 0 ] && [ "$ew" = 0 ] && [ "$et" = 0 ] && echo 1 || echo 0)"
  if [ "$g" = bad ]; then
    check "bad requests: every answer a 4xx ($c4 of $req; 2xx $c2, 5xx $c5)" \
      "$([ "$c4" = "$req" ] && [ "$c5" = 0 ] && [ "$req" -gt 0 ] && echo 1 || echo 0)"
  else
    check "$g: every answer a 2xx ($c2 of $req)" "$([ "$non2xx" = 0 ] && [ "$req" -gt 0 ] && echo 1 || echo 0)"
  fi
done
# The four good groups together: their latency histograms merged, their rates summed.
pcts=$(sort -n "$work/hist.all" | awk '
  {v[NR] = $1; c[NR] = $2; n += $2}
  END {
    p[1] = 0.5; p[2] = 0.9; p[3] = 0.99; k = 1
    for (i = 1; i <= NR && k <= 3; i++) { cum += c[i]; while (k <= 3 && cum >= p[k] * n) q[k++] = v[i] }
    printf "%.2f %.2f %.2f\n", q[1] / 1e3, q[2] / 1e3, q[3] / 1e3
  }')
# shellcheck disable=SC2086 # split into fields
set -- $pcts
all_p50=$1 all_p90=$2 all_p99=$3
echo "all good groups,$all_conns,$all_req,,$all_rate,$all_p50,$all_p90,$all_p99,$all_max,$all_non2xx,$((all_req - all_non2xx)),-,-,,,,," \
  >> "$OUT/load.csv"
echo "| **all good groups** | $all_conns | $all_req | $all_rate | $all_p50 | $all_p90 | $all_p99 | $all_max | $((all_req - all_non2xx)) | $all_non2xx non-2xx | | $all_sock in all |" \
  >> "$work/rows.md"

# Server-side: answers by status during the load window (its /metrics counters).
srv_delta() { # srv_delta CLASS_DIGIT: answers of that class between the two /metrics readings
  echo $(($(metric_sum "$work/metrics.after" "status=\"$1") - $(metric_sum "$work/metrics.before" "status=\"$1")))
}
srv2=$(srv_delta 2) srv4=$(srv_delta 4) srv5=$(srv_delta 5)
check "server's own counters: no 5xx during the load ($srv5; 2xx $srv2, 4xx $srv4)" "$([ "$srv5" = 0 ] && echo 1 || echo 0)"

# Subscribers: each must end with exit 0 after a `done` event.
sse_ok=0 tiles_min='' tiles_max=0
s=0
while [ $s -lt "$SSE" ]; do
  rc=$(cat "$work/sse.$s.rc" 2>/dev/null || echo none)
  if [ "$rc" = 0 ] && grep -q '^event: done' "$work/sse.$s"; then sse_ok=$((sse_ok + 1)); fi
  t=$(grep -c '^event: tile' "$work/sse.$s" 2>/dev/null || true)
  [ -z "$tiles_min" ] || [ "$t" -lt "$tiles_min" ] && tiles_min=$t
  [ "$t" -gt "$tiles_max" ] && tiles_max=$t
  s=$((s + 1))
done
check "event streams: $sse_ok of $SSE subscribers saw \`done\` and ended cleanly" "$([ "$sse_ok" = "$SSE" ] && echo 1 || echo 0)"

# Render throughput: unloaded span (mean of the unloaded phases) ÷ loaded span.
render=$(awk '$1 == "loaded" {l = $2; n = $3} $1 != "loaded" {u += $2; k++}
  END {if (k == 0 || l <= 0 || u <= 0) {print "0 0 0 0 100"; exit}
       printf "%.3f %.3f %d %.3f %.1f\n", u / k, l, k, (u / k) / l, 100 * (1 - (u / k) / l)}' "$work/phases")
# shellcheck disable=SC2086 # split into fields
set -- $render
span_u=$1 span_l=$2 n_u=$3 ratio=$4 lost=$5
# The CPU the HTTP side cost: the loaded phase's server CPU minus what its samples cost to
# render at the unloaded phases' CPU per sample (an estimate: it assumes rendering costs the
# same CPU per sample under load; cache pressure makes it cost more, so this is an upper
# bound). Unlike the throughput ratio it does not depend on what else the machine runs.
all_answers=$((all_req + $(awk -F, '$1 == "bad" {print $3}' "$OUT/load.csv") + SSE))
http_cpu=$(awk -v n="$all_answers" '$1 == "loaded" {l = $4; ls = $3} $1 != "loaded" {u += $4; us += $3}
  END {h = (us > 0) ? l - ls * u / us : 0; if (h < 0) h = 0; printf "%.2f %.0f\n", h, (n > 0) ? 1e6 * h / n : 0}' "$work/phases")
# shellcheck disable=SC2086 # split into fields
set -- $http_cpu
http_cpu_s=$1 http_cpu_us=$2

{
  echo "phase,span_s,samples,samples_per_s,server_cpu_s"
  awk '{printf "%s,%.3f,%d,%.0f,%.2f\n", $1, $2, $3, ($2 > 0) ? $3 / $2 : 0, $4}' "$work/phases"
} > "$OUT/load_render.csv"
{
  echo "mode,connections,sse,bad_connections,requests_per_s,p50_ms,p99_ms,socket_errors,client_non2xx_good,bad_4xx,bad_5xx,server_5xx,unloaded_span_s,loaded_span_s,throughput_ratio,throughput_lost_pct,checks_failed,http_cpu_s,http_cpu_us_per_answer"
  bad4=$(awk -F, '$1 == "bad" {print $12}' "$OUT/load.csv") bad5=$(awk -F, '$1 == "bad" {print $13}' "$OUT/load.csv")
  echo "$([ $LIGHT = 1 ] && echo light || echo full),$CONNS,$SSE,$BAD_CONNS,$all_rate,$all_p50,$all_p99,$all_sock,$all_non2xx,${bad4:-},${bad5:-},$srv5,$span_u,$span_l,$ratio,$lost,$failures,$http_cpu_s,$http_cpu_us"
} > "$OUT/load_summary.csv"

{
  echo "# Load: tessera serve under HTTP load while two jobs render"
  echo
  cpu=$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo 2>/dev/null | head -n 1)
  rev=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
  dirty=$(git -C "$ROOT" status --porcelain --untracked-files=no 2>/dev/null | head -n 1)
  echo "$(date -u +%Y-%m-%dT%H:%MZ), commit $rev${dirty:+ (+ local changes)}, ${cpu:-unknown CPU}, $(nproc) CPUs," \
       "load average $(cut -d' ' -f1-3 /proc/loadavg) at the end; $([ $LIGHT = 1 ] && echo "light version (make test)" || echo "full version")."
  echo "Jobs: the Cornell box (path) and the Cornell box (direct), ${SIZE}×${SIZE}, $SPP spp; server with" \
       "$THREADS render threads, wrk and curl on the same machine. Load for $load_s s (until both jobs were done)."
  echo
  echo "| load group | connections | requests | req/s | p50 ms | p90 ms | p99 ms | max ms | 2xx | 4xx | 5xx | socket errors connect/read/write/timeout |"
  echo "|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|"
  cat "$work/rows.md"
  echo
  echo "Latencies are wrk's (first byte sent → whole answer read), per group; \"all\" merges the four good"
  echo "groups' histograms. In the good groups wrk counts answers outside 2xx/3xx (\"non-2xx\"); the bad"
  echo "group counts every class itself."
  echo
  echo "Server's own count of answers during the load (/metrics): 2xx $srv2, 4xx $srv4, 5xx $srv5."
  echo "Event streams: $sse_ok of $SSE subscribers got \`done\`; tile events per subscriber $tiles_min–$tiles_max."
  echo "Server peak resident memory: $rss_mib MiB."
  echo
  echo "| render phase | both jobs, submission → last done | samples/s | server CPU time | server CPU ÷ ($(nproc) CPUs × span) |"
  echo "|---|--:|--:|--:|--:|"
  awk -v ncpu="$(nproc)" '{printf "| %s | %.2f s | %.3g M | %.1f s | %.2f |\n", $1, $2, ($2 > 0) ? $3 / $2 / 1e6 : 0, $4, ($2 > 0) ? $4 / (ncpu * $2) : 0}' "$work/phases"
  echo
  echo "The load generators (wrk) used $wrk_cpu s of CPU during the loaded phase. In the unloaded phases"
  echo "all the server's CPU time is rendering; a share below 1 there means other processes had the CPUs."
  echo "Estimated server CPU spent on HTTP during the loaded phase: $http_cpu_s s, about $http_cpu_us µs per answer"
  echo "($all_answers answers; the loaded phase's server CPU less its samples at the unloaded CPU cost per sample)."
  echo
  echo "**Render throughput under load ÷ without: $ratio** (throughput lost: $lost %; unloaded = mean of $n_u phase(s))."
  echo
  echo "Checks:"
  echo
  cat "$work/checks"
} > "$OUT/load.md"
cat "$OUT/load.md"
log "wrote $OUT/load.md, load.csv, load_render.csv, load_summary.csv"
[ $failures = 0 ] || { log "$failures check(s) failed; server log: $(tail -n 5 "$work/server.log" | tr '\n' ' ')"; exit 1; }
