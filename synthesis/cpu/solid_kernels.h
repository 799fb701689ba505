// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The per-voxel kernels of lazy solid synthesis (Dong, Lefebvre, Tong, Drettakis 2008, §5.1-5.2),
// on plain integer arrays, in the style of synthesis/cpu/synthesis_kernels.h: each kernel reads
// only its input buffers and writes only its output buffer, processes the rows [rowBegin, rowEnd)
// it is given, and uses integer arithmetic only, so that the Vulkan compute shaders are ports.
//
// A level buffer holds, per voxel, three packed exemplar coordinates (coord_map.h packCoord):
// the coordinates in E_x, E_y and E_z. Voxel (x, y, z) of a buffer is level position
// (grid.x0 + x, grid.y0 + y, grid.z0 + z), index (z * ny + y) * nx + x; row r is (y, z) =
// (r mod ny, r div ny). A mask buffer (`last`, int8 per voxel) says up to which correction step t
// a voxel is needed: -1 = not at all, 0 = after upsampling, T = after the last sub-pass.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace texfab::synthesis::cpu {

struct VolumeGrid {
  int64_t x0 = 0, y0 = 0, z0 = 0;  ///< level position of buffer voxel (0, 0, 0)
  int nx = 0, ny = 0, nz = 0;

  size_t size() const { return size_t(nx) * size_t(ny) * size_t(nz); }
  int rows() const { return ny * nz; }
};

/// An integer projection laid out for the correction kernel (prepareSolidProjection): inputs taken
/// in chunks of 16 (padded with zero weights), the weights of a chunk stored dimension after
/// dimension, so that one chunk of int16 inputs, loaded once, updates every dimension in turn (a
/// pmaddwd per dimension on x86). The centring by the mean is folded into `offset`: q_d =
/// clamp((sum_j basis[d][j] * x_j + offset[d]) >> shift, +-127), with offset[d] = divisor/2 -
/// sum_j basis[d][j] * mean_j. Bit for bit the projection of SolidProjection::project (all terms
/// are exact int32).
struct SolidKernelProjection {
  static constexpr int kLanes = 16;  ///< output dimensions at most; outputs are padded to 16 with zeros
  static constexpr int kChunk = 16;  ///< inputs per chunk
  int dims = 0;
  int rows = 0;                      ///< dims rounded up to a multiple of 4 (extra rows have zero weights)
  int lanes = 0;                     ///< inputs rounded up to a multiple of kChunk
  int shift = 0;
  std::vector<int16_t> weights;      ///< lanes / kChunk chunks of rows x kChunk: basis[d][c * kChunk + i]
  alignas(32) int32_t offset[kLanes] = {};
};
/// `dims` at most SolidKernelProjection::kLanes.
SolidKernelProjection prepareSolidProjection(const int32_t* mean, const int16_t* basis, int inputs, int dims,
                                           int32_t divisor);

/// What the correction kernel reads about one synthesized level (views into SolidLevel).
struct SolidTables {
  int exemplarWidth = 0;
  int exemplarHeight = 0;
  int spacing = 1;      ///< h_l
  int dims = 0;         ///< dimensions of a projected 3-neighborhood
  int k2d = 1;          ///< 2-D candidates compared per pixel
  int k2dStride = 1;    ///< 2-D candidates stored per pixel
  int k3d = 1;          ///< 3-D candidates compared per pixel
  /// Non-toroidal exemplar (SolidLevel::valid): coordinates stay at least this many pixels inside
  /// the exemplar; 0 = they wrap.
  int clampMargin = 0;
  const uint8_t* colors[3] = {};         ///< per exemplar: w*h*3 8-bit colours of this level
  const uint32_t* candidates2d[3] = {};  ///< per exemplar: w*h*k2dStride packed coordinates
  const int8_t* candidateDescriptors2d[3] = {};  ///< per exemplar: w*h*k2dStride*8, each candidate's descriptor
  const uint32_t* triples[3] = {};       ///< per exemplar: w*h*12*3 packed coordinates
  const int8_t* descriptors3d[3] = {};   ///< per exemplar: w*h*12*dims
  /// Null: a voxel's search colour is 2x the sum of its three colours (6x their mean). Otherwise
  /// 3 channels * 766 entries indexed by that sum (SolidLevel::searchColors).
  const int16_t* searchColors = nullptr;
  /// The targets' gain in sixteenths (SolidSynthesisOptions::contrastGain): the search sees each
  /// colour record c of a 3-neighborhood whose mean record is m as
  /// clamp(m + (((c - m) * contrastGain16) >> 4), 0, 1530), per channel; m rounds the mean of the
  /// 61 records to the nearest integer (halves up). 16: as they are.
  int contrastGain16 = 16;
  const SolidKernelProjection* projection2d = nullptr;  ///< the 2-D projection, prepared
  const SolidKernelProjection* projection3d = nullptr;  ///< the 3-D projection, prepared
};

