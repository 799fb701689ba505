#!/usr/bin/env bash
# Installs what texfab needs to build and test on Debian 12, skipping what is already installed.
# Debian packages only (plus npm packages for the real clients some tests run).
# Usage: scripts/install-deps.sh [--fuzz]   (--fuzz: also clang, libFuzzer and llvm-symbolizer for
# scripts/fuzz.sh and scripts/sanitize.sh)
set -euo pipefail

packages=(
  # toolchain
  build-essential cmake pkg-config ccache git
  # images, threads, maths, command line, reports
  libopenimageio-dev openimageio-tools libtbb-dev libeigen3-dev nlohmann-json3-dev libcli11-dev
  libnanoflann-dev
  # meshes: glTF, Draco, 3MF, Embree, halfedge structures, CGAL (and its data set), OpenVDB (a
  # surface that cannot bound a solid rebuilt from its volume)
  libtinygltf-dev libdraco-dev draco lib3mf-dev libzip-dev libembree-dev libopenmesh-dev libcgal-dev libcgal-demo
  libopenvdb-dev
  # slices: zlib (PNG checksums), OpenSSL (SHA-256 of layers in the manifest), LittleCMS (ICC profiles);
  # Zstandard (KTX2 textures in glTF)
  zlib1g-dev libssl-dev liblcms2-dev libzstd-dev
  # tests and benchmarks; real clients that check our outputs (Blender's glTF importer needs numpy,
  # which Debian's blender package does not pull in)
  libgtest-dev libbenchmark-dev assimp-utils nodejs npm blender python3-numpy prusa-slicer
  # the Python module (pybind11) and its tests (pytest)
  pybind11-dev python3-dev python3-pytest
  # the goldens on emulated CPUs (qemu-x86_64 -cpu ...): values must not follow the CPU
  qemu-user
  # a real single-node Slurm for the distributed slicing test (started by the test, not as services)
  slurmctld slurmd slurm-client munge python3
  # Vulkan compute (optional at build time): loader and headers, the GLSL compiler, Mesa's
  # lavapipe (a CPU device, so the Vulkan tests run anywhere), the Khronos validation layer
  libvulkan-dev glslc mesa-vulkan-drivers vulkan-validationlayers
  # test data: GIMP's patterns (marble, granite, brick, wood, ...)
  gimp-data
)
if [ "${1:-}" = "--fuzz" ]; then
  packages+=(clang libclang-rt-14-dev llvm-14)
fi

missing=()
for p in "${packages[@]}"; do
  if [ "$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null)" != "install ok installed" ]; then
    missing+=("$p")
  fi
done
# A node/npm already on PATH (not from Debian) is fine: keep it.
if command -v node >/dev/null && command -v npm >/dev/null; then
  filtered=()
  for p in "${missing[@]}"; do [[ "$p" == nodejs || "$p" == npm ]] || filtered+=("$p"); done
  missing=("${filtered[@]}")
fi

if [ ${#missing[@]} -gt 0 ]; then
  echo "install-deps: installing ${missing[*]}"
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "install-deps: all Debian packages present"
fi

# The Khronos glTF validator (npm gltf-validator), which the geometry tests run on every glTF/GLB
# texfab writes; installed into the repository's ignored .tools/ folder, not system-wide.
repo="$(cd "$(dirname "$0")/.." && pwd)"
if [ ! -f "$repo/.tools/node_modules/gltf-validator/package.json" ]; then
  echo "install-deps: installing gltf-validator into .tools/"
  npm install --prefix "$repo/.tools" --no-audit --no-fund --loglevel=error gltf-validator
else
  echo "install-deps: gltf-validator present"
fi
# three.js, whose Basis Universal transcoder (the one its KTX2Loader runs) reads back the KTX2/UASTC
# textures texfab writes (tests/core/ktx2_transcode.mjs); also into .tools/.
if [ ! -f "$repo/.tools/node_modules/three/package.json" ]; then
  echo "install-deps: installing three into .tools/"
  npm install --prefix "$repo/.tools" --no-audit --no-fund --loglevel=error three@0.187.0
else
  echo "install-deps: three present"
fi
# CGAL's mesh data set for the tests that want more meshes (models/cgal/, ignored).
if [ ! -f "$repo/models/cgal/elephant.off" ]; then "$repo/models/fetch" || true; fi
