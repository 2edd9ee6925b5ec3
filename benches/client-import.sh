#!/usr/bin/env bash
# How long clients take to import leafmagic's exports, measured in the clients
# themselves (issue 21): Blender 4.5 (PyPI bpy) importing the 100-leaf, 10 s
# scene (benches/hundred-leaves.toml) as .glb, .usda, .usdc and PC2 + OBJ, and
# three.js (npm) in headless Chromium (Debian's) loading the same .glb and a
# 120 s, 30 fps fall of one leaf. Each Blender import runs RUNS times in fresh
# processes (median, min, max); each also reports what Blender built and the
# vertex positions it evaluates, which are checked against the PC2 cache (the
# simulation's vertices, f32). Installs bpy and three.js under target/ and skips
# a client with a message where it cannot.
#   bash benches/client-import.sh [RUNS]       (default 3)
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-3}
bin=target/release/leafmagic
[ -x "$bin" ] || cargo build --release --quiet
work=target/client-import
rm -rf "$work"; mkdir -p "$work"
echo "== exports of benches/hundred-leaves.toml (100 leaves, 10 s, 30 fps)"
for f in glb usd pc2; do
  "$bin" scene benches/hundred-leaves.toml --export "$f" --out "$work/scene-$f" | grep -E '^export'
done
mkdir -p "$work/pc2"; cp "$work"/scene-pc2/*.pc2 "$work"/scene-pc2/*.obj "$work/pc2/"
cat > "$work/long.toml" <<'TOML'
name = "long-fall"
description = "one leaf falling for 120 s, for the three.js test"
duration = 120.0
frame_rate = 30
[[leaf]]
name = "leaf"
leaf = "a"
position = [0.0, 0.0, 100.0]
tilt_deg = 10.0
TOML
"$bin" scene "$work/long.toml" --export glb --out "$work/long" | grep -E '^export'

venv=target/venv-tools
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c 'import bpy' 2>/dev/null; then
  python3 -m venv "$venv" && "$venv/bin/pip" install --quiet 'bpy==4.5.*' usd-core ||
    echo "SKIPPED Blender: pip install bpy failed"
fi
if "$venv/bin/python" -c 'import pxr.Sdf' 2>/dev/null; then
  # The binary encoding, converted by Pixar's library from leafmagic's text.
  "$venv/bin/python" -c "from pxr import Sdf; Sdf.Layer.FindOrOpen('$work/scene-usd/hundred-leaves.usda').Export('$work/scene-usd/hundred-leaves.usdc')"
  ls -l "$work"/scene-usd/hundred-leaves.usd? | awk '{print "usd file: " $5 " bytes " $NF}'
fi
if "$venv/bin/python" -c 'import bpy' 2>/dev/null; then
  echo "== Blender $("$venv/bin/python" -c 'import bpy; print(bpy.app.version_string)') import, $runs runs each (fresh process)"
  for f in "$work/scene-glb/hundred-leaves.glb" "$work/scene-usd/hundred-leaves.usda" \
           "$work/scene-usd/hundred-leaves.usdc" "$work/pc2.pc2dir"; do
    for r in $(seq "$runs"); do
      save=""; [ "$r" = 1 ] && save="--save $work/$(basename "$f").blend"
      "$venv/bin/python" benches/client-import/blender_import.py "$f" --frames 0,150,300 $save \
        2>/dev/null | grep '^RESULT ' | sed 's/^RESULT //' > "$work/blender-$(basename "$f")-$r.json"
    done
  done
  "$venv/bin/python" benches/client-import/summarise.py blender "$work" "$runs"
fi

three=target/tmp/threejs
if command -v node >/dev/null && [ -x /usr/bin/chromium ]; then
  if [ ! -d "$three/node_modules/three" ] || [ ! -d "$three/node_modules/playwright-core" ]; then
    mkdir -p "$three" && (cd "$three" && npm install --no-audit --no-fund --silent three@0.187.0 playwright-core@1.65.1) ||
      echo "SKIPPED three.js: npm install failed"
  fi
  if [ -d "$three/node_modules/three" ]; then
    cp benches/client-import/three.html benches/client-import/three_driver.mjs "$three/"
    cp "$work/scene-glb/hundred-leaves.glb" "$work/long/long-fall.glb" "$three/"
    port=$((20000 + RANDOM % 20000))
    (cd "$three" && exec python3 -m http.server "$port" --bind 127.0.0.1 >/dev/null 2>&1) &
    server=$!
    trap 'kill $server 2>/dev/null || true' EXIT
    sleep 1
    echo "== three.js $(node -p "require('./$three/node_modules/three/package.json').version") in headless Chromium, $runs runs"
    for r in $(seq "$runs"); do
      (cd "$three" && node three_driver.mjs "$port" hundred-leaves.glb:0,5,10,15 long-fall.glb:0,60,120,130) |
        grep '^RESULT ' | sed 's/^RESULT //' > "$work/three-$r.json"
    done
    kill "$server" 2>/dev/null || true
    "$venv/bin/python" benches/client-import/summarise.py three "$work" "$runs" 2>/dev/null ||
      python3 benches/client-import/summarise.py three "$work" "$runs"
  fi
else
  echo "SKIPPED three.js: needs node and /usr/bin/chromium (apt-get install chromium)"
fi
