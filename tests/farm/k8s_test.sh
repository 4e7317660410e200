#!/bin/bash
# Kubernetes manifests of docker/k8s: schema validation with the npm packages of
# tests/farm/package.json (installed here, into the build folder, from the lock file), then
# the Jobs' commands run as the Job controller would (k8s_check.mjs).
set -euo pipefail
: "${TS_BINARY:?run through ctest}" "${TS_SOURCE_DIR:?}" "${TS_FARM_COMPARE:?}" "${TS_BUILD_DIR:?}"
command -v node >/dev/null && command -v npm >/dev/null || {
    echo "k8s_test: node and npm are needed (Debian: apt-get install nodejs npm)" >&2
    exit 1
}
mods="$TS_BUILD_DIR/farm-npm"
mkdir -p "$mods"
cp "$TS_SOURCE_DIR/tests/farm/package.json" "$TS_SOURCE_DIR/tests/farm/package-lock.json" "$TS_SOURCE_DIR/tests/farm/k8s_check.mjs" "$mods/"
if ! cmp -s "$mods/package-lock.json" "$mods/node_modules/.tessera-installed-lock" 2>/dev/null; then
    (cd "$mods" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
    cp "$mods/package-lock.json" "$mods/node_modules/.tessera-installed-lock"
fi
T=$(mktemp -d /tmp/tessera-k8s-XXXXXX)
trap 'rm -rf "$T"' EXIT
mkdir -p "$T/bin" "$T/farm" # the Jobs make the folders they write
ln -s "$TS_BINARY" "$T/bin/tessera"
# The operator's step: a small Cornell box onto the shared volume as scene.json.
sed -e 's/"width": 512/"width": 32/; s/"height": 512/"height": 32/; s/"spp": 64/"spp": 16/' \
    "$TS_SOURCE_DIR/scenes/cornell-box.json" >"$T/farm/scene.json"
node "$mods/k8s_check.mjs" "$TS_SOURCE_DIR" "$T/farm" "$T/bin" "$TS_FARM_COMPARE"
