// SPDX-License-Identifier: GPL-3.0-or-later
// The Vulkan backend end to end: the golden outputs (2-D windows from a toroidal exemplar and from
// one that does not tile, solid volume and plane, the texture job in both modes, its GLB) computed
// with the kernels on the device give the golden hashes; more 2-D windows (both kinds of exemplar,
// in tiles under a small binding range), a texture from an exemplar that does not tile, solid
// requests and a solid box equal the CPU backend's; and the choice of the backend (Auto, Vulkan,
// device indices) behaves as documented.
#include "synthesis/backend.h"
#include "tests/golden/golden_cases.h"
#include "tests/vulkan/vulkan_test_support.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <mutex>

namespace texfab::golden {
namespace {

// Skips the test when the backend has no device to run on.
#define TEXFAB_REQUIRE_SHARED_VULKAN()                              \
  try {                                                            \
    synthesis::vulkan::sharedDevice(-1);                           \
  } catch (const Error& e) {                                       \
    GTEST_SKIP() << "no Vulkan device: " << e.what();              \
  }

TEST(VulkanGolden, Window2d) {
  TEXFAB_REQUIRE_SHARED_VULKAN();
  expectStages(window2d(Backend::Vulkan), kWindow2d);
}
TEST(VulkanGolden, Window2dClamp) {
  TEXFAB_REQUIRE_SHARED_VULKAN();
  expectStages(window2dClamp(Backend::Vulkan), kWindow2dClamp);
}
TEST(VulkanGolden, SolidVolume) {
  TEXFAB_REQUIRE_SHARED_VULKAN();
  expectStages(solidVolume(Backend::Vulkan), kSolidVolume);
}
TEST(VulkanGolden, SolidObliquePlane) {
  TEXFAB_REQUIRE_SHARED_VULKAN();
  expectStages(solidPlane(Backend::Vulkan), kSolidObliquePlane);
}
TEST(VulkanGolden, SolidClampVolume) {
  TEXFAB_REQUIRE_SHARED_VULKAN();
  expectStages(solidClampVolume(Backend::Vulkan), kSolidClampVolume);
}
TEST(VulkanGolden, SurfaceTextureAndGlb) {
  TEXFAB_REQUIRE_SHARED_VULKAN();
  expectStages(surfaceTexture(Backend::Vulkan), kSurfaceTexture);
  expectStages(glbBytes(Backend::Vulkan), kGlbBytes);
}
TEST(VulkanGolden, SolidTexture) {
  TEXFAB_REQUIRE_SHARED_VULKAN();
  expectStages(solidTexture(Backend::Vulkan), kSolidTexture);
}
TEST(VulkanGolden, Fracture) {
  TEXFAB_REQUIRE_SHARED_VULKAN();
  expectStages(fracture(Backend::Vulkan), kFracture);
}
TEST(VulkanGolden, SliceLayers) {
  TEXFAB_REQUIRE_SHARED_VULKAN();
  expectStages(sliceLayers(Backend::Vulkan), kSliceLayers);
}

const synthesis::ExemplarAnalysis& marbleAnalysis() {
  static const synthesis::ExemplarAnalysis a = synthesis::analyzeExemplar(marble32(), {}, Context{.threads = 2});
  return a;
}

// Windows far from the origin, tiling periods, every interleave, no correction, one pass, from a
// toroidal exemplar (marble) and from one that does not tile (clampAnalysis64); and windows larger
// than one binding when ctest lowers the range ($TEXFAB_VULKAN_MAX_RANGE): tiles.
TEST(VulkanBackend, WindowsEqualTheCpu) {
  TEXFAB_REQUIRE_SHARED_VULKAN();
  const synthesis::ExemplarAnalysis* tile = &marbleAnalysis();
  const synthesis::ExemplarAnalysis* clamp = &clampAnalysis64();
  struct Case {
    const synthesis::ExemplarAnalysis* analysis;
    synthesis::Window window;
    int interleave, passes, periodX, periodY;
    bool correct;
  };
  for (const Case& c : {Case{tile, {-(int64_t(1) << 38), 12345, 61, 47}, 2, 2, 0, 0, true},
                        Case{tile, {0, 0, 96, 48}, 3, 1, 96, 48, true},
                        Case{tile, {-5, -9, 40, 40}, 1, 3, 0, 0, true},
                        Case{tile, {100, -100, 33, 70}, 2, 2, 0, 0, false},
                        Case{tile, {7, 3, 900, 700}, 2, 1, 0, 0, true},
                        Case{clamp, {-(int64_t(1) << 39), 4321, 45, 38}, 1, 2, 0, 0, true},
                        Case{clamp, {0, 0, 64, 48}, 2, 2, 64, 48, true},
                        Case{clamp, {-9, 5, 41, 30}, 3, 1, 0, 0, true},
                        Case{clamp, {-300, 200, 660, 610}, 1, 1, 0, 0, true}}) {
    synthesis::SynthesisOptions o;
    o.seed = 3;
    o.interleave = c.interleave;
    o.passes = c.passes;
    o.periodX = c.periodX;
    o.periodY = c.periodY;
    o.correct = c.correct;
    const auto cpu = synthesis::synthesize2d(*c.analysis, c.window, o, synthesisContext(Backend::Cpu));
    const auto gpu = synthesis::synthesize2d(*c.analysis, c.window, o, synthesisContext(Backend::Vulkan));
    EXPECT_EQ(gpu.coords.coords, cpu.coords.coords) << c.window.width << "x" << c.window.height;
    EXPECT_EQ(gpu.levels.size(), cpu.levels.size());  // (tiles add up their padding: more texels)
  }
}

// The bundled elephant textured (surface mode) from an exemplar that does not tile: the same
// coordinates and base colour on both backends.
TEST(VulkanBackend, ClampedSurfaceEqualsTheCpu) {
  TEXFAB_REQUIRE_SHARED_VULKAN();
  const geometry::Mesh mesh = geometry::readMesh(bundled("meshes/elephant.off"));
  render::TextureExemplar ex;
  ex.color = &stone64();
  ex.analysis = &clampAnalysis64();
  render::TextureMeshOptions o;
  o.atlas.pack.width = o.atlas.pack.height = 256;
  o.measure = false;
  o.surface.seed = 6;
  const auto cpu = render::textureMesh(mesh, ex, o, Context{.backend = Backend::Cpu});
  const auto gpu = render::textureMesh(mesh, ex, o, Context{.backend = Backend::Vulkan});
  EXPECT_EQ(gpu.coords, cpu.coords);
  EXPECT_EQ(gpu.baseColor->pixels, cpu.baseColor->pixels);
}

std::vector<synthesis::Voxel> shell(int r, int64_t cx, int64_t cy, int64_t cz) {
  std::vector<synthesis::Voxel> v;
  for (int z = -r - 1; z <= r + 1; ++z)
    for (int y = -r - 1; y <= r + 1; ++y)
      for (int x = -r - 1; x <= r + 1; ++x) {
        const double d2 = double(x) * x + double(y) * y + double(z) * z;
        if (d2 >= (r - 0.5) * (r - 0.5) && d2 < (r + 0.5) * (r + 0.5)) v.push_back({cx + x, cy + y, cz + z});
      }
  return v;
}

// The CPU's and the device's triples for `voxels`, level by level the same work; with `cached`, the
// coarse levels come from a cache that a neighbouring request filled (the device then synthesizes
// the finest level only).
void expectSameSolid(const std::vector<synthesis::Voxel>& voxels, const synthesis::SolidSynthesisOptions& o,
                     bool cached) {
  const synthesis::SolidAnalysis& a = solidAnalysis32();
  synthesis::SolidLevelCache cpuCache, gpuCache;
  if (cached) {
    std::vector<synthesis::Voxel> warm = voxels;
    for (auto& v : warm) v.z += 1;
    synthesis::synthesizeSolid(a, warm, o, &cpuCache, synthesisContext(Backend::Cpu));
    synthesis::synthesizeSolid(a, warm, o, &gpuCache, synthesisContext(Backend::Vulkan));
  }
  const auto cpu = synthesis::synthesizeSolid(a, voxels, o, cached ? &cpuCache : nullptr, synthesisContext(Backend::Cpu));
  const auto gpu = synthesis::synthesizeSolid(a, voxels, o, cached ? &gpuCache : nullptr, synthesisContext(Backend::Vulkan));
  EXPECT_EQ(gpu.triples, cpu.triples);
  ASSERT_EQ(gpu.levels.size(), cpu.levels.size());
  for (size_t l = 0; l < cpu.levels.size(); ++l) {
    EXPECT_EQ(gpu.levels[l].voxels, cpu.levels[l].voxels) << "level " << l;
    EXPECT_EQ(gpu.levels[l].corrections, cpu.levels[l].corrections) << "level " << l;
  }
}

// A thin shell far from the origin, and a plane cut with the coarse levels cached.
TEST(VulkanBackend, SolidRequestsEqualTheCpu) {
  TEXFAB_REQUIRE_SHARED_VULKAN();
  expectSameSolid(shell(9, -200, 37, 1000), {}, false);
  std::vector<synthesis::Voxel> cut;
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 96; ++x) cut.push_back({x - 20, y + 3, 17});
  expectSameSolid(cut, {}, true);
}

// A volume (box) away from the origin, every voxel of it: the same triples as the CPU's.
TEST(VulkanBackend, SolidBoxEqualsTheCpu) {
  TEXFAB_REQUIRE_SHARED_VULKAN();
  synthesis::SolidSynthesisOptions o;
  o.seed = 9;
  const synthesis::VoxelBox box{-70, 13, 400, 20, 24, 28};
  const auto cpu = synthesis::synthesizeSolidBox(solidAnalysis32(), box, o, nullptr, synthesisContext(Backend::Cpu));
  const auto gpu = synthesis::synthesizeSolidBox(solidAnalysis32(), box, o, nullptr, synthesisContext(Backend::Vulkan));
  ASSERT_EQ(cpu.triples.size(), size_t(20 * 24 * 28));
  EXPECT_EQ(gpu.triples, cpu.triples);
}

// Targets through a contrast gain (SolidSynthesisOptions::contrastGain): the shader moves them
// away from their neighbourhood's mean as the CPU does, and the tables kept on the device for the
// first request serve the second at another gain.
TEST(VulkanBackend, ContrastGainEqualsTheCpu) {
  TEXFAB_REQUIRE_SHARED_VULKAN();
  synthesis::SolidSynthesisOptions o;
  o.seed = 5;
  const std::vector<synthesis::Voxel> voxels = shell(4, 30, -9, 600);
  const auto plain = synthesis::synthesizeSolid(solidAnalysis32(), voxels, o, nullptr, synthesisContext(Backend::Cpu));
  expectSameSolid(voxels, o, false);
  o.contrastGain = 2.5f;
  expectSameSolid(voxels, o, false);
  const auto gained = synthesis::synthesizeSolid(solidAnalysis32(), voxels, o, nullptr, synthesisContext(Backend::Cpu));
  EXPECT_NE(gained.triples, plain.triples);
}

// Slice refinement runs on the CPU after either backend's levels: the same refined triples.
TEST(VulkanBackend, RefinementEqualsTheCpu) {
  TEXFAB_REQUIRE_SHARED_VULKAN();
  synthesis::SolidSynthesisOptions o;
  o.seed = 3;
  o.contrastGain = 2;
  o.refinePasses = 1;
  expectSameSolid(shell(3, 12, 40, -7), o, false);
}

// The paper's sub-passes (8 per pass; one pass per level, to keep the chain short).
TEST(VulkanBackend, SubPassesEqualTheCpu) {
  TEXFAB_REQUIRE_SHARED_VULKAN();
  synthesis::SolidSynthesisOptions o;
  o.interleave = 2;
  o.passes = 1;
  o.seed = 11;
  expectSameSolid(shell(2, 3, -4, 5), o, false);
}

// A profiling device sums the work of every submit: the tables and levels uploaded, the kernels,
// the window downloaded (at least its texels, 4 bytes each).
TEST(VulkanBackend, ProfileSumsTheWork) {
  TEXFAB_REQUIRE_SHARED_VULKAN();
  const auto device = synthesis::vulkan::sharedDevice(-1);
  device->setProfiling(true);
  synthesis::synthesize2d(marbleAnalysis(), {0, 0, 40, 24}, {}, synthesisContext(Backend::Vulkan));
  const synthesis::vulkan::DeviceProfile p = device->profile();
  device->setProfiling(false);
  EXPECT_GE(p.downloadBytes, 40u * 24u * 4u);
  EXPECT_GT(p.uploadBytes, 0u);
  EXPECT_GT(p.dispatches, 0u);
  EXPECT_GT(p.submits, 0u);
  EXPECT_GT(p.submitSeconds, 0.0);
  EXPECT_GT(p.dispatchSeconds, 0.0);  // lavapipe and GPUs have timestamps
  EXPECT_EQ(device->profile().submits, 0u);  // switching profiling resets the sums
}

// Progress events of a computation: the backend's note.
struct Notes {
  std::mutex mutex;
  std::vector<std::string> backend;
  Context context(Backend b, int device = -1) {
    Context ctx{.threads = 2, .backend = b, .device = device};
    ctx.progress = [this](const ProgressEvent& e) {
      const std::lock_guard lock(mutex);
      if (e.kind == ProgressEvent::Kind::End && e.stage == "backend") backend.emplace_back(e.detail);
    };
    return ctx;
  }
};

// Auto takes a GPU, and says so; a device that emulates a GPU on the CPU (lavapipe) only when it
// is asked for by index, since the CPU backend is faster than it.
TEST(VulkanBackend, AutoUsesAGpuAndSaysSo) {
  TEXFAB_REQUIRE_SHARED_VULKAN();
  const synthesis::vulkan::DeviceInfo& device = synthesis::vulkan::sharedDevice(-1)->info();
  const bool emulated = device.type == "CPU";
  Notes notes;
  const synthesis::Window w{0, 0, 16, 16};
  const auto cpu = synthesis::synthesize2d(marbleAnalysis(), w, {}).coords.coords;
  EXPECT_EQ(synthesis::synthesize2d(marbleAnalysis(), w, {}, notes.context(Backend::Auto)).coords.coords, cpu);
  EXPECT_EQ(synthesis::synthesize2d(marbleAnalysis(), w, {}, notes.context(Backend::Auto, device.index)).coords.coords, cpu);
  ASSERT_EQ(notes.backend.size(), 2u);
  EXPECT_EQ(notes.backend[0].rfind(emulated ? "CPU (the Vulkan device " : "Vulkan: ", 0), 0u) << notes.backend[0];
  EXPECT_EQ(notes.backend[1].rfind("Vulkan: ", 0), 0u) << notes.backend[1];
}

// Without a usable device (here: an index that does not exist), Vulkan is a one-line error and
// Auto falls back to the CPU with a note; the CPU backend never opens a device.
TEST(VulkanBackend, MissingDeviceIsAnErrorOrAFallBack) {
  Notes notes;
  const synthesis::Window w{0, 0, 8, 8};
  try {
    synthesis::synthesize2d(marbleAnalysis(), w, {}, notes.context(Backend::Vulkan, 999));
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.find('\n'), std::string::npos);
    EXPECT_NE(message.find(synthesis::vulkanBuilt() ? "device 999" : "without the Vulkan backend"), std::string::npos)
        << message;  // "device 999 does not exist", or "no Vulkan device found (device 999 asked for)"
  }
  const auto r = synthesis::synthesize2d(marbleAnalysis(), w, {}, notes.context(Backend::Auto, 999));
  ASSERT_EQ(notes.backend.size(), 1u);
  EXPECT_EQ(notes.backend[0].rfind("CPU (", 0), 0u) << notes.backend[0];
  EXPECT_EQ(r.coords.coords, synthesis::synthesize2d(marbleAnalysis(), w, {}).coords.coords);
  synthesis::synthesize2d(marbleAnalysis(), w, {}, notes.context(Backend::Cpu, 999));
  EXPECT_EQ(notes.backend.size(), 1u);
}

TEST(VulkanBackend, MalformedDeviceVariableIsAnError) {
  setenv("TEXFAB_VULKAN_DEVICE", "gpu0", 1);
  EXPECT_THROW(synthesis::synthesize2d(marbleAnalysis(), {0, 0, 8, 8}, {}, Context{.backend = Backend::Vulkan}), Error);
  unsetenv("TEXFAB_VULKAN_DEVICE");
}

} // namespace
} // namespace texfab::golden
