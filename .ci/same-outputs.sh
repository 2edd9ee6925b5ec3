#!/usr/bin/env bash
# Runs the same set of commands with two leafmagic binaries and diffs what they
# write, ignoring only what measures time. Used to show that a change which
# should not alter what the tool computes (a restructure, a refactor) does not.
#
#   bash .ci/same-outputs.sh OLD_BINARY NEW_BINARY [WORK_DIR]
#
# Compared, byte for byte after dropping timing fields:
#   - the default breed's run directory (all but timing.csv), and a --like run;
#   - `drop a|b --json` and `drop --out/--particles` CSVs, tilted and RK4 too;
#   - `check a|b --json`, `check a --stress --json`;
#   - every scene in scenes/ (all CSVs, summary.toml), with --export glb and pc2;
#   - `accuracy`'s CSV (without the wall_s column) and SVG;
#   - `export --format glb|pc2` of the breed, `preview` of the run and a scene;
#   - `classify`, `compare` and `describe`-like output of recorded falls.
# Exit status 0 when everything is identical, 1 otherwise (the differing
# files are listed).
set -uo pipefail
if [ $# -lt 2 ]; then
  echo "usage: $0 OLD_BINARY NEW_BINARY [WORK_DIR]" >&2
  exit 2
fi
old=$(realpath "$1")
new=$(realpath "$2")
repo=$(cd "$(dirname "$0")/.." && pwd)
work=${3:-$(mktemp -d)}
mkdir -p "$work"
work=$(realpath "$work")

# Fields that measure time, not what was computed.
strip_timing() {
  sed -E -e '/"?(wall_s|wall|wall_per_simulated_s|elapsed_s|cpu_s)"? *[:=]/d' \
         -e 's/≈ [0-9.]+ (s|ms) \(extrap/≈ <t> (extrap/g' \
         -e 's/in [0-9.]+ ?(s|ms)\b/in <t>/g' \
         -e 's/[0-9.e+-]+ wall s per simulated s/<t> wall s per simulated s/g' \
         -e 's/finished in +[0-9.]+ s/finished in <t>/'
}

run_set() {
  local bin=$1 out=$2
  rm -rf "$out"
  mkdir -p "$out"
  cd "$out" || exit 2
  # Breeding: the default run, and one toward an example fall.
  "$bin" breed --out breed >/dev/null 2>&1
  rm -f breed/timing.csv
  "$bin" drop "$repo/tests/fixtures/a-tumbler.toml" --out tumbler.csv >/dev/null 2>&1
  "$bin" breed --like tumbler.csv --population 30 --generations 3 --out like >/dev/null 2>&1
  rm -f like/timing.csv
  # Drops.
  for leaf in a b "$repo/tests/fixtures/a-spinner.toml" "$repo/tests/fixtures/a-lilter.toml"; do
    tag=$(basename "$leaf" .toml)
    "$bin" drop "$leaf" --json 2>&1 | strip_timing >"drop-$tag.json"
    "$bin" drop "$leaf" --out "drop-$tag.csv" --particles "drop-$tag-particles.csv" 2>&1 |
      strip_timing >"drop-$tag.txt"
  done
  "$bin" drop a --integrator rk4 --tilt 30,5 --seconds 3 --json 2>&1 | strip_timing >drop-rk4.json
  "$bin" drop a --integrator implicit --seconds 2 --json 2>&1 | strip_timing >drop-implicit.json
  "$bin" drop a --integrator euler --dt 0.01 --seconds 1 2>&1 | strip_timing >drop-diverges.txt
  # Stability.
  "$bin" check a --json >check-a.json 2>&1
  "$bin" check b --json >check-b.json 2>&1
  "$bin" check a --stress --json 2>&1 | strip_timing >stress.json
  # Scenes.
  for scene in "$repo"/scenes/*.toml; do
    name=$(basename "$scene" .toml)
    "$bin" scene "$scene" --out "scene-$name" --json 2>&1 | strip_timing >"scene-$name.json"
  done
  "$bin" scene "$repo/scenes/inhale.toml" --out export-glb --export glb >/dev/null 2>&1
  "$bin" scene "$repo/scenes/swings.toml" --out export-pc2 --export pc2 >/dev/null 2>&1
  # Accuracy (the wall_s column dropped).
  # The "cheapest run to error ≤ tol" table picks runs by measured wall
  # time, so it may differ from run to run; the rest must not.
  "$bin" accuracy --out acc 2>&1 | strip_timing |
    awk '/cheapest run to error/ {skip = 1} skip && /^$/ {skip = 0} !skip' >acc.txt
  if [ -f acc/accuracy.csv ]; then
    python3 - acc/accuracy.csv <<'EOF'
import csv, sys
rows = list(csv.reader(open(sys.argv[1])))
keep = [i for i, h in enumerate(rows[0]) if h != "wall_s"]
with open(sys.argv[1] + ".stripped", "w") as f:
    for r in rows:
        f.write(",".join(r[i] for i in keep) + "\n")
EOF
    rm acc/accuracy.csv acc/accuracy.svg # the SVG plots wall time
  fi
  # Export and preview.
  "$bin" export breed --top 3 --out export-glb-breed --format glb 2>&1 | strip_timing >export-glb.txt
  "$bin" export breed --top 3 --out export-pc2-breed --format pc2 2>&1 | strip_timing >export-pc2.txt
  "$bin" preview breed --out preview-breed.html 2>&1 | strip_timing >preview-breed.txt
  "$bin" preview scene-inhale --out preview-inhale.html 2>&1 | strip_timing >preview-inhale.txt
  # Classification of recorded falls.
  "$bin" classify drop-a-spinner.csv --json >classify-spinner.json 2>&1
  "$bin" classify tumbler.csv >classify-tumbler.txt 2>&1
  "$bin" compare tumbler.csv drop-a-lilter.csv --json >compare.json 2>&1
  # Refusals: the message of each error path.
  {
    "$bin" drop a --seconds=-1
    "$bin" drop a --dt 0
    "$bin" drop a --dt 1e-12 --seconds 100
    "$bin" drop a --integrator nonsense
    "$bin" breed --population 1 --out refused-1
    "$bin" breed --target-features wobble=1 --out refused-2
    "$bin" breed --target undetermined --out refused-3
    "$bin" shard breed --generation 8
    env -u SLURM_PROCID -u SLURM_ARRAY_TASK_ID "$bin" shard breed --generation 8 --count 2
    "$bin" check a --stress --explicit sometimes
    "$bin" export breed --top 1 --out refused-4 --format fbx
    sed 's/^frame_rate = .*/frame_rate = 1e-320/' "$repo/scenes/hover.toml" >bad-rate.toml
    "$bin" scene bad-rate.toml --out refused-5
    sed 's/^duration = .*/duration = 1e12/' "$repo/scenes/hover.toml" >bad-duration.toml
    "$bin" scene bad-duration.toml --out refused-6
    printf 't,x,y,z\n0,0,0,0\n' >short.csv
    "$bin" classify short.csv
  } >refusals.txt 2>&1
  # Scene summaries carry wall times.
  for f in */summary.toml; do
    strip_timing <"$f" >"$f.stripped" && rm "$f"
  done
  cd - >/dev/null || exit 2
}

echo "old: $old"
echo "new: $new"
echo "work: $work"
# Both run under the name `leafmagic` (clap prints the program's name).
mkdir -p "$work/bin-old" "$work/bin-new"
cp "$old" "$work/bin-old/leafmagic"
cp "$new" "$work/bin-new/leafmagic"
run_set "$work/bin-old/leafmagic" "$work/old"
run_set "$work/bin-new/leafmagic" "$work/new"
# The run directories name themselves and the example; they are in both.
if diff -r "$work/old" "$work/new" >"$work/diff.txt"; then
  echo "identical: $(find "$work/old" -type f | wc -l) files, $(du -sh "$work/old" | cut -f1)"
  exit 0
else
  echo "DIFFERENT:"
  grep -E '^(Only in|diff -r|Binary files)' "$work/diff.txt" | head -40
  exit 1
fi
