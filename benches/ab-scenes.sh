#!/usr/bin/env bash
# Times two leafmagic binaries side by side on scenes, interleaved (A B, then
# B A, ...), so that a neighbour's load falls on both alike. Each run's
# stepping-loop time is read from `scene --json` (`wall_s`), so loading and
# writing do not dilute the difference. Reports per scene the median and
# spread (min–max) of each binary, and the median and spread of the ratios
# new/old of the runs made side by side.
#
#   bash benches/ab-scenes.sh OLD_BINARY NEW_BINARY [ROUNDS] [SCENE.toml ...]
#
# Default scenes: benches/hundred-leaves.toml, scenes/inhale.toml,
# scenes/shockwave.toml, scenes/ground-blow.toml.
set -euo pipefail
if [ $# -lt 2 ]; then
  echo "usage: $0 OLD_BINARY NEW_BINARY [ROUNDS] [SCENE.toml ...]" >&2
  exit 2
fi
old=$(realpath "$1")
new=$(realpath "$2")
rounds=${3:-7}
shift $(($# < 3 ? $# : 3))
repo=$(cd "$(dirname "$0")/.." && pwd)
if [ $# -eq 0 ]; then
  set -- "$repo/benches/hundred-leaves.toml" "$repo/scenes/inhale.toml" \
    "$repo/scenes/shockwave.toml" "$repo/scenes/ground-blow.toml"
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 - "$old" "$new" "$rounds" "$work" "$@" <<'PY'
import json, statistics, subprocess, sys
old, new, rounds, work = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
scenes = sys.argv[5:]
def wall(b, scene, k):
    out = subprocess.run([b, "scene", scene, "--json", "--out", f"{work}/{k}"],
                         check=True, capture_output=True, text=True).stdout
    subprocess.run(["rm", "-rf", f"{work}/{k}"])
    doc = json.loads(out)
    return doc["wall_s"] if "wall_s" in doc else doc["stats"]["wall_s"]
print(f"{rounds} interleaved rounds; stepping-loop wall seconds: median (min–max); new/old per round")
print(f"{'scene':<16} {'old':>24} {'new':>24} {'new/old median (min–max)':>28}")
for scene in scenes:
    t = {"old": [], "new": []}
    for r in range(rounds):
        order = (("old", old), ("new", new)) if r % 2 == 0 else (("new", new), ("old", old))
        for tag, b in order:
            t[tag].append(wall(b, scene, f"{tag}{r}"))
    ratios = [n / o for n, o in zip(t["new"], t["old"])]
    fmt = lambda v: f"{statistics.median(v):.4f} ({min(v):.4f}–{max(v):.4f})"
    name = scene.rsplit("/", 1)[-1].removesuffix(".toml")
    print(f"{name:<16} {fmt(t['old']):>24} {fmt(t['new']):>24} "
          f"{statistics.median(ratios):>10.3f} ({min(ratios):.3f}–{max(ratios):.3f})")
PY
