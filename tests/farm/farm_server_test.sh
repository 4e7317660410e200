#!/bin/bash
# ctest farm_server (docs/design.md §7): `tessera serve --farm slurm` on a real one-node
# Slurm (slurm_lib.sh: Debian's slurm-wlm + munge, unprivileged ports, the machine's CPUs,
# at least 2, so tasks overlap). farm_server.mjs drives it: the refusals; a 4-shard job over
# HTTP, its events and its EXR bit for bit against the CLI's; cancel mid-run (squeue empty,
# the image kept); one task scancelled (requeued, still equal); kill -9 of the server and a
# restart on the same --data (re-attached, nothing submitted twice); the web UI's shard
# view in chromium (reported as not run where chromium is missing). Exit 77 (ctest:
# skipped) when Slurm cannot start here, with the reason; never a pass without a real run.
set -uo pipefail
: "${TS_BINARY:?run through ctest}" "${TS_SOURCE_DIR:?}" "${TS_EXR_COMPARE:?}" "${TS_BUILD_DIR:?}"
command -v node >/dev/null || { echo "farm_server: node is needed (Debian: apt-get install nodejs)" >&2; exit 1; }
. "$(dirname "$0")/slurm_lib.sh"
slurm_start farm_server
cpus=$(sinfo -h -o '%c' | head -n 1)
[ "${cpus:-0}" -ge 2 ] || skip "the one node has ${cpus:-no} CPUs; the farm tests need 2 so that tasks overlap"
export T SLURM_CONF
timeout 600 node "$TS_SOURCE_DIR/tests/farm/farm_server.mjs"
rc=$?
[ $rc = 0 ] || slurm_dump_logs
exit $rc
