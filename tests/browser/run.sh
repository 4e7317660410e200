#!/bin/bash
# Browser tests of the web UI (ctest browser_ui): playwright-core from the web build's npm
# packages (web/package-lock.json, installed in the build folder by the web build) drives
# Debian's chromium headless against a real `tessera serve` on loopback (ui_test.mjs).
# Without chromium the test says so and exits 77, which ctest reports as skipped.
set -euo pipefail
: "${TS_BINARY:?run through ctest}" "${TS_SOURCE_DIR:?}" "${TS_BUILD_DIR:?}"
chromium=${TS_CHROMIUM:-/usr/bin/chromium}
if [ ! -x "$chromium" ]; then
    echo "SKIPPED: browser tests need Debian's chromium at $chromium, which is not installed here" \
         "(make deps installs it; or set TS_CHROMIUM)." >&2
    exit 77
fi
command -v node >/dev/null || { echo "browser tests: node is needed (Debian: apt-get install nodejs)" >&2; exit 1; }
mods="$TS_BUILD_DIR/web/src/node_modules"
[ -d "$mods/playwright-core" ] || { echo "browser tests: $mods/playwright-core is missing: build tessera with TS_WEB=ON first" >&2; exit 1; }
export TS_WEB_NODE_MODULES="$mods" TS_ARTIFACTS="$TS_BUILD_DIR/test-artifacts/browser"
rm -rf "$TS_ARTIFACTS"
exec timeout 300 node "$TS_SOURCE_DIR/tests/browser/ui_test.mjs"
