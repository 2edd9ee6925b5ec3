#!/usr/bin/env bash
# Runs criterion bench binaries in alternation (A B A B ..., the order swapped
# every round), so that a neighbour's load or a slow spell of the machine falls
# on every binary alike, and reports per benchmark the median over rounds of
# criterion's own median, the spread (min–max) and the ratio to the first
# binary. With --ratio NUM DEN (repeatable) it also reports, per binary, the
# ratio of two benchmarks taken round by round (for aero_laws: the unsteady law's drop over
# the linear law's, the figure issue 17 bounds). Machines of one kind differ
# by 2x and are noisy: only ratios measured in one run mean anything.
#
#   bash benches/ab-criterion.sh [--rounds N] [--filter F] [--ratio NUM DEN]... BENCH_BINARY...
#
# A bench binary is what `cargo bench --bench NAME --no-run` builds (it prints
# its path); copy it aside before building the other revision, e.g.
#
#   git worktree add /tmp/old OLD_REV
#   (cd /tmp/old && CARGO_TARGET_DIR=/tmp/old-target cargo bench --bench aero_laws --no-run)
#   cargo bench --bench aero_laws --no-run
#   bash benches/ab-criterion.sh --rounds 7 \
#     --ratio aero_laws/unsteady_drop_10s aero_laws/linear_drop_10s \
#     /tmp/old-target/release/deps/aero_laws-HASH target/release/deps/aero_laws-HASH
#
# Each round gives criterion 1 s of warm-up and 2 s of measurement per
# benchmark (--measurement-time 2 --warm-up-time 1).
set -euo pipefail
rounds=7
filter=""
ratios=""
while [ $# -gt 0 ]; do
  case "$1" in
    --rounds) rounds=$2; shift 2 ;;
    --filter) filter=$2; shift 2 ;;
    --ratio) ratios="$ratios $2 $3"; shift 3 ;;
    -*) echo "unknown option $1" >&2; exit 2 ;;
    *) break ;;
  esac
done
if [ $# -lt 1 ]; then
  echo "usage: $0 [--rounds N] [--filter F] [--ratio NUM DEN]... BENCH_BINARY..." >&2
  exit 2
fi
bins=()
for b in "$@"; do
  if [ ! -x "$b" ]; then
    echo "error: $b: not an executable bench binary" >&2
    exit 2
  fi
  bins+=("$(realpath "$b")")
done
python3 - "$rounds" "$filter" "$ratios" "${bins[@]}" <<'EOF'
import re, statistics, subprocess, sys
rounds, flt, pairs = int(sys.argv[1]), sys.argv[2], sys.argv[3].split()
bins = sys.argv[4:]
unit = {"ns": 1e-9, "µs": 1e-6, "us": 1e-6, "ms": 1e-3, "s": 1.0}
# times[bin][bench] = [seconds per round]
times = {b: {} for b in bins}
for r in range(rounds):
    order = bins if r % 2 == 0 else list(reversed(bins))
    for b in order:
        cmd = [b, "--bench", "--measurement-time", "2", "--warm-up-time", "1", "--noplot"]
        if flt:
            cmd.append(flt)
        out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
        bench = None
        for line in out.splitlines():
            m = re.match(r"^(\S+/\S+)\s*$", line) or re.match(r"^(\S+/\S+)\s+time:", line)
            if m:
                bench = m.group(1)
            m = re.search(r"time:\s+\[\S+ \S+ (\S+) (\S+) \S+ \S+\]", line)
            if m and bench:
                times[b].setdefault(bench, []).append(float(m.group(1)) * unit[m.group(2)])
                bench = None
names = sorted({n for t in times.values() for n in t})
if not names:
    sys.exit("error: no criterion results read (wrong binary or filter?)")
fmt = lambda v: f"{statistics.median(v) * 1e3:.3f} ms ({min(v) * 1e3:.3f}–{max(v) * 1e3:.3f})"
print(f"{rounds} alternated rounds; criterion medians per round: median over rounds (min–max)")
for n in names:
    print(n)
    base = statistics.median(times[bins[0]].get(n, [float("nan")]))
    for b in bins:
        v = times[b].get(n)
        if not v:
            print(f"  {b}: not run")
            continue
        print(f"  {b}: {fmt(v)}  ×{statistics.median(v) / base:.3f} of the first")
for num, den in zip(pairs[0::2], pairs[1::2]):
    print(f"{num} / {den}, round by round: median (min–max)")
    for b in bins:
        a, d = times[b].get(num), times[b].get(den)
        if not a or not d:
            print(f"  {b}: not both run")
            continue
        ratios = [x / y for x, y in zip(a, d)]
        print(f"  {b}: {statistics.median(ratios):.3f} ({min(ratios):.3f}–{max(ratios):.3f})")
EOF
