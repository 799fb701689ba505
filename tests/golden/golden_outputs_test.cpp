// SPDX-License-Identifier: GPL-3.0-or-later
// Golden outputs: hashes of the bytes texfab produces for fixed inputs. Every synthesized value is
// a pure function of (analysis, seed, parameters, position), and the floating-point model is
// pinned (-ffp-contract=off), so these hashes hold for every build of texfab on every x86-64 CPU.
// A change of output fails here. When the change is deliberate, update the hash (golden_cases.h)
// in the same commit and say why in its message; the failure prints the new value.
#include "golden_cases.h"

#include <gtest/gtest.h>

namespace texfab::golden {
namespace {

TEST(Golden, Window2d) { EXPECT_EQ(hex(window2d()), kWindow2d); }
TEST(Golden, Window2dClamp) { EXPECT_EQ(hex(window2dClamp()), kWindow2dClamp); }
TEST(Golden, SolidVolume) { EXPECT_EQ(hex(solidVolume()), kSolidVolume); }
TEST(Golden, SolidObliquePlane) { EXPECT_EQ(hex(solidPlane()), kSolidObliquePlane); }
TEST(Golden, SolidClampVolume) { EXPECT_EQ(hex(solidClampVolume()), kSolidClampVolume); }
#ifndef TEXFAB_GOLDEN_SYNTHESIS_ONLY
TEST(Golden, AtlasTexelUvs) { EXPECT_EQ(hex(atlasTexelUvs()), kAtlasTexelUvs); }
TEST(Golden, SurfaceTexture) { EXPECT_EQ(hex(surfaceTexture()), kSurfaceTexture); }
TEST(Golden, SolidTexture) { EXPECT_EQ(hex(solidTexture()), kSolidTexture); }
TEST(Golden, GlbBytes) { EXPECT_EQ(hex(glbBytes()), kGlbBytes); }
#endif

} // namespace
} // namespace texfab::golden
