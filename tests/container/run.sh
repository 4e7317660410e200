#!/bin/bash
# The container image for real (docker/README.md). Installs podman, runc, catatonit
# and debootstrap if missing (`make image-deps`), builds docker/Dockerfile with
# docker/build-image.sh (podman's layer cache reused; the Debian base images debootstrapped
# where no registry answers), checks the image (size ≤ 150 MB, user 10001, HEALTHCHECK, no
# unresolved library), then, with every port on 127.0.0.1 only:
#   1. serve: `tessera serve` in a container published on 127.0.0.1; the HEALTHCHECK is
#      healthy, unhealthy while the server is stopped (SIGSTOP), healthy again; the embedded
#      web UI is served; a job submitted over HTTP gives an EXR bit-identical to the CLI's
#      render of the same scene (bench_exr_compare); SIGTERM stops it with status 0.
#   2. farm: shard 0 of 2 from a Kubernetes Indexed Job's JOB_COMPLETION_INDEX + --shard-count,
#      shard 1 from a Slurm array's SLURM_ARRAY_TASK_ID/MIN/COUNT (the shipped
#      tessera-shard.sbatch, tessera in the container), merged by tessera-merge.sbatch in a
#      container; the merge equals one render (farm_compare).
#   3. docker/k8s under `podman kube play`: the claim, one Pod per completion index from the
#      Indexed Job's pod template, then the merge Job's Pod (kube_pods.mjs makes them as the
#      Job controller would); the merge equals one render.
#   4. a real one-node Slurm running the shipped scripts with tessera in the container
#      (tests/farm/slurm_test.sh with TS_SLURM_TESSERA); its own skip (77) is reported and
#      does not skip this test.
# Exit 77 (ctest: skipped) with the reason where podman cannot run containers here (e.g. in a
# chroot) or cannot be installed; never a pass without the containers having run.
set -uo pipefail
: "${TS_BINARY:?run through ctest}" "${TS_SOURCE_DIR:?}" "${TS_FARM_COMPARE:?}" "${TS_EXR_COMPARE:?}" "${TS_BUILD_DIR:?}"
skip() { echo "SKIPPED: $*" >&2; exit 77; }
fail() { echo "container_test: FAIL: $*" >&2; exit 1; }
log() { echo "container_test: $*"; }
t0=$(date +%s.%N)
since() { awk -v a="$1" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }'; }

# ---- podman: installed, and able to run a container here ----
if ! deps_log=$(make -s -C "$TS_SOURCE_DIR" image-deps 2>&1); then
    tail -n 3 <<<"$deps_log" >&2
    skip "could not install the image packages (make image-deps needs root or sudo)"
