#!/usr/bin/env bash
# Does starting from an earlier run's archive find a rare class sooner?
# For each seed: a run toward floaters from prototype A keeping an archive,
# then two runs toward lilters (rare around A): from the prototype alone, and
# --start-from the archive run. Prints, per run, the generation that first
# held a lilter, the lilters and the best score at each generation.
#
#   bash benches/start-from.sh [BINARY] [SEEDS] [OUT_DIR]
set -euo pipefail
bin=$(realpath "${1:-target/release/leafmagic}")
seeds=${2:-3}
out=${3:-$(mktemp -d)}
mkdir -p "$out"
common=(--prototype a --population 40 --generations 5)
for s in $(seq 1 "$seeds"); do
  "$bin" breed "${common[@]}" --target floater --archive --seed $((100 + s)) --out "$out/archive-$s" >/dev/null 2>&1
  "$bin" breed "${common[@]}" --target lilter --seed "$s" --out "$out/fresh-$s" >/dev/null 2>&1
  "$bin" breed "${common[@]}" --target lilter --seed "$s" --start-from "$out/archive-$s" --out "$out/start-$s" >/dev/null 2>&1
done
python3 - "$out" "$seeds" <<'PY'
import csv, sys
out, seeds = sys.argv[1], int(sys.argv[2])
print("| seed | start | archive cells | first generation with a lilter | lilters per generation | best score per generation |")
print("|---|---|---|---|---|---|")
for s in range(1, seeds + 1):
    cells = sum(1 for l in open(f"{out}/archive-{s}/archive.csv") if l[0].isdigit())
    for kind in ("fresh", "start"):
        rows = list(csv.DictReader(l for l in open(f"{out}/{kind}-{s}/generations.csv") if not l.startswith("#")))
        lil = [int(r["lilter"]) for r in rows]
        first = next((int(r["generation"]) for r, n in zip(rows, lil) if n > 0), "none")
        best = " ".join(f"{float(r['best_score']):.3f}" for r in rows)
        print(f"| {s} | {kind} | {cells if kind == 'start' else '—'} | {first} | {' '.join(map(str, lil))} | {best} |")
PY
