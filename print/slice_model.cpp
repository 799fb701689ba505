// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: K. Vidimce, S.-P. Wang, J. Ragan-Kelley, W. Matusik. OpenFab: a programmable pipeline
//   for multi-material fabrication. SIGGRAPH 2013, §4 (streaming: only a few layers in memory).
#include "print/slice_model.h"

#include "core/error.h"
#include "core/mip_pyramid.h"
#include "core/parallel.h"
#include "print/color_difference.h"
#include "print/icc_profile.h"
#include "print/png_row_encoder.h"
#include "print/slice_preview.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iterator>

namespace texfab::print {

namespace {

using Clock = std::chrono::steady_clock;

// CPU seconds per stage, summed over threads.
struct StageClock {
  std::atomic<int64_t> voxelize{0}, color{0}, dither{0}, encode{0}, write{0};
  static int64_t since(Clock::time_point& t) {
    const Clock::time_point now = Clock::now();
    const int64_t ns = std::chrono::duration_cast<std::chrono::nanoseconds>(now - t).count();
    t = now;
    return ns;
  }
};

const char* ditherName(DitherMode d) {
  return d == DitherMode::BlueNoise ? "blue-noise" : d == DitherMode::FloydSteinberg ? "floyd-steinberg" : "none";
}

// Sums of one 16 x 16 column of a layer, or of a 16^3 block: the requested and the printed colour
// (linear) of its opaque shell voxels.
struct BlockSums {
  static constexpr int kSide = 16;
  double want[3] = {0, 0, 0}, got[3] = {0, 0, 0};
  int64_t voxels = 0;
  void add(const BlockSums& o) {
    for (int c = 0; c < 3; ++c) want[c] += o.want[c], got[c] += o.got[c];
    voxels += o.voxels;
  }
};

// PrintColorError over 16-layer bands: each layer's column sums are added in layer order (the
// figures do not depend on the thread count), and a band's blocks are measured once its last
// layer is in.
class PrintColorTally {
public:
  PrintColorTally(int width, int height)
      : columns_((width + BlockSums::kSide - 1) / BlockSums::kSide), rows_((height + BlockSums::kSide - 1) / BlockSums::kSide) {}
  std::vector<BlockSums> layerSums() const { return std::vector<BlockSums>(size_t(columns_) * size_t(rows_)); }
  size_t index(int x, int y) const { return size_t(y / BlockSums::kSide) * size_t(columns_) + size_t(x / BlockSums::kSide); }

  void add(int layer, const std::vector<BlockSums>& sums) {
    if (layer / BlockSums::kSide != band_) flush();
    band_ = layer / BlockSums::kSide;
    if (bandSums_.empty()) bandSums_ = layerSums();
    for (size_t i = 0; i < sums.size(); ++i) bandSums_[i].add(sums[i]);
  }

  PrintColorError finish() {
    flush();
    PrintColorError e;
    e.blocks = deltas_.size();
    if (deltas_.empty()) return e;
    for (double d : deltas_) e.mean += d, e.max = std::max(e.max, d);
    e.mean /= double(deltas_.size());
    std::vector<double> sorted = deltas_;
    const size_t k = std::min(sorted.size() - 1, size_t(std::ceil(0.95 * double(sorted.size()))) - 1);
    std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(k), sorted.end());
    e.p95 = sorted[k];
    return e;
  }

private:
  void flush() {
    constexpr int64_t kEnough = BlockSums::kSide * BlockSums::kSide * BlockSums::kSide / 2;
    for (const BlockSums& b : bandSums_) {
      if (b.voxels < kEnough) continue;
      std::array<double, 3> want, got;
      for (int c = 0; c < 3; ++c) want[size_t(c)] = b.want[c] / double(b.voxels), got[size_t(c)] = b.got[c] / double(b.voxels);
      deltas_.push_back(deltaE2000(labFromLinearSrgb(want), labFromLinearSrgb(got)));
    }
    bandSums_.clear();
  }

