#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Fails when an include runs from a lower floor to a higher one (docs/design.md#layout):
core -> geometry | synthesis -> atlas -> render -> print -> python | apps. geometry and synthesis do not
include each other (synthesis knows nothing of meshes), nor do python and apps.
Usage: check_floors.py [REPO]"""
import re
import sys
from pathlib import Path

MAY_INCLUDE = {
    "core": {"core"},
    "geometry": {"core", "geometry"},
    "synthesis": {"core", "synthesis"},
    "atlas": {"core", "geometry", "synthesis", "atlas"},
    "render": {"core", "geometry", "synthesis", "atlas", "render"},
    "print": {"core", "geometry", "synthesis", "atlas", "render", "print"},
    "python": {"core", "geometry", "synthesis", "atlas", "render", "print", "python"},
    "apps": {"core", "geometry", "synthesis", "atlas", "render", "print", "apps"},
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"/]+)/')


def main():
    repo = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parents[2])
    violations, files = [], 0
    for floor, allowed in MAY_INCLUDE.items():
        for path in sorted((repo / floor).rglob("*")):
            if path.suffix not in (".h", ".cpp", ".comp", ".glsl"):
                continue
            files += 1
            for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
                match = INCLUDE.match(line)
                if match and match.group(1) in MAY_INCLUDE and match.group(1) not in allowed:
                    violations.append(f"{path.relative_to(repo)}:{number}: {floor}/ includes {match.group(1)}/")
    for v in violations:
        print(v)
    print(f"check-floors: {files} files, {len(violations)} includes against the floors")
    return 1 if violations or files == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
