#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Tests the Blender add-on (python/blender/texfab_blender) in Debian's `blender`, headless, against
# the texfab module and command line of a build (tests/python/blender_addon_test.py): it registers,
# textures, fractures and slices the bundled elephant, and its images equal the command line's.
# Exit 77 when Blender is not installed.
# Usage: scripts/blender-addon-check.sh [BUILD_DIR [WORK_DIR]]
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
build="$(cd "${1:-$repo/build}" && pwd)"
work="${2:-$(mktemp -d)}"
command -v blender >/dev/null || { echo "blender-addon-check: blender is not installed: skipped"; exit 77; }
mkdir -p "$work"
rm -rf "${work:?}"/*

set +e +o pipefail
PYTHONPATH="$build/python${PYTHONPATH:+:$PYTHONPATH}" \
  blender -b --factory-startup -noaudio --python-exit-code 1 --python "$repo/tests/python/blender_addon_test.py" -- \
  "$repo" "$work" "$build/python" >"$work/blender.log" 2>&1
status=$?
grep -E '^(blender-addon-test|Error|Traceback|  File|[A-Za-z]*Error)' "$work/blender.log"
exit $status
