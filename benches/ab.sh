#!/usr/bin/env bash
# Times two leafmagic binaries side by side on the same work, interleaved
# (A B A B ...), so that a neighbour's load or a slow spell of the machine
# falls on both alike; reports the median, the spread (min–max) and the ratio
# of medians per workload. Machines of one kind differ by 2x and are noisy:
# only ratios measured in one run mean anything.
#
#   bash benches/ab.sh OLD_BINARY NEW_BINARY [ROUNDS]
#
# Workloads: a 100 s drop of prototype A (stepping dominates), the default
# breed (100 leaves x 8 generations of 10 s falls, on all cores), and a
# 1 s drop repeated (start-up and choosing the step).
set -euo pipefail
if [ $# -lt 2 ]; then
  echo "usage: $0 OLD_BINARY NEW_BINARY [ROUNDS]" >&2
  exit 2
fi
old=$(realpath "$1")
new=$(realpath "$2")
rounds=${3:-7}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 - "$old" "$new" "$rounds" "$work" <<'EOF'
import statistics, subprocess, sys, time
old, new, rounds, work = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
loads = {
    "drop a, 100 s": lambda b, k: [b, "drop", "a", "--seconds", "100", "--json"],
    "default breed": lambda b, k: [b, "breed", "--out", f"{work}/breed-{k}"],
    "drop a, 1 s": lambda b, k: [b, "drop", "a", "--seconds", "1", "--json"],
}
times = {name: {"old": [], "new": []} for name in loads}
for r in range(rounds):
    for name, cmd in loads.items():
        for tag, b in (("old", old), ("new", new)) if r % 2 == 0 else (("new", new), ("old", old)):
            t = time.perf_counter()
            subprocess.run(cmd(b, f"{tag}{r}"), check=True, stdout=subprocess.DEVNULL)
            times[name][tag].append(time.perf_counter() - t)
            subprocess.run(["rm", "-rf", f"{work}/breed-{tag}{r}"])
print(f"{rounds} interleaved rounds; wall seconds: median (min–max)")
print(f"{'workload':<16} {'old':>22} {'new':>22}  new/old")
for name, t in times.items():
    mo, mn = statistics.median(t["old"]), statistics.median(t["new"])
    fmt = lambda v, m: f"{m:.4f} ({min(v):.4f}–{max(v):.4f})"
    print(f"{name:<16} {fmt(t['old'], mo):>22} {fmt(t['new'], mn):>22}  {mn / mo:.3f}")
EOF