  int columns_, rows_;
  int band_ = -1;
  std::vector<BlockSums> bandSums_;
  std::vector<double> deltas_;
};

// What every layer of a run shares.
struct LayerSetup {
  const print::PrintGrid& grid;
  const SliceOptions& options;
  const VoxelColorSource& colors;
  const MaterialMixer* mixer = nullptr;        // dithered modes
  const BlueNoiseVolume* noise = nullptr;      // blue noise
  std::vector<Rgba8> palette;                  // index 0 empty, i material i - 1
  uint8_t core = 0;                            // palette index of the core material
  int channels = 1;                            // 1 indexed, 4 RGBA
  SlicePreview* preview = nullptr;
  const PrintColorTally* tally = nullptr;
};

// Adds a dithered row's opaque shell voxels to the layer's column sums: requested colour and the
// chosen material's.
void tallyRow(const LayerSetup& s, const PrintColorTally& tally, int y, std::span<const print::VoxelSpan> spans,
              const float* shell, const uint8_t* materials, std::vector<BlockSums>& sums) {
  for (const print::VoxelSpan& span : spans) {
    if (!span.shell) continue;
    for (int x = span.begin; x < span.end; ++x, shell += 4) {
      if (shell[3] < 1 || materials[x] == 0 || !s.options.materials[materials[x] - 1u].opaque()) continue;
      BlockSums& b = sums[tally.index(x, y)];
      const std::array<float, 3>& printed = s.mixer->linearColor(materials[x] - 1);
      for (int c = 0; c < 3; ++c) b.want[c] += std::clamp(shell[c], 0.0f, 1.0f), b.got[c] += printed[size_t(c)];
      ++b.voxels;
    }
  }
}

// One row of a layer as material indices (dithered) or continuous RGBA (DitherMode::None); a
// dithered row is tallied into `sums`.
void assembleRow(const LayerSetup& s, LayerDitherer* ditherer, int y, std::span<const print::VoxelSpan> spans,
                 const float* shell, uint8_t* out, std::vector<BlockSums>& sums) {
  const int w = s.grid.width;
  if (ditherer) {
    std::fill(out, out + w, uint8_t(0));
    for (const print::VoxelSpan& span : spans)
      if (!span.shell) std::fill(out + span.begin, out + span.end, s.core);
    ditherer->ditherRow(y, spans, shell, out);
    tallyRow(s, *s.tally, y, spans, shell, out, sums);
    if (s.channels == 4)  // material colours, expanded in place from the back
      for (int x = w - 1; x >= 0; --x) std::copy(s.palette[out[x]].begin(), s.palette[out[x]].end(), out + 4 * x);
    return;
  }
  std::fill(out, out + 4 * size_t(w), uint8_t(0));
  for (const print::VoxelSpan& span : spans)
    for (int x = span.begin; x < span.end; ++x) {
      uint8_t* p = out + 4 * x;
      if (!span.shell) {
        std::copy(s.palette[s.core].begin(), s.palette[s.core].end(), p);
        continue;
      }
      for (int c = 0; c < 3; ++c) p[c] = uint8_t(std::lround(255.0f * linearToSrgb(std::clamp(shell[c], 0.0f, 1.0f))));
      p[3] = uint8_t(std::lround(255.0f * std::clamp(shell[3], 0.0f, 1.0f)));
      shell += 4;
    }
}

// One layer, rendered row by row into a PNG; its colour sums (dithered modes) in `sums`.
std::vector<uint8_t> renderLayer(const LayerSetup& s, const print::LayerSpans& layer, StageClock& clock,
                                 std::vector<BlockSums>& sums) {
  const print::PrintGrid& g = s.grid;
  PngRowEncoder encoder(g.width, g.height, s.channels, s.palette,
                        {uint32_t(std::lround(1000.0 / g.pitchMm.x())), uint32_t(std::lround(1000.0 / g.pitchMm.y()))});
  std::optional<LayerDitherer> ditherer;
  if (s.options.dither != DitherMode::None) ditherer.emplace(*s.mixer, s.options.dither, s.noise, layer.layer, g.width);
  std::vector<float> shell(4 * size_t(g.width));
  std::vector<uint8_t> row(4 * size_t(g.width));
  std::vector<uint8_t> rgba(s.preview ? 4 * size_t(g.width) : 0);
  int64_t colorNs = 0, ditherNs = 0, encodeNs = 0;
  Clock::time_point t = Clock::now();
  for (int r = 0; r < g.height; ++r) {
    const int y = g.height - 1 - r;
    const std::span<const print::VoxelSpan> spans = layer.row(r);
    float* next = shell.data();
    for (const print::VoxelSpan& span : spans)
      if (span.shell) {
        s.colors.colors(layer.layer, y, span.begin, span.end, next);
        next += 4 * (span.end - span.begin);
      }
    colorNs += StageClock::since(t);
    assembleRow(s, ditherer ? &*ditherer : nullptr, y, spans, shell.data(), row.data(), sums);
    if (s.preview) {
      for (int x = 0; x < g.width; ++x)
        if (s.channels == 1) std::copy(s.palette[row[size_t(x)]].begin(), s.palette[row[size_t(x)]].end(), &rgba[4 * size_t(x)]);
      s.preview->addRow(layer.layer, r, spans, s.channels == 1 ? rgba.data() : row.data());
    }
    ditherNs += StageClock::since(t);
    encoder.addRow(row.data());
    encodeNs += StageClock::since(t);
  }
  std::vector<uint8_t> png = encoder.finish();
  encodeNs += StageClock::since(t);
  clock.color += colorNs;
  clock.dither += ditherNs;
  clock.encode += encodeNs;
  return png;
}

} // namespace

