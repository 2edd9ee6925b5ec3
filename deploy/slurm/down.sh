#!/usr/bin/env bash
# Stops exactly the Slurm and munge daemons that up.sh started (by the pids
# it recorded in $STATE/pids/), in reverse order, and nothing else. Leaves
# the packages, the key and the state directory (logs) in place.
set -euo pipefail

STATE=${LEAFMAGIC_SLURM_STATE:-/var/tmp/leafmagic-slurm}
PIDS=$STATE/pids

for name in slurmd slurmctld munged; do
  f=$PIDS/$name
  [ -f "$f" ] || continue
  pid=$(cat "$f")
  # Only a live process that is still that daemon (pids are reused).
  if kill -0 "$pid" 2>/dev/null && grep -q "$name" "/proc/$pid/cmdline" 2>/dev/null; then
    echo "slurm-down: stopping $name (pid $pid)" >&2
    kill -TERM "$pid" 2>/dev/null || true
    for _ in $(seq 100); do
      kill -0 "$pid" 2>/dev/null || break
      sleep 0.1
    done
    if kill -0 "$pid" 2>/dev/null; then
      echo "slurm-down: $name (pid $pid) ignored SIGTERM for 10 s; SIGKILL" >&2
      kill -KILL "$pid" 2>/dev/null || true
    fi
  fi
  rm -f "$f"
done
# The symlink up.sh made (never a real file someone else wrote).
if [ -L /etc/slurm/slurm.conf ] && [ "$(readlink /etc/slurm/slurm.conf)" = "$STATE/slurm.conf" ]; then
  rm -f /etc/slurm/slurm.conf
fi
