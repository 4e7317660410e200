# slurm_lib.sh — a real one-node Slurm for the farm tests (docs/design.md §7), sourced by
# slurm_test.sh and farm_server_test.sh: installs Debian's slurm-wlm and munge if missing,
# starts munged, slurmctld and slurmd in a temporary folder on unprivileged ports, and
# stops every daemon it started by its PID at exit. Where the daemons cannot run here it
# exits 77 (ctest: skipped) with the reason; never a pass without a real Slurm.
#   slurm_start NAME     after it: $T (the temporary folder, removed at exit), SLURM_CONF
#                        exported, $slurm_host, slurm_pids (add your own to be stopped too)
#   slurm_dump_logs      the daemons' last log lines, on stderr
skip() { echo "SKIPPED: $*" >&2; exit 77; }
slurm_pids=()
slurm_cleanup() {
    for pid in "${slurm_pids[@]}"; do kill -TERM "$pid" 2>/dev/null; done
    for pid in "${slurm_pids[@]}"; do
        for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
        kill -KILL "$pid" 2>/dev/null
        wait "$pid" 2>/dev/null
    done
    [ -n "${T:-}" ] && rm -rf "$T"
}
slurm_dump_logs() { for f in "$T"/*.log "$T"/out/logs/*; do [ -f "$f" ] && { echo "== $f"; tail -n 20 "$f"; }; done >&2; }

slurm_start() {
    local name=$1 p need=""
    # ---- install what is missing (Debian packages) ----
    for p in slurm-wlm munge; do
        dpkg-query -W -f='${Status}\n' "$p" 2>/dev/null | grep -q '^install ok installed' || need="$need $p"
    done
    if [ -n "$need" ]; then
        local sudo=""; [ "$(id -u)" = 0 ] || sudo="sudo -n"
        echo "$name: installing$need"
        { $sudo apt-get update -qq && DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends $need; } \
            >/dev/null 2>&1 || skip "could not install$need with apt-get (needs root or password-less sudo)"
    fi
    for p in munged slurmctld slurmd sbatch squeue scontrol scancel sinfo setpriv; do
        command -v "$p" >/dev/null || skip "$p is not installed"
    done
    [ "$(id -u)" = 0 ] || skip "starting munged as the munge user and slurmd needs root here"
    id munge >/dev/null 2>&1 || skip "the munge user does not exist"

    T=$(mktemp -d "${TMPDIR:-/tmp}/tessera-slurm-XXXXXX")
    chmod 755 "$T"
    trap slurm_cleanup EXIT

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
    slurm_pids+=($!)
    for _ in $(seq 50); do [ -S "$T/munge/munge.sock" ] && break; sleep 0.1; done
    [ -S "$T/munge/munge.sock" ] || { tail "$T/munge/munged.log" >&2; skip "munged did not start"; }

    # ---- slurm.conf: this host as the one node, unprivileged free ports ----
    local ctld_port slurmd_port node state=""
    ctld_port=$(slurm_free_port) && slurmd_port=$(slurm_free_port) || skip "no free port"
    slurm_host=$(hostname -s)
    node=$(slurmd -C 2>/dev/null | head -n 1 | sed -E 's/^NodeName=[^ ]+ //; s/ ?RealMemory=[0-9]+//')
    [ -n "$node" ] || skip "slurmd -C cannot describe this machine"
    mkdir -p "$T/state" "$T/spool"
    export SLURM_CONF="$T/slurm.conf"
    cat >"$SLURM_CONF" <<CONF
ClusterName=tessera-test
SlurmctldHost=$slurm_host(127.0.0.1)
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
KillWait=5
NodeName=$slurm_host NodeAddr=127.0.0.1 $node State=UNKNOWN
PartitionName=tessera Nodes=$slurm_host Default=YES MaxTime=INFINITE State=UP
CONF
    slurmctld -D -i >/dev/null 2>&1 &
    slurm_pids+=($!)
    slurmd -D >/dev/null 2>&1 &
    slurm_pids+=($!)
    for _ in $(seq 150); do
        state=$(sinfo -h -n "$slurm_host" -o %t 2>/dev/null)
        [ "$state" = idle ] && break
        sleep 0.2
    done
    [ "$state" = idle ] || { slurm_dump_logs; skip "the one-node Slurm did not come up (node state '${state:-none}')"; }
    echo "$name: munged, slurmctld (port $ctld_port), slurmd (port $slurmd_port) up, $(sinfo -h -o '%c') CPUs"
}

slurm_free_port() {
    local p
    for _ in $(seq 100); do
        p=$((20000 + RANDOM % 25000))
        (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null || { echo "$p"; return; }
    done
    return 1
}
