#!/bin/sh
# Submits a tessera render to Slurm: a job array of N shards, then the merge with
# --dependency=afterok on the whole array. Prints the two job ids.
#   usage: submit.sh SCENE OUT_DIR [N] [extra sbatch options...]
# SCENE and OUT_DIR must be on storage every node sees. TESSERA (how to run tessera) and
# TESSERA_ARGS (extra render options) are passed on to the jobs; see tessera-shard.sbatch.
set -eu
if [ $# -lt 2 ]; then
    echo "usage: $0 SCENE OUT_DIR [N] [sbatch options...]" >&2
    exit 2
fi
here=$(cd "$(dirname "$0")" && pwd)
scene=$(realpath "$1")
mkdir -p "$2/logs"
out=$(realpath "$2")
n=${3:-4}
[ $# -ge 3 ] && shift 3 || shift $#
case $n in '' | *[!0-9]* | 0) echo "$0: N must be a positive whole number, got '$n'" >&2; exit 2 ;; esac
array=$(sbatch --parsable --array="0-$((n - 1))" --output="$out/logs/shard-%A_%a.out" \
    --export="ALL,TESSERA_SCENE=$scene,TESSERA_OUT=$out" "$@" "$here/tessera-shard.sbatch")
array=${array%%;*} # "id;cluster" on multi-cluster set-ups
merge=$(sbatch --parsable --dependency="afterok:$array" --kill-on-invalid-dep=yes \
    --output="$out/logs/merge-%j.out" --export="ALL,TESSERA_OUT=$out" "$@" "$here/tessera-merge.sbatch")
merge=${merge%%;*}
echo "tessera: submitted render array $array ($n shards of $scene) and merge $merge (afterok); output in $out"
echo "$array $merge" >"$out/jobs"
