#!/usr/bin/env bash
# Do two leafmagic binaries compute the same things? Runs one set of commands
# with each (a drop, a small breed and its export in every format and its
# preview, a scene and its export, classify and describe of a fall) in
# folders of their own, then compares every file byte for byte, timing
# files aside (timing.csv, and the lines of JSON, CSV or tables that carry
# wall-clock seconds, and each side's folder name, are not compared: see
# `normalise`). Prints each file
# that differs and exits 1 if any does.
#
#   bash .ci/same-outputs.sh OLD_BINARY NEW_BINARY
#
# The two binaries run from the repository's root (scenes/, prototypes/).
set -euo pipefail
if [ $# -ne 2 ]; then
  echo "usage: $0 OLD_BINARY NEW_BINARY" >&2
  exit 2
fi
old=$(realpath "$1")
new=$(realpath "$2")
cd "$(dirname "$0")/.."
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

run_all() {
  local bin=$1 out=$2
  mkdir -p "$out"
  "$bin" drop a --seconds 3 --out "$out/drop-a.csv" --json >"$out/drop-a.json"
  "$bin" drop b --seconds 3 --tilt 30,5 --json >"$out/drop-b.json"
  "$bin" breed --population 12 --generations 2 --seconds 3 --threads 1 --out "$out/breed" >"$out/breed.txt" 2>&1
  for f in glb usd abc pc2; do
    "$bin" export "$out/breed" --top 2 --format "$f" --out "$out/export-$f" >/dev/null 2>&1
  done
  "$bin" preview "$out/breed" >/dev/null 2>&1
  "$bin" scene scenes/inhale.toml --out "$out/scene" --export glb --json >"$out/scene.json" 2>/dev/null
  "$bin" classify "$out/drop-a.csv" --json >"$out/classify.json"
  "$bin" describe "$out/drop-a.csv" --json >"$out/describe.json"
  "$bin" check a >"$out/check.txt"
}

# Wall-clock fields vary from run to run: drop them before comparing.
# Each side's own folder name is replaced too, as files that name a path
# name theirs.
normalise() {
  sed -E "s#$work/(old|new)#OUT#g" "$1" |
    sed -E 's/"(wall|elapsed|cpu)[a-z_]*": *[0-9.eE+-]+/"\1": T/g; s/in [0-9.]+ (s|ms)\b/in T/g; s/[0-9.]+ s wall/T wall/g'
}

echo "== running $old"
run_all "$old" "$work/old"
echo "== running $new"
run_all "$new" "$work/new"

differ=0
while IFS= read -r rel; do
  case "$rel" in */timing.csv|timing.csv) continue ;; esac
  a="$work/old/$rel"; b="$work/new/$rel"
  if [ ! -e "$b" ]; then
    echo "only in old: $rel"; differ=1; continue
  fi
  if ! cmp -s "$a" "$b" && ! cmp -s <(normalise "$a") <(normalise "$b"); then
    echo "differs: $rel"; differ=1
  fi
done < <(cd "$work/old" && find . -type f | sed 's|^\./||' | sort)
while IFS= read -r rel; do
  [ -e "$work/old/$rel" ] || { echo "only in new: $rel"; differ=1; }
done < <(cd "$work/new" && find . -type f | sed 's|^\./||' | sort)
if [ "$differ" = 0 ]; then
  echo "same outputs: every file identical ($(cd "$work/new" && find . -type f | wc -l) files)"
fi
exit "$differ"