fi
for c in curl node npm; do command -v $c >/dev/null || fail "$c is needed (make deps installs it)"; done
export CONTAINER_ENGINE=podman
# shellcheck source=docker/engine.sh
. "$TS_SOURCE_DIR/docker/engine.sh"
ts_engine_init || skip "podman is not usable"
T=$(mktemp -d "${TMPDIR:-/tmp}/tessera-container-XXXXXX")
chmod 755 "$T"
name="tessera-ctest-$$"
image="localhost/tessera:ctest"
started=() pods=() volumes=()
cleanup() {
    for c in "${started[@]}"; do "${engine[@]}" rm -f -t 2 "$c" >/dev/null 2>&1; done
    for p in "${pods[@]}"; do "${engine[@]}" pod rm -f "$p" >/dev/null 2>&1; done
    for v in "${volumes[@]}"; do "${engine[@]}" volume rm -f "$v" >/dev/null 2>&1; done
    rm -rf "$T"
}
trap cleanup EXIT
# Where this process may not raise resource limits (no CAP_SYS_RESOURCE, as in some sandboxes),
# podman's defaults for a container (1048576 files, 4194304 processes) cannot be set: the
# containers get this host's own limits instead (podman runs conmon with at most 32768
# processes), through a containers.conf of the test's (also read by `podman kube play`).
cap_eff=$(awk '/^CapEff:/ { print $2 }' /proc/self/status)
if [ -n "$cap_eff" ] && [ $(((16#$cap_eff >> 24) & 1)) = 0 ]; then
    nproc=$(ulimit -Hu)
    [ "$nproc" = unlimited ] || [ "$nproc" -gt 32768 ] && nproc=32768
    printf '[containers]\ndefault_ulimits = ["nofile=%s:%s", "nproc=%s:%s"]\n' \
        "$(ulimit -Hn)" "$(ulimit -Hn)" "$nproc" "$nproc" >"$T/containers.conf"
    export CONTAINERS_CONF="$T/containers.conf"
    log "no CAP_SYS_RESOURCE here: containers get nofile $(ulimit -Hn), nproc $nproc ($CONTAINERS_CONF)"
fi
# The probe: /usr/bin/true and its libraries as a root file system, run by podman.
mkdir -p "$T/probe"
for f in /usr/bin/true $(ldd /usr/bin/true | grep -o '/[^ ]*'); do
    mkdir -p "$T/probe$(dirname "$f")" && cp -L "$f" "$T/probe$f"
done
if ! "${engine[@]}" run --rm --network none --rootfs "$T/probe" /usr/bin/true >"$T/probe.log" 2>&1; then
    skip "podman cannot run a container here: $(grep -v '^time=' "$T/probe.log" | head -n 1)"
fi
log "podman runs containers here ($(podman --version), ${engine[*]})"

# ---- the image ----
build_t=$(date +%s.%N)
if ! "$TS_SOURCE_DIR/docker/build-image.sh" "$image" >"$T/build.log" 2>&1; then
    tail -n 40 "$T/build.log" >&2
    fail "docker/build-image.sh failed"
fi
build_s=$(since "$build_t")
grep '^image:' "$T/build.log" | sed 's/^/  /'
log "image built in $build_s s"
size=$("${engine[@]}" image inspect --format '{{.Size}}' "$image")
[ "$size" -le 150000000 ] || fail "the image is $((size / 1000000)) MB, over the 150 MB target"
user=$("${engine[@]}" image inspect --format '{{.Config.User}}' "$image")
[ "$user" = 10001:10001 ] || fail "the image runs as '$user', not 10001:10001"
health=$("${engine[@]}" image inspect --format '{{json .HealthCheck}}' "$image")
grep -q '"CMD","perl"' <<<"$health" || fail "no exec-form HEALTHCHECK in the image: $health"
# Only the binary and its libraries: no toolchain, node or curl; every library resolved.
"${engine[@]}" run --rm --network none --entrypoint /bin/sh "$image" -c \
    'for c in gcc cc cmake make node npm curl; do command -v $c && exit 1; done
     ! ldd /usr/local/bin/tessera | grep "not found"' >"$T/contents.log" 2>&1 ||
    fail "the final image holds more or less than it should: $(grep -v '^time=' "$T/contents.log" | head -n 3)"
log "image: $((size / 1000000)) MB, user $user, HEALTHCHECK $health"

small_scene() { # small_scene SIZE SPP OUT: the Cornell box, SIZE² pixels, SPP samples per pixel
    sed -e "s/\"width\": 512/\"width\": $1/; s/\"height\": 512/\"height\": $1/; s/\"spp\": 64/\"spp\": $2/" \
        "$TS_SOURCE_DIR/scenes/cornell-box.json" >"$3"
    grep -q "\"spp\": $2" "$3" && grep -q "\"width\": $1" "$3" || fail "could not shrink scenes/cornell-box.json"
}
# A folder a container's user 10001 may write, as a volume's fsGroup would make it.
shared_dir() {
    mkdir -p "$1"
    if [ "$(id -u)" = 0 ]; then chown -R 10001:10001 "$1"; else chmod -R a+rwX "$1"; fi
}
json_field() { sed -n "s/.*\"$2\":\"\{0,1\}\([^,\"}]*\).*/\1/p" "$1" | head -n 1; }
# Polls the server at $URL until job $1 has ended (600 polls 0.2 s apart); fails unless it
# is done, naming it as $2 with its status.
wait_done() {
    local state=""
    for _ in $(seq 600); do
        curl -sS --max-time 10 "$URL/api/v1/jobs/$1" >"$T/status.json" || true
        state=$(json_field "$T/status.json" state)
        case $state in done | failed | cancelled) break ;; esac
        sleep 0.2
    done
    [ "$state" = done ] || fail "$2 $1 ended '$state': $(cat "$T/status.json")"
}

# ---- 1. serve ----
part=$(date +%s.%N)
small_scene 64 16 "$T/serve.json"
"$TS_BINARY" render "$T/serve.json" -o "$T/cli.exr" --quiet || fail "the CLI reference render failed"
srv="$name-serve"
started+=("$srv")
"${engine[@]}" run -d --name "$srv" -p 127.0.0.1::8080 "$image" serve --bind 0.0.0.0 --port 8080 --allowed-hosts localhost --threads 2 \
    >"$T/run.log" 2>&1 || fail "could not start the server container: $(grep -v '^time=' "$T/run.log" | head -n 1)"
published=$("${engine[@]}" port "$srv" 8080/tcp)
case $published in 127.0.0.1:[0-9]*) ;; *) fail "port 8080 published as '$published', not on 127.0.0.1 only" ;; esac
URL="http://$published"
up=0
for _ in $(seq 100); do
    curl -sf --max-time 2 "$URL/healthz" >/dev/null && { up=1; break; }
    sleep 0.2
done
[ $up = 1 ] || { "${engine[@]}" logs "$srv" >&2; fail "the server did not answer on $URL/healthz"; }
# `podman healthcheck run`: exit 0 when healthy, 1 and "unhealthy" when not.
healthcheck() { "${engine[@]}" healthcheck run "$srv" >"$T/health.out" 2>&1; }
health_log() { "${engine[@]}" inspect --format '{{range .State.Health.Log}}{{.Output}}; {{end}}' "$srv"; }
healthcheck || fail "the HEALTHCHECK does not report healthy: $(health_log)"
pid=$("${engine[@]}" inspect --format '{{.State.Pid}}' "$srv")
kill -STOP "$pid"
healthcheck && { kill -CONT "$pid"; fail "the HEALTHCHECK reports healthy while the server is stopped"; }
kill -CONT "$pid"
grep -q unhealthy "$T/health.out" || fail "the HEALTHCHECK of a stopped server: $(cat "$T/health.out")"
healthcheck || fail "the HEALTHCHECK does not report healthy after SIGCONT: $(health_log)"
log "serve: $URL (127.0.0.1 only); HEALTHCHECK healthy, unhealthy while stopped, healthy again: $(health_log)"
# The web UI as a browser on this machine asks for it (Host: localhost, hence --allowed-hosts).
curl -sf --max-time 10 "http://localhost:${published#*:}/" -o "$T/index.html" || fail "GET / as localhost failed"
asset=$(grep -o '/assets/[^"]*\.js' "$T/index.html" | head -n 1)
grep -q 'id="jobs-h"' "$T/index.html" && [ -n "$asset" ] || fail "GET / is not the built web UI"
curl -sf --max-time 10 "$URL$asset" -o /dev/null || fail "the web UI's $asset is not served"
curl -sS --max-time 30 -X POST -H 'Content-Type: application/json' --data-binary @"$T/serve.json" \
    "$URL/api/v1/jobs" >"$T/post.json" || fail "POST /api/v1/jobs failed"
id=$(json_field "$T/post.json" id)
[ -n "$id" ] || fail "the job was not created: $(cat "$T/post.json")"
wait_done "$id" job
curl -sSf --max-time 30 -o "$T/job.exr" "$URL/api/v1/jobs/$id/image.exr" || fail "GET image.exr failed"
"$TS_EXR_COMPARE" "$T/cli.exr" "$T/job.exr" >"$T/cmp.txt" 2>&1 || fail "the job's EXR differs from the CLI's: $(cat "$T/cmp.txt")"
log "serve: job $id over HTTP, its EXR equals tessera render's ($(cat "$T/cmp.txt"))"
# A job that carries its files: the image links libarchive statically (tar + gzip), so
# this is the check that its reader is in the binary.
mkdir -p "$T/bundle" && cp "$T/serve.json" "$T/bundle/scene.json"
tar -C "$T/bundle" -czf "$T/bundle.tar.gz" scene.json
curl -sS --max-time 30 -X POST -H 'Content-Type: application/x-tar' --data-binary @"$T/bundle.tar.gz" \
    "$URL/api/v1/jobs" >"$T/post-bundle.json" || fail "POST of a bundle failed"
bid=$(json_field "$T/post-bundle.json" id)
[ -n "$bid" ] || fail "the bundle job was not created: $(cat "$T/post-bundle.json")"
wait_done "$bid" "bundle job"
curl -sSf --max-time 30 -o "$T/bundle.exr" "$URL/api/v1/jobs/$bid/image.exr" || fail "GET the bundle job's image.exr failed"
"$TS_EXR_COMPARE" "$T/cli.exr" "$T/bundle.exr" >"$T/cmp.txt" 2>&1 || fail "the bundle job's EXR differs from the CLI's: $(cat "$T/cmp.txt")"
log "serve: a gzip tar bundle as job $bid, its EXR equals tessera render's"
"${engine[@]}" stop -t 10 "$srv" >/dev/null 2>&1
code=$("${engine[@]}" inspect --format '{{.State.ExitCode}}' "$srv")
[ "$code" = 0 ] || fail "the server exited $code on SIGTERM"
log "serve: stopped by SIGTERM with status 0; part 1 in $(since "$part") s"

# ---- 2. two shards from the Kubernetes and Slurm variables, merged, all in containers ----
part=$(date +%s.%N)
farm="$T/farm"
shared_dir "$farm/shards"
small_scene 32 16 "$farm/scene.json"
# Kubernetes: the Job controller sets JOB_COMPLETION_INDEX; the count comes from --shard-count.
"${engine[@]}" run --rm --network none -v "$farm:/farm" -e JOB_COMPLETION_INDEX=0 "$image" \
    render /farm/scene.json --shard auto --shard-count 2 -o /farm/shards/shard-0.exr >"$T/k8s-shard.log" 2>&1 ||
    { cat "$T/k8s-shard.log" >&2; fail "the Kubernetes-style shard failed"; }
grep -q 'shard 0/2 from JOB_COMPLETION_INDEX=0' "$T/k8s-shard.log" || { cat "$T/k8s-shard.log" >&2; fail "shard 0 did not come from JOB_COMPLETION_INDEX"; }
# Slurm: task 1 of an array 0-1, through the shipped script with tessera in the container
# (docker/README.md, "Slurm with the image"); the same path inside as outside.
tessera_in_podman="${engine[*]} run --rm --network none --user $(id -u):$(id -g) -v $farm:$farm --env SLURM_* $image"
SLURM_ARRAY_TASK_ID=1 SLURM_ARRAY_TASK_MIN=0 SLURM_ARRAY_TASK_MAX=1 SLURM_ARRAY_TASK_COUNT=2 \
    TESSERA="$tessera_in_podman" TESSERA_SCENE="$farm/scene.json" TESSERA_OUT="$farm" \
    "$TS_SOURCE_DIR/docker/slurm/tessera-shard.sbatch" >"$T/slurm-shard.log" 2>&1 ||
    { cat "$T/slurm-shard.log" >&2; fail "the Slurm-style shard failed"; }
grep -q 'shard 1/2 from SLURM_ARRAY_TASK_ID' "$T/slurm-shard.log" || { cat "$T/slurm-shard.log" >&2; fail "shard 1 did not come from SLURM_ARRAY_TASK_ID"; }
rm -f "$farm"/shards/checkpoint-*.exr
TESSERA="$tessera_in_podman" TESSERA_OUT="$farm" "$TS_SOURCE_DIR/docker/slurm/tessera-merge.sbatch" >"$T/merge.log" 2>&1 ||
    { cat "$T/merge.log" >&2; fail "the merge in a container failed"; }
"$TS_BINARY" render "$farm/scene.json" --shard 0/1 -o "$T/farm-ref.exr" --quiet || fail "the reference render failed"
"$TS_FARM_COMPARE" "$farm/image.exr" "$T/farm-ref.exr" >"$T/farm-cmp.txt" 2>&1 || { cat "$T/farm-cmp.txt" >&2; fail "the merged shards differ from one render"; }
grep -h 'shard .* from ' "$T/k8s-shard.log" "$T/slurm-shard.log" | sed 's/^/  /'
log "farm: merged in a container; $(cat "$T/farm-cmp.txt"); part 2 in $(since "$part") s"

# ---- 3. docker/k8s under podman kube play ----
part=$(date +%s.%N)
mods="$TS_BUILD_DIR/container-npm"
mkdir -p "$mods"
cp "$TS_SOURCE_DIR/tests/farm/package.json" "$TS_SOURCE_DIR/tests/farm/package-lock.json" \
    "$TS_SOURCE_DIR/tests/container/kube_pods.mjs" "$mods/"
if ! cmp -s "$mods/package-lock.json" "$mods/node_modules/.tessera-installed-lock" 2>/dev/null; then
    (cd "$mods" && npm ci --no-audit --no-fund --loglevel=error >/dev/null) || fail "npm ci of tests/farm/package.json failed"
    cp "$mods/package-lock.json" "$mods/node_modules/.tessera-installed-lock"
fi
claim="$name-farm"
mkdir -p "$T/kube"
node "$mods/kube_pods.mjs" "$TS_SOURCE_DIR" "$T/kube" "$image" "$claim" "$name" >"$T/kube/names" ||
    fail "could not make Pods of docker/k8s"
field() { sed -n "s/^$1 //p" "$T/kube/names"; }
read -r -a render_pods <<<"$(field render)"
read -r -a render_ctrs <<<"$(field render-containers)"
read -r -a merge_pods <<<"$(field merge)"
read -r -a merge_ctrs <<<"$(field merge-containers)"
volumes+=("$claim")
# podman 4.3's kube play looks in its working directory for a folder named as the image (to
# build it), even with --build=false, and fails on the build folder's file `tessera`.
kube_play() { (cd "$T/kube" && "${engine[@]}" kube play --build=false "$1"); }
kube_play "$T/kube/claim.yaml" >"$T/kube/play.log" 2>&1 || { cat "$T/kube/play.log" >&2; fail "kube play of the claim failed"; }
vol=$("${engine[@]}" volume inspect --format '{{.Mountpoint}}' "$claim") || fail "the claim made no volume"
small_scene 32 16 "$vol/scene.json" # the operator's step (README): the scene onto the volume
shared_dir "$vol"                   # what the pod's fsGroup 10001 does on a cluster
# play_pods YAML CONTAINER...: kube play, then each container's exit status must be 0.
play_pods() {
    local yaml=$1 c code
    shift
    kube_play "$yaml" >>"$T/kube/play.log" 2>&1 || { cat "$T/kube/play.log" >&2; fail "kube play $(basename "$yaml") failed"; }
    for c in "$@"; do
        code=$(timeout 300 "${engine[@]}" wait "$c" 2>/dev/null)
        "${engine[@]}" logs "$c" >"$T/kube/$c.log" 2>&1
        [ "$code" = 0 ] || { cat "$T/kube/$c.log" >&2; fail "container $c exited '${code:-no status}'"; }
    done
}
pods+=("${render_pods[@]}" "${merge_pods[@]}")
play_pods "$T/kube/render-pods.yaml" "${render_ctrs[@]}"
play_pods "$T/kube/merge-pod.yaml" "${merge_ctrs[@]}"
"$TS_BINARY" render "$vol/scene.json" --shard 0/1 -o "$T/kube-ref.exr" --quiet || fail "the reference render failed"
"$TS_FARM_COMPARE" "$vol/out/image.exr" "$T/kube-ref.exr" >"$T/kube-cmp.txt" 2>&1 || { cat "$T/kube-cmp.txt" >&2; fail "the kube play merge differs from one render"; }
[ -s "$vol/out/image.png" ] || fail "the merge Pod wrote no image.png"
grep -h 'from JOB_COMPLETION_INDEX' "$T"/kube/*-tessera.log | sed 's/^/  /'
log "kube play: ${#render_ctrs[@]} index Pods + the merge Pod; $(cat "$T/kube-cmp.txt"); part 3 in $(since "$part") s"

# ---- 4. a real one-node Slurm, tessera in the container ----
part=$(date +%s.%N)
mkdir -p "$T/slurm"
chmod 755 "$T/slurm"
TMPDIR="$T/slurm" TS_SLURM_TESSERA="${engine[*]} run --rm --network none --user $(id -u):$(id -g) -v $T/slurm:$T/slurm --env SLURM_* $image" \
    "$TS_SOURCE_DIR/tests/farm/slurm_test.sh" >"$T/slurm.log" 2>&1
rc=$?
case $rc in
0) sed 's/^/  /' "$T/slurm.log"; log "slurm with podman: passed in $(since "$part") s" ;;
77) log "slurm with podman: not run: $(grep -h SKIPPED "$T/slurm.log")" ;;
*) cat "$T/slurm.log" >&2; fail "the Slurm run with tessera in the container failed (exit $rc)" ;;
esac

log "passed in $(since "$t0") s (image build $build_s s)"
