#!/bin/sh
# A one-node Slurm cluster on this machine, for trying the job scripts and for the
# test that submits a real sharded render (tests/it/slurm.rs). Everything lives in
# DIR: its own munge key and socket, slurm.conf, state, logs; nothing in /etc is
# touched. Needs Debian's slurm-wlm and munge packages (slurmctld, slurmd, munged).
#
#   tools/slurm/local-cluster.sh start DIR [CPUS]   # prints: export SLURM_CONF=DIR/slurm.conf
#   tools/slurm/local-cluster.sh stop DIR
#
# The node runs jobs as the user who starts it, with proctrack/linuxproc and no
# cgroups (containers rarely allow them). Exit status 3: a daemon would not start
# (the reason is on stderr).
set -eu
cmd=${1:?usage: local-cluster.sh start|stop DIR [CPUS]}
dir=${2:?usage: local-cluster.sh start|stop DIR [CPUS]}
cpus=${3:-$(nproc)}

stop() {
    for d in slurmd slurmctld munged; do
        if [ -f "$dir/$d.pid" ]; then
            kill "$(cat "$dir/$d.pid")" 2>/dev/null || true
        fi
    done
    sleep 1
    for d in slurmd slurmctld munged; do
        if [ -f "$dir/$d.pid" ]; then
            kill -9 "$(cat "$dir/$d.pid")" 2>/dev/null || true
            rm -f "$dir/$d.pid"
        fi
    done
}

cannot() {
    echo "local-cluster: $*" >&2
    stop
    exit 3
}

free_port() {
    python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

if [ "$cmd" = stop ]; then
    stop
    exit 0
fi
[ "$cmd" = start ] || { echo "local-cluster: unknown command $cmd" >&2; exit 2; }
for b in munged slurmctld slurmd sbatch sinfo; do
    command -v "$b" >/dev/null 2>&1 || [ -x "/usr/sbin/$b" ] || cannot "$b is not installed (apt-get install slurm-wlm munge)"
done
PATH=$PATH:/usr/sbin
mkdir -p "$dir/state" "$dir/spool"
dir=$(cd "$dir" && pwd)
user=$(id -un)
head -c 1024 /dev/urandom >"$dir/munge.key"
chmod 600 "$dir/munge.key"
munged --socket="$dir/munge.socket" --key-file="$dir/munge.key" --pid-file="$dir/munged.pid" \
    --log-file="$dir/munged.log" --seed-file="$dir/munged.seed" --force >/dev/null 2>&1 ||
    cannot "munged would not start: $(tail -n 3 "$dir/munged.log" 2>/dev/null)"
cat >"$dir/slurm.conf" <<CONF
ClusterName=pbrtsppm
SlurmctldHost=localhost(127.0.0.1)
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
AuthInfo=socket=$dir/munge.socket
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SwitchType=switch/none
MpiDefault=none
SlurmctldPort=$(free_port)
SlurmdPort=$(free_port)
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
NodeName=localnode NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=local Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$dir/slurm.conf"
slurmctld -c >/dev/null 2>&1 || cannot "slurmctld would not start: $(tail -n 3 "$dir/slurmctld.log" 2>/dev/null)"
slurmd -N localnode >/dev/null 2>&1 || cannot "slurmd would not start: $(tail -n 3 "$dir/slurmd.log" 2>/dev/null)"
for _ in $(seq 60); do
    if [ "$(sinfo -h -o %t 2>/dev/null)" = idle ]; then
        echo "export SLURM_CONF=$dir/slurm.conf"
        exit 0
    fi
    sleep 0.5
done
cannot "the node never became idle: $(sinfo 2>&1 | tail -n 2); $(tail -n 3 "$dir/slurmd.log" 2>/dev/null)"
