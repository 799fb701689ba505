#!/usr/bin/env bash
# Installs dependencies, builds texfab, and runs the main job on bundled data.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
mkdir -p out
build/apps/texfab synth models/exemplars/brick.png -o out/brick_1024.png --size 1024x1024 \
  --coords out/brick_1024_coords.png --report out/brick_1024.json
echo "quickstart: wrote out/brick_1024.png (and its coordinate map and report)"
