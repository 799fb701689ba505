#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""The Python module's costs: `import texfab` (target <= 0.3 s) and its overhead over the C++
entries on the texture job (target <= 2 %): the time texfab.texture_mesh spends outside the
library's stages (converting arguments and results, measuring the exemplar's wrap, the GIL and the
progress callback), against the stages' span, from the first stage's beginning to the last one's
end as the progress callback sees them. Inputs are a loaded mesh and exemplar; the exemplar's
analysis comes from a warm cache.

    PYTHONPATH=build/python /usr/bin/python3 bench/python_overhead.py [--resolution 2048] [--reps 5]
"""
import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def import_seconds(reps):
    code = "import time; t = time.perf_counter(); import texfab; print(time.perf_counter() - t)"
    return [float(subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout)
            for _ in range(reps)]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default=str(REPO / "models/meshes/elephant.off"))
    parser.add_argument("--exemplar", default=str(REPO / "models/exemplars/brick.png"))
    parser.add_argument("--resolution", type=int, default=2048)
    parser.add_argument("--reps", type=int, default=5)
    args = parser.parse_args()
    imports = import_seconds(5)
    print(f"import texfab: median {statistics.median(imports):.3f} s (of {len(imports)}; target <= 0.3 s)")

    import texfab

    with tempfile.TemporaryDirectory() as cache:
        mesh, exemplar = texfab.load_mesh(args.model), texfab.read_image(args.exemplar)
        texfab.texture_mesh(mesh, exemplar, resolution=args.resolution, cache_dir=cache)  # warms the cache
        walls, spans = [], []
        for _ in range(args.reps):
            events = []
            start = time.perf_counter()
            texfab.texture_mesh(mesh, exemplar, resolution=args.resolution, cache_dir=cache,
                                progress=lambda stage, done: events.append(time.perf_counter()))
            walls.append(time.perf_counter() - start)
            spans.append(events[-1] - events[0])
    outside = [w - s for w, s in zip(walls, spans)]
    o, s = statistics.median(outside), statistics.median(spans)
    print(f"texture job {args.resolution}^2: library stages {s:.3f} s, outside them {1000 * o:.1f} ms (medians of "
          f"{args.reps}): overhead {100 * o / s:.2f} % (target <= 2 %)")


if __name__ == "__main__":
    main()
