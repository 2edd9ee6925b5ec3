#!/usr/bin/env bash
# Brings up a single-node Slurm cluster on this Debian machine (run as root):
# installs slurmd, slurmctld, slurm-client and munge if missing, writes a
# munge key (if the package made none) and a slurm.conf for one node with
# this machine's cores, starts munged, slurmctld and slurmd, and waits until
# `sinfo` shows the node idle. Idempotent: daemons it started before and that
# still run are left alone. It records the pid of every daemon it starts in
# $STATE/pids/, so that down.sh stops exactly those (and nothing else).
#
# State (configs, logs, spool, pids): $LEAFMAGIC_SLURM_STATE, default
# /var/tmp/leafmagic-slurm. /etc/slurm/slurm.conf is made a symlink to the
# generated file unless a real file is already there, so that plain `sinfo`,
# `srun`, `sbatch` work; otherwise export SLURM_CONF=$STATE/slurm.conf.
set -euo pipefail

STATE=${LEAFMAGIC_SLURM_STATE:-/var/tmp/leafmagic-slurm}
CONF=$STATE/slurm.conf
PIDS=$STATE/pids

say() { echo "slurm-up: $*" >&2; }
die() { say "error: $*"; exit 1; }

[ "$(id -u)" = 0 ] || die "run as root (installs packages and starts daemons)"

running() { # running NAME: true when the daemon we recorded is alive
  local f=$PIDS/$1
  [ -f "$f" ] && kill -0 "$(cat "$f")" 2>/dev/null &&
    grep -q "$1" "/proc/$(cat "$f")/cmdline" 2>/dev/null
}

# 1. Packages (about 10 s on a Debian 12 VM with a warm mirror).
need=()
for p in slurmd slurmctld slurm-client munge; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || need+=("$p")
done
if [ ${#need[@]} -gt 0 ]; then
  say "installing ${need[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get install -y -q --no-install-recommends "${need[@]}" >/dev/null 2>&1 || {
    apt-get update -q >/dev/null
    apt-get install -y -q --no-install-recommends "${need[@]}" >/dev/null
  }
fi

mkdir -p "$STATE"/{ctld,spool,log} "$PIDS"

# 2. Munge: a key (the package usually creates one), and the daemon.
if [ ! -s /etc/munge/munge.key ]; then
  say "creating a munge key"
  mkdir -p /etc/munge
  dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key status=none
fi
chown munge:munge /etc/munge/munge.key 2>/dev/null || true
chmod 400 /etc/munge/munge.key
mkdir -p /run/munge /var/lib/munge /var/log/munge
chown munge:munge /run/munge /var/lib/munge /var/log/munge 2>/dev/null || true
if munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
  running munged || say "munged already running (not ours: down.sh will leave it)"
else
  say "starting munged"
  if id munge >/dev/null 2>&1; then
    # setpriv execs (no intermediate process), so $! is munged's own pid.
    setsid setpriv --reuid=munge --regid=munge --init-groups munged -F \
      >"$STATE/log/munged.log" 2>&1 &
  else
    setsid munged -F --force >"$STATE/log/munged.log" 2>&1 &
  fi
  echo $! >"$PIDS/munged"
  for _ in $(seq 100); do
    munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break
    sleep 0.1
  done
  munge -n | unmunge >/dev/null || die "munged did not start; see $STATE/log/munged.log"
fi

# 3. slurm.conf: one node, this machine's cores and memory.
host=$(hostname -s)
cpus=$(nproc)
mem_mb=$(awk '/MemTotal/ {print int($2 / 1024 * 0.9)}' /proc/meminfo)
cat >"$CONF.new" <<CONF
# Written by leafmagic deploy/slurm/up.sh: a single-node test cluster.
ClusterName=leafmagic
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
MpiDefault=none
# No cgroups needed (containers, CI VMs): track processes by parent pid and
# bind no tasks.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
# FIFO, scheduled at submit: the shortest path from sbatch to a running job.
SchedulerType=sched/builtin
# Schedule pending jobs (array elements waiting for a CPU) as soon as one
# ends, not at the default batch_sched_delay of 3 s.
SchedulerParameters=batch_sched_delay=0
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
StateSaveLocation=$STATE/ctld
SlurmdSpoolDir=$STATE/spool
SlurmctldPidFile=$STATE/slurmctld.pid
SlurmdPidFile=$STATE/slurmd.pid
SlurmctldLogFile=$STATE/log/slurmctld.log
SlurmdLogFile=$STATE/log/slurmd.log
SlurmctldPort=6817
SlurmdPort=6818
# Let an array or a rerun start at once rather than at the next tick.
MinJobAge=30
KillWait=5
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP OverSubscribe=NO
CONF
changed=no
if [ -f "$CONF" ] && cmp -s "$CONF" "$CONF.new"; then
  rm "$CONF.new"
else
  mv "$CONF.new" "$CONF"
  changed=yes
fi
mkdir -p /etc/slurm
if [ -L /etc/slurm/slurm.conf ] || [ ! -e /etc/slurm/slurm.conf ]; then
  ln -sfn "$CONF" /etc/slurm/slurm.conf
elif ! cmp -s /etc/slurm/slurm.conf "$CONF"; then
  say "/etc/slurm/slurm.conf is someone else's file: export SLURM_CONF=$CONF"
fi
export SLURM_CONF=$CONF

# 4. The daemons, in the foreground of a process we own, so $! is their pid.
if ! running slurmctld; then
  say "starting slurmctld"
  setsid slurmctld -D -i -f "$CONF" >>"$STATE/log/slurmctld.out" 2>&1 &
  echo $! >"$PIDS/slurmctld"
fi
if ! running slurmd; then
  say "starting slurmd"
  setsid slurmd -D -f "$CONF" >>"$STATE/log/slurmd.out" 2>&1 &
  echo $! >"$PIDS/slurmd"
fi

# A cluster already up from an older slurm.conf takes the new one.
if [ "$changed" = yes ] && running slurmctld && sinfo -h >/dev/null 2>&1; then
  say "slurm.conf changed: scontrol reconfigure"
  scontrol reconfigure
fi

# 5. Wait for the node.
for _ in $(seq 300); do
  state=$(sinfo -h -N -o '%T' 2>/dev/null | head -n1 || true)
  case "$state" in
    idle | mixed | allocated) break ;;
  esac
  sleep 0.2
done
case "$state" in
  idle | mixed | allocated) ;;
  *) die "node not idle after 60 s (state '${state:-none}'); logs in $STATE/log" ;;
esac
say "up: node $host, $cpus CPUs, state $state (SLURM_CONF=$CONF)"
