#!/usr/bin/env bash
# Measures what the README's cost model ("Beyond one machine") needs:
#   1. per-generation overhead of each executor: generations of 3 children
#      of 0.01 s falls (no work to speak of), median of generations 1-10;
#   2. time per leaf and the throughput of 1, 2, 4 shards: one generation of
#      200 leaves x 10 s run by `leafmagic shard` processes directly, and
#      whole breeds (median of generations 1-2, 180 children each) with the
#      processes and slurm executors;
#   3. bookkeeping (plan, merge, files, checkpoint) of a 10^4 population.
# Usage: cargo build --release && bash benches/executors.sh [WORK_DIR]
# The Slurm rows need a cluster (deploy/slurm/up.sh); without sinfo they are
# left out. Run it on an otherwise idle machine: it times wall clock.
set -euo pipefail
cd "$(dirname "$0")/.."
B=$PWD/target/release/leafmagic
[ -x "$B" ] || { echo "build first: cargo build --release" >&2; exit 1; }
W=${1:-$(mktemp -d /tmp/leafmagic-bench.XXXXXX)}
mkdir -p "$W"
slurm=no
sinfo -h >/dev/null 2>&1 && slurm=yes

# median wall seconds of generations FROM..TO of a run's timing.csv
median() {
  awk -F, -v a="$2" -v b="$3" 'NR > 1 && $1 >= a && $1 <= b {print $2}' "$1/timing.csv" |
    sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'
}
ms() { awk -v s="$1" 'BEGIN {printf "%.1f", s * 1000}'; }
now() { date +%s.%N; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN {printf "%.3f", b - a}'; }

echo "machine: $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg), slurm: $slurm"
echo
echo "## 1. per-generation overhead (population 4, 0.01 s falls; median of generations 1-10)"
TINY=(--population 4 --generations 11 --seconds 0.01)
run_tiny() { # name, then breed arguments
  local name=$1; shift
  rm -rf "$W/tiny-$name"
  "$@" "${TINY[@]}" --out "$W/tiny-$name" >/dev/null 2>&1
  echo "| $name | $(ms "$(median "$W/tiny-$name" 1 10)") ms |"
}
echo "| executor | per generation |"
echo "|---|---|"
run_tiny local "$B" breed --threads 1
for s in 1 2 4; do run_tiny "processes-$s" "$B" breed --executor processes --shards "$s" --threads 1; done
if [ $slurm = yes ]; then
  for s in 1 2 4; do run_tiny "slurm-step-$s" salloc -Q -n 2 "$B" breed --executor slurm --shards "$s" --threads 1; done
  run_tiny slurm-array-2 "$B" breed --executor slurm --shards 2 --threads 1
fi

echo
echo "## 2a. one generation of 200 leaves x 10 s, by shard processes (1 thread each)"
# A run directory before generation 0: run.toml only.
rm -rf "$W/g200"
"$B" breed --population 200 --generations 2 --seconds 10 --out "$W/g200" >/dev/null
find "$W/g200" -mindepth 1 ! -name run.toml -exec rm -rf {} +
shards() { # count: all shards of generation 0 at once, wall seconds
  local n=$1 t0 pids=()
  t0=$(now)
  for ((i = 0; i < n; i++)); do
    "$B" shard "$W/g200" --generation 0 --index "$i" --count "$n" --threads 1 >/dev/null &
    pids+=($!)
  done
  wait "${pids[@]}"
  since "$t0"
}
t1=$(shards 1); t2=$(shards 2); t4=$(shards 4)
echo "| shards | wall (s) | throughput vs 1 shard |"
echo "|---|---|---|"
for p in "1 $t1" "2 $t2" "4 $t4"; do
  set -- $p
  echo "| $1 | $2 | $(awk -v a="$t1" -v b="$2" 'BEGIN {printf "%.2fx", a / b}') |"
done
echo "time per leaf (1 shard, 1 thread): $(awk -v t="$t1" 'BEGIN {printf "%.2f ms", t / 200 * 1000}')"

echo
echo "## 2b. breeds of 200 x 10 s (median of generations 1-2, 180 children each)"
FULL=(--population 200 --generations 3 --seconds 10)
run_full() {
  local name=$1; shift
  rm -rf "$W/full-$name"
  "$@" "${FULL[@]}" --out "$W/full-$name" >/dev/null 2>&1
  echo "| $name | $(median "$W/full-$name" 1 2) s |"
}
echo "| executor | per generation |"
echo "|---|---|"
run_full local-1-thread "$B" breed --threads 1
run_full local-2-threads "$B" breed --threads 2
for s in 1 2 4; do run_full "processes-$s" "$B" breed --executor processes --shards "$s" --threads 1; done
if [ $slurm = yes ]; then
  for s in 1 2 4; do run_full "slurm-step-$s" salloc -Q -n 2 "$B" breed --executor slurm --shards "$s" --threads 1; done
fi

echo
echo "## 3. bookkeeping at 10^4 leaves (0.001 s falls; generation 1)"
BIG=(--population 10000 --generations 2 --seconds 0.001)
for e in "local --threads 2" "processes --executor processes --shards 2 --threads 1"; do
  set -- $e
  name=$1; shift
  rm -rf "$W/big-$name"
  "$B" breed "${BIG[@]}" "$@" --out "$W/big-$name" >/dev/null 2>&1
  echo "| $name | $(median "$W/big-$name" 1 1) s |"
done
echo
echo "work directory: $W"
