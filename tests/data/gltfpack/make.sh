#!/usr/bin/env bash
# Blender's exports of ../blender/ after gltfpack, as a web pipeline
# optimises a client's glTF before it reaches us. Needs node and npm:
#
#     npm install gltfpack@0.25 && PATH=$PWD/node_modules/.bin:$PATH bash make.sh
#
# gltfpack's defaults (KHR_mesh_quantization) but keys at 24 Hz (-af 24,
# Blender's frames; its default resamples at 30 Hz), and once with meshopt
# compression (-c) as well, for the reader to refuse by name.
set -euo pipefail
cd "$(dirname "$0")"
gltfpack -i ../blender/tumble_thick.glb -o tumble_thick.glb -af 24
gltfpack -i ../blender/tumble_thick_rigged.glb -o tumble_thick_rigged.glb -af 24
gltfpack -i ../blender/tumble_thick.glb -o tumble_thick_meshopt.glb -af 24 -c
