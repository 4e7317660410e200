#!/bin/bash
# A real one-node Slurm (docs/design.md §7): installs Debian's slurm-wlm and munge if
# missing, starts munged, slurmctld and slurmd in a temporary folder on unprivileged ports,
# submits docker/slurm/submit.sh for a small Cornell box as 4 array tasks plus the afterok
# merge, waits with squeue/scontrol, compares the merged image with a single render, and
# stops every daemon it started by its PID. Exit 77 (ctest: skipped) when the daemons
# cannot run here, with the reason; never a pass without a real run.
# TS_SLURM_TESSERA: how the tasks run tessera (the scripts' TESSERA; default the built
# binary); tests/container/run.sh runs it in the image, with TMPDIR its mounted folder.
set -uo pipefail
: "${TS_BINARY:?run through ctest}" "${TS_SOURCE_DIR:?}" "${TS_FARM_COMPARE:?}"
t0=$(date +%s.%N)
elapsed() { awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }'; }
. "$(dirname "$0")/slurm_lib.sh"
slurm_start slurm_test
dump_logs() { slurm_dump_logs; }

# ---- the shipped scripts on a small Cornell box ----
sed -e 's/"width": 512/"width": 32/; s/"height": 512/"height": 32/; s/"spp": 64/"spp": 16/' \
    "$TS_SOURCE_DIR/scenes/cornell-box.json" >"$T/cornell.json"
grep -q '"spp": 16' "$T/cornell.json" || { echo "could not shrink the scene" >&2; exit 1; }
cd "$T"
submit_t=$(date +%s.%N)
TESSERA="${TS_SLURM_TESSERA:-$TS_BINARY}" "$TS_SOURCE_DIR/docker/slurm/submit.sh" "$T/cornell.json" "$T/out" 4 || { dump_logs; exit 1; }
read -r array merge <"$T/out/jobs"
for _ in $(seq 600); do
    [ -z "$(squeue -h -j "$array,$merge" 2>/dev/null)" ] && break
    sleep 0.2
done
run_s=$(awk -v a="$submit_t" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
echo "slurm_test: job states after $run_s s:"
{ scontrol show job "$array"; scontrol show job "$merge"; } 2>/dev/null | grep -o 'JobId=[0-9]* .*\|JobState=[A-Z_]*' |
    grep -o 'JobName=[a-z-]*\|JobState=[A-Z_]*\|ArrayTaskId=[0-9]*' | paste -sd ' ' | sed 's/ JobName/\n  JobName/g; s/^/  /' 
n_done=$(scontrol show job "$array" | grep -c 'JobState=COMPLETED')
m_done=$(scontrol show job "$merge" | grep -c 'JobState=COMPLETED')
if [ "$n_done" != 4 ] || [ "$m_done" != 1 ]; then
    echo "slurm_test: expected 4 completed array tasks and a completed merge" >&2
    dump_logs
    exit 1
fi
grep -h "shard .* from SLURM_ARRAY_TASK_ID" "$T"/out/logs/shard-* | sed 's/^/  /'
"$TS_BINARY" render "$T/cornell.json" --shard 0/1 -o "$T/reference.exr" --quiet || exit 1
"$TS_FARM_COMPARE" "$T/out/image.exr" "$T/reference.exr" || { dump_logs; exit 1; }
[ -s "$T/out/image.png" ] || { echo "no image.png" >&2; exit 1; }
echo "slurm_test: passed: 4-task array + afterok merge in $run_s s; whole test $(elapsed) s"
