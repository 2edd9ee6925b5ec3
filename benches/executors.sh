#!/usr/bin/env bash
# Measures what the cost model of docs/guide/scale-out.md needs:
#   1. per-generation overhead of each executor: generations of 3 children
#      of 0.01 s falls (no work to speak of), median of generations 1-10;
#   2. time per leaf and the throughput of 1, 2, 4 shards: one generation of
#      200 leaves x 10 s run by `leafmagic shard` processes directly, and
#      whole breeds (generations 1-2, 180 children each) with the processes
#      and slurm executors;
#   3. the merge (reading the shards, the generation's files, the
#      checkpoint) at 200 and 10^4 leaves.
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
# Interleaved repetitions: the machine may be shared (or its host busy), so
# each repetition times 1, 2 and 4 shards back to back and the throughput
# ratio is taken within it; the table gives the medians.
REPS=${REPS:-9}
: >"$W/g200.times"
for ((r = 0; r < REPS; r++)); do
  echo "$(shards 1) $(shards 2) $(shards 4)" >>"$W/g200.times"
done
med() { sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }
t1=$(awk '{print $1}' "$W/g200.times" | med)
echo "| shards | wall (s), median of $REPS | throughput vs 1 shard, median of the per-repetition ratios |"
echo "|---|---|---|"
for c in 1 2 3; do
  n=$(( c == 3 ? 4 : c ))
  t=$(awk -v c="$c" '{print $c}' "$W/g200.times" | med)
  x=$(awk -v c="$c" '{print $1 / $c}' "$W/g200.times" | med)
  echo "| $n | $t | $(awk -v x="$x" 'BEGIN {printf "%.2fx", x}') |"
done
echo "time per leaf (1 shard, 1 thread): $(awk -v t="$t1" 'BEGIN {printf "%.2f ms", t / 200 * 1000}')"

echo
echo "## 2b. breeds of 200 x 10 s (fastest of generations 1-2 in 3 runs, 180 children each)"
FULL=(--population 200 --generations 3 --seconds 10)
run_full() { # the fastest generation 1 or 2 of 3 runs
  local name=$1 m b=1e9; shift
  for r in 1 2 3; do
    rm -rf "$W/full-$name"
    "$@" "${FULL[@]}" --out "$W/full-$name" >/dev/null 2>&1
    m=$(awk -F, 'NR > 1 && ($1 == 1 || $1 == 2) {print $2}' "$W/full-$name/timing.csv" | sort -g | head -n1)
    b=$(awk -v a="$b" -v m="$m" 'BEGIN {print (m < a) ? m : a}')
  done
  echo "| $name | $(awk -v b="$b" 'BEGIN {printf "%.3f", b}') s |"
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
echo "## 3. merge: \`leafmagic merge\` of generation 1 with its 2 shards already on disk (0.001 s falls)"
echo "| population | merge (s) |"
echo "|---|---|"
for pop in 200 10000; do
  d=$W/merge-$pop
  rm -rf "$d"
  "$B" breed --population "$pop" --generations 3 --seconds 0.001 --out "$d" --create-only >/dev/null
  for g in 0 1; do
    for i in 0 1; do "$B" shard "$d" --generation "$g" --index "$i" --count 2 --threads 1 >/dev/null & done
    wait
    t0=$(now)
    "$B" merge "$d" --generation "$g" --count 2 >/dev/null 2>&1
    t=$(since "$t0")
  done
  echo "| $pop | $t |"
done
echo
echo "work directory: $W"
