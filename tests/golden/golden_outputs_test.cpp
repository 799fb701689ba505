// SPDX-License-Identifier: GPL-3.0-or-later
// Golden outputs: hashes of the bytes texfab produces for fixed inputs. Every synthesized value is
// a pure function of (analysis, seed, parameters, position), and the floating-point model is
// pinned (-ffp-contract=off; Eigen's blocking does not follow the CPU's caches: EIGEN_NO_CPUID), so
// these hashes hold for every build of texfab on every x86-64 CPU (Golden.EmulatedCpu.* runs them
// under qemu-x86_64 with other CPU models).
// A change of output fails here. When the change is deliberate, update the hash (golden_cases.h)
// in the same commit and say why in its message; the failure prints the new value.
#include "golden_cases.h"

#include <gtest/gtest.h>

namespace texfab::golden {
namespace {

TEST(Golden, Window2d) { expectStages(window2d(), kWindow2d); }
TEST(Golden, Window2dClamp) { expectStages(window2dClamp(), kWindow2dClamp); }
TEST(Golden, SolidVolume) { expectStages(solidVolume(), kSolidVolume); }
TEST(Golden, SolidObliquePlane) { expectStages(solidPlane(), kSolidObliquePlane); }
TEST(Golden, SolidClampVolume) { expectStages(solidClampVolume(), kSolidClampVolume); }
TEST(Golden, SolidTiles) { expectStages(solidTiles(solidAnalysis32()), kSolidTiles); }
TEST(Golden, SolidTilesTwoLevels) { expectStages(solidTiles(solidAnalysis32(), 16), kSolidTilesTwoLevels); }
TEST(Golden, SolidClampTiles) { expectStages(solidTiles(solidClampAnalysis40()), kSolidClampTiles); }
#ifndef TEXFAB_GOLDEN_SYNTHESIS_ONLY
TEST(Golden, AtlasTexelUvs) { expectStages(atlasTexelUvs(), kAtlasTexelUvs); }
TEST(Golden, SurfaceTexture) { expectStages(surfaceTexture(), kSurfaceTexture); }
TEST(Golden, SolidTexture) { expectStages(solidTexture(), kSolidTexture); }
TEST(Golden, GlbBytes) { expectStages(glbBytes(), kGlbBytes); }
TEST(Golden, Fracture) { expectStages(fracture(), kFracture); }
TEST(Golden, SliceLayers) { expectStages(sliceLayers(), kSliceLayers); }
TEST(Golden, NdfMipChain) { expectStages(ndfMipChain(), kNdfMipChain); }
#endif

} // namespace
} // namespace texfab::golden
