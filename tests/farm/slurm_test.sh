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
skip() { echo "SKIPPED: $*" >&2; exit 77; }
t0=$(date +%s.%N)
elapsed() { awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }'; }

# ---- install what is missing (Debian packages) ----
need=""
for p in slurm-wlm munge; do
    dpkg-query -W -f='${Status}\n' "$p" 2>/dev/null | grep -q '^install ok installed' || need="$need $p"
done
if [ -n "$need" ]; then
    sudo=""; [ "$(id -u)" = 0 ] || sudo="sudo -n"
    echo "slurm_test: installing$need"
    { $sudo apt-get update -qq && DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends $need; } \
        >/dev/null 2>&1 || skip "could not install$need with apt-get (needs root or password-less sudo)"
fi
for c in munged slurmctld slurmd sbatch squeue scontrol sinfo setpriv; do
    command -v "$c" >/dev/null || skip "$c is not installed"
done
[ "$(id -u)" = 0 ] || skip "starting munged as the munge user and slurmd needs root here"
id munge >/dev/null 2>&1 || skip "the munge user does not exist"

T=$(mktemp -d "${TMPDIR:-/tmp}/tessera-slurm-XXXXXX")
chmod 755 "$T"
pids=()
cleanup() {
    for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null; done
    for pid in "${pids[@]}"; do
        for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
        kill -KILL "$pid" 2>/dev/null
        wait "$pid" 2>/dev/null
    done
    rm -rf "$T"
}
trap cleanup EXIT
dump_logs() { for f in "$T"/*.log "$T"/out/logs/*; do [ -f "$f" ] && { echo "== $f"; tail -n 20 "$f"; }; done >&2; }

# ---- munge: its own socket and key in a 755 folder, run as the munge user ----
mkdir -p "$T/munge"
chown munge: "$T/munge"
chmod 700 "$T/munge"
dd if=/dev/urandom of="$T/munge/munge.key" bs=1024 count=1 status=none
chown munge: "$T/munge/munge.key"
chmod 400 "$T/munge/munge.key"
chmod 755 "$T/munge" # clients reach the socket
setpriv --reuid=munge --regid=munge --init-groups munged -F --socket="$T/munge/munge.sock" \
    --key-file="$T/munge/munge.key" --pid-file="$T/munge/munged.pid" --seed-file="$T/munge/munged.seed" \
    --log-file="$T/munge/munged.log" >/dev/null 2>&1 &
pids+=($!)
for _ in $(seq 50); do [ -S "$T/munge/munge.sock" ] && break; sleep 0.1; done
[ -S "$T/munge/munge.sock" ] || { tail "$T/munge/munged.log" >&2; skip "munged did not start"; }

# ---- slurm.conf: this host as the one node, unprivileged free ports ----
free_port() {
    local p
    for _ in $(seq 100); do
        p=$((20000 + RANDOM % 25000))
        (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null || { echo "$p"; return; }
    done
    return 1
}
ctld_port=$(free_port) && slurmd_port=$(free_port) || skip "no free port"
host=$(hostname -s)
node=$(slurmd -C 2>/dev/null | head -n 1 | sed -E 's/^NodeName=[^ ]+ //; s/ ?RealMemory=[0-9]+//')
[ -n "$node" ] || skip "slurmd -C cannot describe this machine"
mkdir -p "$T/state" "$T/spool"
export SLURM_CONF="$T/slurm.conf"
cat >"$SLURM_CONF" <<CONF
ClusterName=tessera-test
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$T/munge/munge.sock
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/slurmctld.log
SlurmdLogFile=$T/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
MinJobAge=600
NodeName=$host NodeAddr=127.0.0.1 $node State=UNKNOWN
PartitionName=tessera Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
slurmctld -D -i >/dev/null 2>&1 &
pids+=($!)
slurmd -D >/dev/null 2>&1 &
pids+=($!)
state=""
for _ in $(seq 150); do
    state=$(sinfo -h -n "$host" -o %t 2>/dev/null)
    [ "$state" = idle ] && break
    sleep 0.2
done
[ "$state" = idle ] || { dump_logs; skip "the one-node Slurm did not come up (node state '${state:-none}')"; }
echo "slurm_test: munged, slurmctld (port $ctld_port), slurmd (port $slurmd_port) up after $(elapsed) s"

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
