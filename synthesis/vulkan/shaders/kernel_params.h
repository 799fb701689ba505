// SPDX-License-Identifier: GPL-3.0-or-later
// The parameter blocks (push constants) of the compute kernels: one definition, read by the C++
// kernel wrappers and by the GLSL shaders (GL_EXT_shader_explicit_arithmetic_types gives GLSL the
// same integer types). Scalars and structs of scalars only, 64-bit fields first and 8-aligned, so
// that the std430 layout of a push-constant block equals the C++ layout; the static_asserts below
// pin the sizes.
#ifndef TEXFAB_KERNEL_PARAMS_H
#define TEXFAB_KERNEL_PARAMS_H

#ifdef __cplusplus
#include <cstdint>
namespace texfab::synthesis::vulkan {
#define TEXFAB_CONST inline constexpr
#else
#define TEXFAB_CONST const
#endif

/// A rectangle of one level of the plane (cpu::LevelGrid).
struct GridParams {
  int64_t x0;
  int64_t y0;
  int32_t width;
  int32_t height;
};

/// A non-toroidal exemplar's valid region at one level (ValidRegion: inclusive bounds, in
/// exemplar pixels). `clamp` 0: the exemplar tiles, coordinates wrap and the bounds are unused.
struct RegionParams {
  int32_t clamp;
  int32_t x0;
  int32_t y0;
  int32_t x1;
  int32_t y1;
};

/// initKernel.
struct InitParams {
  GridParams grid;
  int64_t periodX;
  int64_t periodY;
  int32_t spacing;
  int32_t exemplarWidth;
  int32_t exemplarHeight;
  RegionParams region;
};

/// upsampleKernel.
struct UpsampleParams {
  GridParams grid;
  GridParams parentGrid;
  int32_t spacing;
  int32_t exemplarWidth;
  int32_t exemplarHeight;
  RegionParams region;
};

/// jitterKernel.
struct JitterParams {
  GridParams grid;
  int64_t amplitude256;
  int64_t periodX;
  int64_t periodY;
  uint32_t seed;
  int32_t level;
  int32_t exemplarWidth;
  int32_t exemplarHeight;
  RegionParams region;
  int32_t unused;
};

/// correctKernel: one sub-pass over the buffer rectangle [ax0, ax1) x [ay0, ay1).
struct CorrectParams {
  GridParams grid;
  int32_t spacing;
  int32_t exemplarWidth;
  int32_t exemplarHeight;
  int32_t k;
  int32_t interleave;
  int32_t classX;
  int32_t classY;
  int32_t ax0;
  int32_t ax1;
  int32_t ay0;
  int32_t ay1;
  RegionParams region;
};

/// initSurfaceKernel, upsampleSurfaceKernel, jitterSurfaceKernel: the sites [first, first + count)
/// of a level, whose per-site arrays are bound from site `first` on.
struct SurfaceParams {
  int64_t amplitude256;
  uint32_t first;
  uint32_t count;
  int32_t exemplarWidth;
  int32_t exemplarHeight;
  uint32_t seed;
  int32_t atlasLevel;
  RegionParams region;
  int32_t unused;
};

/// correctSurfaceKernel, over the sites [first, first + count).
struct CorrectSurfaceParams {
  uint32_t first;
  uint32_t count;
  int32_t cls;
  int32_t spacing;
  int32_t exemplarWidth;
  int32_t exemplarHeight;
  int32_t k;
  RegionParams region;
};

/// Solid kernels work on 16^3 chunks of a level (the lazy engine's chunks).
TEXFAB_CONST int32_t kSolidChunkShift = 4;

/// Every solid kernel (each reads the fields it needs) over `chunks` chunks of 4096 voxels.
struct SolidParams {
  int64_t jitter256;
  uint32_t chunks;
  uint32_t seed;
  int32_t spacing;
  int32_t exemplarWidth;
  int32_t exemplarHeight;
  int32_t step;
  int32_t interleave;
  int32_t minLast;
  int32_t dims;
  int32_t k2d;
  int32_t k2dStride;
  int32_t k3d;
  int32_t shift2d;
  int32_t shift3d;
  int32_t offsetCells;
  int32_t clampMargin;  ///< cpu::SolidTables::clampMargin
  int32_t contrastGain16;  ///< cpu::SolidTables::contrastGain16
};

/// solidGatherKernel.
struct GatherParams {
  uint32_t count;
};

/// solidTilesKernel: the voxels of the box (x0, y0, z0) + [0, nx) x [0, ny) x [0, nz), x fastest,
/// from a tile set of SolidTileLayout (side = 1 << shift, V variants, its face and interior
/// element offsets); solidTilesCellsKernel: the `count` cells that box touches;
/// solidTilesListKernel: `count` listed voxels (the box fields unused).
struct TilesParams {
  int32_t x0;
  int32_t y0;
  int32_t z0;
  int32_t nx;
  int32_t ny;
  int32_t nz;
  uint32_t seed;
  int32_t shift;
  int32_t variants;
  uint32_t faces;
  uint32_t interiors;
  uint32_t count;
};

#ifdef __cplusplus
static_assert(sizeof(GridParams) == 24 && alignof(GridParams) == 8);
static_assert(sizeof(RegionParams) == 20 && alignof(RegionParams) == 4);
static_assert(sizeof(InitParams) == 72);
static_assert(sizeof(UpsampleParams) == 80);
static_assert(sizeof(JitterParams) == 88);
static_assert(sizeof(CorrectParams) == 88);
static_assert(sizeof(SurfaceParams) == 56);
static_assert(sizeof(CorrectSurfaceParams) == 48);
static_assert(sizeof(SolidParams) == 80);
static_assert(sizeof(GatherParams) == 4);
static_assert(sizeof(TilesParams) == 48);
} // namespace texfab::synthesis::vulkan
#endif
#undef TEXFAB_CONST

#endif
