#!/usr/bin/env bash
# bench/hostile/run.sh BUILD_DIR [OUT_DIR] — issue 27's hostile-client run against one
# `tessera serve` on loopback (port 0): "no request can hang the server".
#
# While /healthz is polled HOSTILE_POLLS times (every 10 ms), these arrive at once:
#   mix-chain.json ×2      a 39-level self-mix material chain (2 KB)          400, ≤ 1 s
#   tex-chain.json         a 30-level self-mix texture chain                  400, ≤ 1 s
#   mix-chain.pbrt ×2      the material chain as a bundle's scene.pbrt        400, ≤ 1 s
#   png-bomb.tgz           a 40 KB PNG whose header says 16384² in a bundle   413, ≤ 1 s
#   gzip-bomb.tgz          a bundle expanding past --max-bundle-expanded      413, ≤ 5 s
#   subdiv.json ×3         200 bytes that take seconds to load (2 M triangles) 422,
#                          ≤ --max-load-seconds + 5 s (the loaders' bound)
#   (any of these may instead be 503 at --max-load-seconds + 0.5 s: the loads above keep
#   both loader threads busy, and a load that waited its whole bound is answered then)
#   slow headers ×2        a byte line a second, never ending its headers    closed
#                          within --request-timeout + 2 s
#   image.exr ×4           of a finished job, while the loaders are busy       200, ≤ 1 s
#   costly texture job     a 638-lookup texture, 256² × 4096 spp, cancelled by a POST
#                          …/cancel with no body and no Content-Type           200, cancelled ≤ 1 s
# then, with two slow loads in flight, SIGTERM: exit 0 within 1 s.
# Checks (exit 1 when one fails, after the report): every answer as listed within its
# bound, /healthz 200 "ok" every time with p99 < 50 ms, SIGTERM as said. Loopback only;
# every client has a time limit (curl --max-time 60), the loops are counted. Writes
# OUT_DIR/hostile.md. Needs curl, gzip and tar (exit 77 without them).
set -u
[ $# -ge 1 ] || { echo "usage: bench/hostile/run.sh BUILD_DIR [OUT_DIR]" >&2; exit 2; }
BUILD=$1
case $BUILD in /*) ;; *) BUILD=$(pwd)/$BUILD ;; esac
OUT=${2:-$BUILD/test-artifacts/hostile}
POLLS=${HOSTILE_POLLS:-400}
LOAD_S=2
REQUEST_TIMEOUT=5
for tool in curl gzip tar bc; do
  command -v $tool >/dev/null || { echo "SKIPPED: bench/hostile needs $tool" >&2; exit 77; }
done
[ -x "$BUILD/tessera" ] || { echo "bench hostile: $BUILD/tessera is missing; build first" >&2; exit 1; }
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
work=$(mktemp -d "${TMPDIR:-/tmp}/ts_hostile_XXXXXX")
server='' pids=''
cleanup() {
  for p in $pids; do kill "$p" 2>/dev/null; done
  [ -n "$server" ] && kill "$server" 2>/dev/null
  wait 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT
cd "$work" || exit 1
log() { echo "bench hostile: $*" >&2; }
now() { date +%s.%N; }
fail=0
bad() { echo "FAIL: $*" >> "$work/failures"; fail=1; }

# ---- the inputs ----
cam='"camera":{"from":[0,0,5],"to":[0,0,0],"fov":40},"film":{"width":16,"height":16},"sampler":{"spp":1}'
{
  printf '{"tessera":1,%s,"materials":{"m0":{"type":"diffuse"}' "$cam"
  for k in $(seq 1 39); do printf ',"m%d":{"type":"mix","materials":["m%d","m%d"]}' "$k" $((k - 1)) $((k - 1)); done
  printf '},"shapes":[{"type":"sphere","radius":1,"material":"m39"}]}\n'
} > mix-chain.json
{
  printf '{"tessera":1,%s,"textures":{"t0":{"type":"checkerboard","tex1":0.2,"tex2":0.8}' "$cam"
  for k in $(seq 1 29); do printf ',"t%d":{"type":"mix","tex1":"t%d","tex2":"t%d"}' "$k" $((k - 1)) $((k - 1)); done
  printf '},"materials":{"m":{"type":"diffuse","reflectance":"t29"}},"shapes":[{"type":"sphere","radius":1,"material":"m"}]}\n'
} > tex-chain.json
mkdir -p pbrt png gz
{
  printf 'Film "image" "integer xresolution" [16] "integer yresolution" [16]\nCamera "perspective"\nWorldBegin\n'
  printf 'MakeNamedMaterial "m0" "string type" "matte"\n'
  for k in $(seq 1 39); do
    printf 'MakeNamedMaterial "m%d" "string type" "mix" "string namedmaterial1" "m%d" "string namedmaterial2" "m%d"\n' \
      "$k" $((k - 1)) $((k - 1))
  done
  printf 'NamedMaterial "m39"\nShape "sphere"\nWorldEnd\n'
} > pbrt/scene.pbrt
tar -C pbrt -cf mix-chain-pbrt.tar scene.pbrt
# A PNG header of 16384² 1-bit grey (IHDR with its CRC), then 40 KB of IDAT that never
# decodes: it passes the decoder's 1032:1 check, so only the header's size stops it.
{
  printf '\211PNG\r\n\032\n\000\000\000\015IHDR\000\000\100\000\000\000\100\000\001\000\000\000\000\201\263\055\051'
  printf '\000\000\234\100IDAT'
  head -c 40000 /dev/zero
  printf '\000\000\000\000'
} > png/huge.png
printf '{"tessera":1,%s,"textures":{"t":{"type":"imagemap","file":"huge.png"}},"materials":{"m":{"type":"diffuse","reflectance":"t"}},"shapes":[{"type":"sphere","radius":1,"material":"m"}]}\n' "$cam" > png/scene.json
tar -C png -czf png-bomb.tgz scene.json huge.png
cp png/scene.json gz/scene.json
head -c 100000000 /dev/zero > gz/zeros.bin
tar -C gz -czf gzip-bomb.tgz scene.json zeros.bin
rm -f gz/zeros.bin
printf '{"tessera":1,%s,"integrator":{"type":"ao"},"materials":{"m":{"type":"diffuse"}},"shapes":[{"type":"loopsubdiv","levels":10,"positions":[-1,-1,0, 1,-1,0, 1,1,0, -1,1,0],"indices":[0,1,2, 0,2,3],"material":"m"}]}\n' "$cam" > subdiv.json
{
  printf '{"tessera":1,"camera":{"from":[0,0,5],"to":[0,0,0],"fov":40},"film":{"width":256,"height":256},"sampler":{"spp":4096},'
  printf '"integrator":{"type":"path","max_depth":2},"textures":{"t0":{"type":"checkerboard","tex1":0.2,"tex2":0.8}'
  for k in $(seq 1 7); do printf ',"t%d":{"type":"mix","tex1":"t%d","tex2":"t%d"}' "$k" $((k - 1)) $((k - 1)); done
  printf '},"materials":{"m":{"type":"diffuse","reflectance":"t7"}},"shapes":[{"type":"sphere","radius":1.5,"material":"m"}],'
  printf '"lights":[{"type":"point","position":[0,3,3],"intensity":10}]}\n'
} > costly.json
printf '{"tessera":1,%s,"integrator":{"type":"ao"},"materials":{"m":{"type":"diffuse"}},"shapes":[{"type":"sphere","radius":1,"material":"m"}]}\n' "$cam" > small.json

# ---- the server ----
start_server() {
  : > "$work/server.log"
  "$BUILD/tessera" serve --bind 127.0.0.1 --port 0 --threads 1 --http-threads 2 --max-load-seconds $LOAD_S \
    --request-timeout $REQUEST_TIMEOUT --client-timeout $REQUEST_TIMEOUT --max-bundle-expanded 67108864 \
    > "$work/server.log" 2>&1 &
  server=$!
  port=
  for _ in $(seq 1 100); do
    port=$(sed -n 's|.*listening on http://127\.0\.0\.1:\([0-9]*\)/.*|\1|p' "$work/server.log")
    [ -n "$port" ] && break
    kill -0 "$server" 2>/dev/null || break
    sleep 0.1
  done
  [ -n "$port" ] || { log "the server did not start"; cat "$work/server.log" >&2; exit 1; }
  URL=http://127.0.0.1:$port
}
start_server

# post NAME FILE TYPE: in the background, "NAME status seconds" into results
post() {
  (curl -s -o "$work/$1.body" -w "$1 %{http_code} %{time_total}\n" --max-time 60 -X POST -H "Content-Type: $3" \
    --data-binary @"$2" "$URL/api/v1/jobs" >> "$work/results") &
  pids="$pids $!"
}
id_of() { sed -n 's/.*"id":"\([^"]*\)".*/\1/p' "$1" | head -n 1; }

# A finished job for the image requests, and the costly texture job.
curl -s --max-time 30 -H 'Content-Type: application/json' --data-binary @small.json "$URL/api/v1/jobs" > small.post
small=$(id_of small.post)
curl -s --max-time 30 -H 'Content-Type: application/json' --data-binary @costly.json "$URL/api/v1/jobs" > costly.post
costly=$(id_of costly.post)
[ -n "$small" ] && [ -n "$costly" ] || { log "setting up failed: $(cat small.post costly.post)"; exit 1; }
for _ in $(seq 1 100); do
  curl -s --max-time 5 "$URL/api/v1/jobs/$small" | grep -q '"state":"done"' && break
  sleep 0.1
done

# ---- the hostile clients, all at once ----
: > results
post mix-chain-1 mix-chain.json application/json
post mix-chain-2 mix-chain.json application/json
post tex-chain tex-chain.json application/json
post mix-chain-pbrt-1 mix-chain-pbrt.tar application/x-tar
post mix-chain-pbrt-2 mix-chain-pbrt.tar application/x-tar
post png-bomb png-bomb.tgz application/gzip
post gzip-bomb gzip-bomb.tgz application/gzip
for k in 1 2 3; do post subdiv-$k subdiv.json application/json; done
for k in 1 2; do
  (
    trap '' PIPE
    t0=$(now)
    if exec 3<>"/dev/tcp/127.0.0.1/$port"; then
      printf 'GET /healthz HTTP/1.1\r\nHost: 127.0.0.1\r\n' >&3
      for _ in $(seq 1 30); do
        sleep 1
        printf 'X-Slow: 1\r\n' >&3 2>/dev/null || break
      done
    fi
    echo "slow-headers-$k closed $(echo "$(now) - $t0" | bc)" >> "$work/results"
  ) &
  pids="$pids $!"
done
for k in 1 2 3 4; do
  (curl -s -o /dev/null -w "image-$k %{http_code} %{time_total}\n" --max-time 60 "$URL/api/v1/jobs/$small/image.exr" \
    >> "$work/results") &
  pids="$pids $!"
done
(
  t0=$(now)
  code=$(curl -s -o /dev/null -w '%{http_code}' --max-time 60 -X POST -H 'Content-Type:' "$URL/api/v1/jobs/$costly/cancel")
  for _ in $(seq 1 200); do
    curl -s --max-time 5 "$URL/api/v1/jobs/$costly" | grep -q '"state":"cancelled"' && break
    sleep 0.01
  done
  echo "cancel-bare $code $(echo "$(now) - $t0" | bc)" >> "$work/results"
) &
pids="$pids $!"

: > health
for _ in $(seq 1 "$POLLS"); do
  curl -s -o health.body -w '%{http_code} %{time_total}\n' --max-time 10 "$URL/healthz" >> health
  grep -q '"status":"ok"' health.body || echo "not-ok $(cat health.body)" >> health
  sleep 0.01
done
wait $pids 2>/dev/null
pids=''

# ---- SIGTERM with two slow loads in flight ----
post term-1 subdiv.json application/json
post term-2 subdiv.json application/json
sleep 0.3
t0=$(now)
kill -TERM "$server"
wait "$server"
rc=$?
term_s=$(echo "$(now) - $t0" | bc)
server=''
wait $pids 2>/dev/null
pids=''

# ---- checks and report ----
expect() { # expect NAME STATUS:BOUND_S…: one of the statuses, within its bound
  line=$(grep "^$1 " results)
  [ -n "$line" ] || { bad "$1: no answer"; return; }
  name=$1
  shift
  set -- $line "$@"
  got=$2 secs=$3
  shift 3
  for want in "$@"; do
    [ "$got" = "${want%%:*}" ] || continue
    [ "$(echo "$secs <= ${want#*:}" | bc)" = 1 ] && return
    bad "$name: $got after $secs s, its bound is ${want#*:} s"
    return
  done
  bad "$name: status $got, expected one of $* ($(head -c 200 "$work/$name.body" 2>/dev/null))"
}
# A cheap refusal is quick unless every loader is busy with a costly load: then 503 at
# its own --max-load-seconds (the pool's watchdog answers it), never later.
busy=503:$(echo "$LOAD_S + 0.5" | bc)
for n in mix-chain-1 mix-chain-2 tex-chain mix-chain-pbrt-1 mix-chain-pbrt-2; do expect $n 400:1 "$busy"; done
expect png-bomb 413:1 "$busy"
expect gzip-bomb 413:5 "$busy"
for k in 1 2 3; do expect subdiv-$k 422:$((LOAD_S + 5)) "$busy"; done
for k in 1 2; do expect slow-headers-$k closed:$((REQUEST_TIMEOUT + 2)); done
for k in 1 2 3 4; do expect image-$k 200:1; done
expect cancel-bare 200:1
grep -q '^not-ok' health && bad "/healthz was not ok: $(grep '^not-ok' health | head -n 1)"
n_h=$(grep -c '^[0-9]' health)
sorted=$(awk '/^[0-9]/{print $2}' health | sort -n)
p50=$(echo "$sorted" | awk -v n="$n_h" 'NR==int(n*0.5+0.5){print}')
p99=$(echo "$sorted" | awk -v n="$n_h" 'NR==int(n*0.99+0.5){print}')
max=$(echo "$sorted" | tail -n 1)
awk '/^[0-9]/ && $1 != 200 {exit 1}' health || bad "/healthz answered other than 200"
[ "$(echo "$p99 < 0.050" | bc)" = 1 ] || bad "/healthz p99 $p99 s, not under 50 ms"
[ "$rc" = 0 ] || bad "SIGTERM: exit status $rc"
[ "$(echo "$term_s < 1" | bc)" = 1 ] || bad "SIGTERM: the server took $term_s s to exit"
{
  echo "# Hostile-client run ($(date -u +%Y-%m-%dT%H:%MZ), load $(cut -d' ' -f1-3 /proc/loadavg))"
  echo
  echo "Server: --threads 1 --http-threads 2 --max-load-seconds $LOAD_S --request-timeout $REQUEST_TIMEOUT."
  echo
  echo "| request | answer | seconds |"
  echo "|---|---|---|"
  sort results | awk '{printf "| %s | %s | %.3f |\n", $1, $2, $3}'
  echo
  echo "/healthz: $n_h answers while they ran: p50 $(echo "$p50 * 1000" | bc) ms, p99 $(echo "$p99 * 1000" | bc) ms, max $(echo "$max * 1000" | bc) ms."
  echo "SIGTERM with two loads in flight: exit $rc after $term_s s."
  echo
  if [ $fail = 0 ]; then echo "All checks passed."; else echo "Failures:"; cat failures; fi
} > "$OUT/hostile.md"
cat "$OUT/hostile.md"
exit $fail