void SliceOptions::validate() const {
  if (firstLayer < 0) throw Error("the first layer must be >= 0, got " + std::to_string(firstLayer));
  if (layerCount < -1 || layerCount == 0) throw Error("the layer count must be positive, got " + std::to_string(layerCount));
  if (batchLayers < 1 || batchLayers > 4096) throw Error("batch of " + std::to_string(batchLayers) + " layers: 1-4096");
  validatePrintMaterials(materials, "materials");
  findPrintMaterial(materials, coreMaterial);
  if (format == SliceFormat::VoxelPrint)
    for (size_t i = 0; i < materials.size(); ++i)
      for (size_t j = 0; j < i; ++j)
        if (hexColor(materials[i].color) == hexColor(materials[j].color))
          throw Error("materials " + materials[j].name + " and " + materials[i].name + " have the same colour " +
                      hexColor(materials[i].color) + ": Voxel Print tells materials apart by colour");
  if (!iccProfile.empty()) checkMaterialsInGamut(materials, IccProfile(iccProfile), iccProfile.string());
}

namespace {

nlohmann::ordered_json sourceJson(const PrintSource& s) {
  nlohmann::ordered_json colors;
  switch (s.colors) {
  case PrintColors::Model: colors = {{"mode", "model"}}; break;
  case PrintColors::Solid:
    colors = {{"mode", "solid"}, {"method", synthesis::toString(s.method)}, {"exemplar", s.exemplar}, {"seed", s.seed},
              {"contrast_gain", s.contrastGain}, {"refine_passes", s.refinePasses}, {"texture_scale", s.textureScale},
              {"downsampled", s.downsampling}, {"sampling", toString(s.sampling)}};
    break;
  case PrintColors::Surface: colors = {{"mode", "surface"}, {"exemplar", s.exemplar}, {"seed", s.seed}}; break;
  }
  return {{"model", s.model}, {"colors", colors}};
}

// The manifest's "print" block.
nlohmann::ordered_json printInfo(const print::PrintGrid& g, const SliceOptions& o, double shellMm, const PrintSource& source) {
  nlohmann::ordered_json materials = nlohmann::ordered_json::array();
  for (size_t i = 0; i < o.materials.size(); ++i)
    materials.push_back({{"index", i + 1}, {"name", o.materials[i].name}, {"color", hexColor(o.materials[i].color)},
                         {"opacity", o.materials[i].opacity}});
  nlohmann::ordered_json info;
  info["image"] = {{"width", g.width},
                   {"height", g.height},
                   {"pixels", o.dither == DitherMode::None ? "rgba-color"
                              : o.format == SliceFormat::Indexed ? "indexed" : "rgba-material"},
                   {"empty", o.dither != DitherMode::None && o.format == SliceFormat::Indexed ? "index 0" : "alpha 0"},
                   {"row_0", "largest y (the layer seen from above, +x right, +y up)"}};
  info["layer_thickness_mm"] = g.pitchMm.z();
  info["dpi"] = {25.4 / g.pitchMm.x(), 25.4 / g.pitchMm.y()};
  info["voxel_mm"] = {g.pitchMm.x(), g.pitchMm.y(), g.pitchMm.z()};
  info["size_mm"] = {g.sizeMm().x(), g.sizeMm().y(), g.sizeMm().z()};
  info["mm_per_model_unit"] = g.mmPerUnit;
  info["origin_model_units"] = {g.origin.x(), g.origin.y(), g.origin.z()};
  info["materials"] = materials;
  info["core_material"] = o.materials[findPrintMaterial(o.materials, o.coreMaterial)].name;
  info["shell_mm"] = shellMm;
  info["dither"] = ditherName(o.dither);
  if (o.dither != DitherMode::None) info["mix"] = o.mixSpace == MixSpace::Perceptual ? "cielab" : "linear-rgb";
  if (!o.iccProfile.empty()) {  // named, described and fingerprinted: shards must share the profile
    std::ifstream in(o.iccProfile, std::ios::binary);
    const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    info["icc_profile"] = {{"file", o.iccProfile.filename().string()},
                           {"description", IccProfile(o.iccProfile).description()},
                           {"sha256", sha256Hex(bytes)}};
  }
  if (o.dither == DitherMode::BlueNoise) info["blue_noise_period"] = o.blueNoiseSize;
  info["format"] = o.format == SliceFormat::Indexed ? "png-indexed" : "voxelprint";
  info["source"] = sourceJson(source);
  return info;
}

} // namespace

