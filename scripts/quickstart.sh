#!/usr/bin/env bash
# Installs dependencies, builds texfab, and runs the main job on bundled data: a texture
# synthesized over the bundled elephant from the bundled brick exemplar.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
mkdir -p out
build/apps/texfab texture models/meshes/elephant.off --exemplar models/exemplars/brick.png \
  -o out/elephant.glb --preview out/elephant.png --report out/elephant.json
echo "quickstart: wrote out/elephant.glb (textured model), out/elephant.png (preview) and out/elephant.json"
