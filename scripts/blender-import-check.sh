#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Textures the bundled elephant with texfab, writes it in every textured format texfab writes
# (GLB; .gltf with files beside it and embedded; OBJ+MTL; JPEG textures), and imports each
# into Blender headless (Debian's `blender`): each must show a material whose base colour is an
# image texture, a normal map connected through a Normal Map node, and one UV island per atlas
# chart (scripts/blender-import-check.py). Exit 77 when Blender is not installed. WebP textures are
# not checked: Debian 12's Blender (3.4) refuses EXT_texture_webp, which texfab marks required.
# Usage: scripts/blender-import-check.sh [TEXFAB [WORK_DIR]]
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
texfab="${1:-$repo/build/apps/texfab}"
work="${2:-$(mktemp -d)}"
command -v blender >/dev/null || { echo "blender-import-check: blender is not installed: skipped"; exit 77; }
mkdir -p "$work"
rm -rf "${work:?}"/*

model="$repo/models/meshes/elephant.off"
exemplar="$repo/models/exemplars/brick.png"
common=(-e "$exemplar" --maps "normal=$exemplar" --resolution 256 -q --cache-dir "$work/cache")
"$texfab" texture "$model" "${common[@]}" -o "$work/elephant.glb" --report "$work/report.json"
charts="$(sed -n 's/^ *"charts": \([0-9]*\),*$/\1/p' "$work/report.json" | head -1)"
"$texfab" convert -q "$work/elephant.glb" "$work/elephant.gltf"
"$texfab" convert -q --embed "$work/elephant.glb" "$work/embedded.gltf"
"$texfab" convert -q "$work/elephant.glb" "$work/elephant.obj"
"$texfab" convert -q --texture-format jpeg "$work/elephant.glb" "$work/jpeg.glb"

checks=()
for file in elephant.glb elephant.gltf embedded.gltf elephant.obj jpeg.glb; do
  checks+=("$work/$file:$charts:normal")
done
set +e +o pipefail
blender -b --factory-startup -noaudio --python-exit-code 1 --python "$repo/scripts/blender-import-check.py" -- \
  "${checks[@]}" >"$work/blender.log" 2>&1
status=$?
grep -E '^(blender-import-check|Error|Traceback|  File|[A-Za-z]*Error)' "$work/blender.log"
exit $status
