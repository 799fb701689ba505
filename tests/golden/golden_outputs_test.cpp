// SPDX-License-Identifier: GPL-3.0-or-later
// Golden outputs: hashes of the bytes texfab produces for fixed inputs. Every synthesized value is
// a pure function of (analysis, seed, parameters, position), and the floating-point model is
// pinned (-ffp-contract=off), so these hashes hold for every build of texfab on every x86-64 CPU.
// A change of output fails here. When the change is deliberate, update the hash in the same commit
// and say why in its message; the failure prints the new value.
#include "golden_cases.h"

#include <gtest/gtest.h>

namespace texfab::golden {
namespace {

TEST(Golden, Window2d) { EXPECT_EQ(hex(window2d()), "72908d5d3414dcbb"); }
TEST(Golden, SolidVolume) { EXPECT_EQ(hex(solidVolume()), "fc5a806ef9d84627"); }
TEST(Golden, SolidObliquePlane) { EXPECT_EQ(hex(solidPlane()), "e555c1be435c67fa"); }
#ifndef TEXFAB_GOLDEN_SYNTHESIS_ONLY
TEST(Golden, AtlasTexelUvs) { EXPECT_EQ(hex(atlasTexelUvs()), "66752b2be1750fd4"); }
TEST(Golden, SurfaceTexture) { EXPECT_EQ(hex(surfaceTexture()), "0b8d074efefb46ee"); }
TEST(Golden, SolidTexture) { EXPECT_EQ(hex(solidTexture()), "cd4a11d13c3d08ca"); }
TEST(Golden, GlbBytes) { EXPECT_EQ(hex(glbBytes()), "b4cb60ad089f5722"); }
#endif

} // namespace
} // namespace texfab::golden