/// `interleave` is 2 (sub-pass t corrects the voxels of parity class (t-1) mod 8, §5.1) or 1
/// (every step corrects every voxel from the previous step's values: plain Jacobi passes).
///
/// Backward dependency step t (sub-pass class (t-1) mod 8): every voxel of that class with
/// last >= t needs its 3-neighborhood (the 61-voxel cross, which contains the 3x3 plane
/// neighbors candidates come from) after step t-1: last = max(last, t-1) there. Over the whole
/// grid (it writes rows around each row it reads); voxels within 2 of the border are not spread.
void solidDilateKernel(int8_t* last, const VolumeGrid& grid, int interleave, int step);

/// The random choices of the initialization (SolidSynthesisOptions seed, jitter, offsetCells).
struct SolidInit {
  uint32_t seed = 0;
  int64_t jitter256 = 0;  ///< warp amplitude, 1/256 voxel
  int offsetCells = 0;    ///< side of the cells reading the slab at their own offset; 0 = one tiling
};

/// Initialization (§5.1): the candidate slab of E_z (best triple of each pixel, thickened by
/// +-2 voxels along z, §4.3) tiled over the volume, read through the random warp ("jitter once"):
/// voxel q shows the slab at p = round(q + d(q)), d a sum of compactly supported bumps on two
/// hashed grids (4 and 8 voxels), amplitude jitter256/256 voxels. With offsetCells = c > 0, the
/// cell floor(p / c) reads the slab shifted by its own hashed offset (any exemplar pixel, any slab
/// layer), so that the volume does not repeat with the exemplar's period (a deviation from the
/// paper). The slab's layers shift E_x's and E_y's coordinates along z, wrapped, or with
/// clampMargin reflected into the valid region. Writes voxels with last >= 0.
void solidInitKernel(uint32_t* out, const int8_t* last, const VolumeGrid& grid, const SolidTables& tables,
                     const SolidInit& init, int rowBegin, int rowEnd);

/// Upsampling by coordinate inheritance with a stack (§5.1, errata §20.2): the child voxel q takes
/// its parent's triple plus spacing * (bits of q along each exemplar's u and v axes).
/// Writes voxels with last >= 0; `parent` must cover their parents.
void solidUpsampleKernel(const uint32_t* parent, const VolumeGrid& parentGrid, uint32_t* out, const int8_t* last,
                         const VolumeGrid& grid, int spacing, int exemplarWidth, int exemplarHeight, int rowBegin,
                         int rowEnd);

/// A colour buffer holds, per voxel, 4 int16: 2 x the sum of the voxel's three exemplar colours
/// (R, G, B; so 6 x their mean, the scale of the projection inputs), then 0. It is derived from
/// the level buffer (a cache of the 183 colour lookups a 3-neighborhood would otherwise cost).
/// Writes the colours of the voxels with last >= minLast.
void solidColorKernel(const uint32_t* triples, int16_t* colors, const int8_t* last, int minLast, const VolumeGrid& grid,
                      const SolidTables& tables, int rowBegin, int rowEnd);

/// Correction sub-pass `step` (class (step-1) mod 8 of the 2x2x2 interleave): for every voxel of
/// that class with last >= step, the two-step search (§5.1): the best 2-D candidate in each
/// direction among the k-coherence candidates of its 3x3 plane neighbors, then the best of the
/// 3-D candidates of those three pixels, by integer SSD of projected neighborhoods; step 1's ties
/// go to the smaller packed coordinate, step 2's to the earliest candidate (direction x, y, z;
/// then rank). Reads triples `in` and their colours `inColors`; writes only those voxels of `out`
/// and `outColors`. `tables.projection2d/projection3d` must be set. The portable kernel searches
/// one voxel at a time (the specification); on x86 batches of voxels are searched phase by phase
/// with SSE or AVX2 (same integers, same result).
void solidCorrectKernel(const uint32_t* in, const int16_t* inColors, uint32_t* out, int16_t* outColors,
                        const int8_t* last, const VolumeGrid& grid, const SolidTables& tables, int interleave, int step,
                        int rowBegin, int rowEnd);

/// The instruction sets the correction kernel may use: at most `limit`, as far as the CPU has
/// them (default Avx2). For tests: every setting gives the same bytes.
enum class SolidSimd : uint8_t { Portable, Sse, Avx2 };
void solidLimitSimd(SolidSimd limit);

/// Copies the voxels corrected at `step` (triples and colours) from `from` to `to`.
void solidCommitKernel(const uint32_t* from, const int16_t* fromColors, uint32_t* to, int16_t* toColors,
                       const int8_t* last, const VolumeGrid& grid, int interleave, int step, int rowBegin, int rowEnd);

} // namespace texfab::synthesis::cpu