uint64_t sliceMemoryBytes(const print::PrintGrid& g, const SliceOptions& o, const Context& ctx) {
  const int threads = ctx.threads > 0 ? ctx.threads : tbb::this_task_arena::max_concurrency();
  const int channels = o.dither == DitherMode::None || o.format == SliceFormat::VoxelPrint ? 4 : 1;
  const uint64_t pixels = uint64_t(g.width) * uint64_t(g.height);
  // Per layer in flight, at worst: its PNG (noise: 9 bits per byte) and its spans (a span per
  // voxel); per batch: the spans of its layers.
  const uint64_t perLayer = pixels * uint64_t(channels) * 9 / 8 + pixels * sizeof(print::VoxelSpan) / 4;
  return perLayer * uint64_t(std::max(1, threads) + std::max(1, o.batchLayers));
}

SliceResult sliceModel(const print::LayerVoxelizer& voxelizer, VoxelColorSource& colors, const SliceOptions& o,
                       SliceWriter& writer, const PrintSource& source, const Context& ctx) {
  o.validate();
  const print::PrintGrid& g = voxelizer.grid();
  if (o.firstLayer >= g.layers)
    throw Error("layer " + std::to_string(o.firstLayer) + " is beyond the print's " + std::to_string(g.layers) + " layers");
  const int count = o.layerCount < 0 ? g.layers - o.firstLayer : o.layerCount;
  if (o.firstLayer + count > g.layers)
    throw Error("layers " + std::to_string(o.firstLayer) + ":" + std::to_string(o.firstLayer + count) +
                " reach beyond the print's " + std::to_string(g.layers) + " layers");
  const Clock::time_point start = Clock::now();
  std::optional<MaterialMixer> mixer;
  std::optional<BlueNoiseVolume> noise;
  if (o.dither != DitherMode::None) {
    const std::optional<IccProfile> profile = o.iccProfile.empty() ? std::nullopt : std::optional(IccProfile(o.iccProfile));
    mixer.emplace(o.materials, MaterialMixerOptions{o.mixSpace, profile ? &*profile : nullptr});
  }
  std::optional<SlicePreview> preview;
  if (o.preview) preview.emplace(g, o.firstLayer, count);
  PrintColorTally tally(g.width, g.height);
  LayerSetup setup{g, o, colors, mixer ? &*mixer : nullptr, nullptr, {}, 0, 1, preview ? &*preview : nullptr, &tally};
  setup.palette.push_back({0, 0, 0, 0});
  for (const PrintMaterial& m : o.materials) setup.palette.push_back(m.color);
  setup.core = uint8_t(findPrintMaterial(o.materials, o.coreMaterial) + 1);
  setup.channels = o.dither == DitherMode::None || o.format == SliceFormat::VoxelPrint ? 4 : 1;

  SliceResult result;
  StageClock clock;
  std::atomic<int> done{0};
  std::atomic<int64_t> inside{0}, shellVoxels{0};
  std::atomic<uint64_t> bytes{0};
  Stage stage(ctx, "slice");
  for (int batch = o.firstLayer; batch < o.firstLayer + count; batch += o.batchLayers) {
    const int n = std::min(o.batchLayers, o.firstLayer + count - batch);
    std::vector<print::LayerSpans> spans(static_cast<size_t>(n));
    // Item -1 of the first batch builds the blue-noise array (serial work) beside the voxelization.
    const int extra = o.dither == DitherMode::BlueNoise && !noise ? 1 : 0;
    parallelFor(-extra, n, ctx, [&](int b, int e) {
      Clock::time_point t = Clock::now();
      for (int i = b; i < e; ++i)
        if (i < 0) noise = blueNoiseVolume(o.blueNoiseSize, g.pitchMm);
        else spans[size_t(i)] = voxelizer.voxelize(batch + i);
      clock.voxelize += StageClock::since(t);
    });
    setup.noise = noise ? &*noise : nullptr;
    Clock::time_point t = Clock::now();
    colors.prepare(spans, stage.inner());
    result.report.prepareSeconds += double(StageClock::since(t)) * 1e-9;
    std::vector<std::vector<BlockSums>> sums(static_cast<size_t>(n));
    parallelFor(0, n, ctx, [&](int b, int e) {
      for (int i = b; i < e; ++i) {
        const print::LayerSpans& layer = spans[size_t(i)];
        if (mixer) sums[size_t(i)] = tally.layerSums();
        const std::vector<uint8_t> png = renderLayer(setup, layer, clock, sums[size_t(i)]);
        Clock::time_point w = Clock::now();
        writer.writeLayer(layer.layer, g.layers, png);
        clock.write += StageClock::since(w);
        inside += layer.insideVoxels();
        shellVoxels += layer.shellVoxels();
        bytes += png.size();
        stage.advance(int64_t(++done), int64_t(count));
      }
    });
    if (mixer)
      for (int i = 0; i < n; ++i) tally.add(batch + i, sums[size_t(i)]);
  }
  writer.seal(printInfo(g, o, voxelizer.options().shellMm, source), o.firstLayer, count, g.layers);
  SliceReport& r = result.report;
  r.layers = count;
  r.colorError = tally.finish();
  r.insideVoxels = inside;
  r.shellVoxels = shellVoxels;
  r.bytes = bytes;
  r.voxelizeSeconds = double(clock.voxelize) * 1e-9;
  r.colorSeconds = double(clock.color) * 1e-9;
  r.ditherSeconds = double(clock.dither) * 1e-9;
  r.encodeSeconds = double(clock.encode) * 1e-9;
  r.writeSeconds = double(clock.write) * 1e-9;
  r.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  if (preview) result.preview = preview->compose();
  stage.finish(std::to_string(count) + " layers, " + std::to_string(r.shellVoxels) + " shell voxels of " +
               std::to_string(r.insideVoxels));
  return result;
}

} // namespace texfab::print
