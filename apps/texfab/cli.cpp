// SPDX-License-Identifier: GPL-3.0-or-later
#include "apps/texfab/cli.h"

#include "apps/texfab/progress.h"
#include "synthesis/analysis_cache.h"
#include "synthesis/backend.h"
#include "synthesis/exemplar_analysis.h"

#include <sys/resource.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>

namespace texfab::cli {
namespace fs = std::filesystem;

namespace {

std::string formatNumber(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.10g", v);
  return text;
}

double peakMemoryMiB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;  // Linux reports KiB
}

} // namespace

std::string Range::text() const {
  // Bounds beyond any float are the limits of a type, not worth stating.
  const bool low = min > -1e38, high = max < 1e38;
  if (low && high) return minExclusive ? "greater than " + formatNumber(min) + " and at most " + formatNumber(max)
                                       : formatNumber(min) + " to " + formatNumber(max);
  if (low) return (minExclusive ? "greater than " : "at least ") + formatNumber(min);
  if (high) return "at most " + formatNumber(max);
  return {};
}

double parseNumber(const std::string& flag, const std::string& text, const Range& range, bool integer) {
  const char* begin = text.data() + (text.starts_with('+') ? 1 : 0);
  double value = 0;
  const auto [end, ec] = std::from_chars(begin, text.data() + text.size(), value);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size())
    throw CLI::ValidationError(flag, "'" + text + "' is not a number");
  if (!std::isfinite(value)) throw CLI::ValidationError(flag, "'" + text + "' is not a finite number");
  if (integer && value != std::floor(value)) throw CLI::ValidationError(flag, "'" + text + "' is not a whole number");
  if (!range.contains(value)) throw CLI::ValidationError(flag, "must be " + range.text() + ", got " + text);
  return value;
}

std::vector<double> parseNumbers(const std::string& flag, const std::string& text, size_t count, const Range& range,
                                 bool integer) {
  std::vector<double> values;
  size_t begin = 0;
  while (begin <= text.size()) {
    const size_t end = std::min(text.find(',', begin), text.size());
    values.push_back(parseNumber(flag, text.substr(begin, end - begin), range, integer));
    begin = end + 1;
  }
  if (count && values.size() != count)
    throw CLI::ValidationError(flag, "expected " + std::to_string(count) + " comma-separated numbers, got '" + text + "'");
  return values;
}

std::pair<int, int> parseSize(const std::string& flag, const std::string& text, const Range& range, bool powerOfTwo) {
  const size_t x = text.find_first_of("xX");
  const std::string w = text.substr(0, x), h = x == std::string::npos ? w : text.substr(x + 1);
  std::pair<int, int> size;
  try {
    size = {int(parseNumber(flag, w, range, true)), int(parseNumber(flag, h, range, true))};
  } catch (const CLI::ValidationError&) {
    throw CLI::ValidationError(flag, "expected N or WxH, each " + range.text() + (powerOfTwo ? " and a power of two" : "") +
                                         ", got '" + text + "'");
  }
  auto pow2 = [](int v) { return (v & (v - 1)) == 0; };
  if (powerOfTwo && !(pow2(size.first) && pow2(size.second)))
    throw CLI::ValidationError(flag, "sides must be powers of two, got '" + text + "'");
  return size;
}

uint64_t parseBytes(const std::string& flag, const std::string& text) {
  std::string digits = text;
  double unit = 1;
  const std::string suffixes = "KMGT";
  while (!digits.empty() && (digits.back() == 'B' || digits.back() == 'b' || digits.back() == 'i')) digits.pop_back();
  if (!digits.empty()) {
    const size_t s = suffixes.find(char(std::toupper(static_cast<unsigned char>(digits.back()))));
    if (s != std::string::npos) {
      unit = std::pow(1024.0, double(s + 1));
      digits.pop_back();
    }
  }
  try {
    return uint64_t(parseNumber(flag, digits, {0, 1e18 / unit}) * unit);
  } catch (const CLI::ValidationError&) {
    throw CLI::ValidationError(flag, "expected a size such as 512M or 2G, got '" + text + "'");
  }
}

// Flags --------------------------------------------------------------------------------------

std::string Flags::longName(const std::string& flags) {  // the first "--name" ("-o,--output": --output)
  for (size_t begin = 0; begin < flags.size();) {
    const size_t end = std::min(flags.find(',', begin), flags.size());
    if (flags.compare(begin, 2, "--") == 0) return flags.substr(begin, end - begin);
    begin = end + 1;
  }
  return flags;
}

std::string Flags::show(double v) { return formatNumber(v); }

CLI::Option* Flags::input(const std::string& name, std::string& value, const std::string& help) {
  return app_->add_option(name, value, help)->required();
}

CLI::Option* Flags::text(const std::string& flags, std::string& value, const std::string& help) {
  return app_->add_option(flags, value, help);
}

CLI::Option* Flags::flag(const std::string& flags, bool& value, const std::string& help) {
  return app_->add_flag(flags, value, help);
}

CLI::Option* Flags::number(const std::string& flags, const std::string& help, const Range& range, bool integer,
                           std::function<void(double)> set) {
  const std::string described = range.text().empty() ? help : help + " (" + range.text() + ")";
  return app_->add_option_function<std::string>(
      flags, [set, range, integer, f = longName(flags)](const std::string& text) { set(parseNumber(f, text, range, integer)); },
      described);
}

CLI::Option* Flags::numbers(const std::string& flags, size_t count, const std::string& typeName,
                            const std::string& help, const Range& range, bool integer,
                            std::function<void(const std::vector<double>&)> set) {
  const std::string described = range.text().empty() ? help : help + " (each " + range.text() + ")";
  CLI::Option* o = app_->add_option_function<std::string>(
      flags,
      [set, count, range, integer, f = longName(flags)](const std::string& text) {
        set(parseNumbers(f, text, count, range, integer));
      },
      described);
  o->type_name(typeName);
  return o;
}

CLI::Option* Flags::option(const std::string& flags, Eigen::Vector3f& field, const std::string& help) {
  CLI::Option* o = numbers(flags, 3, "X,Y,Z", help, {}, false, [&field, f = longName(flags)](const std::vector<double>& v) {
    field = Eigen::Vector3f(float(v[0]), float(v[1]), float(v[2]));
    if (!(field.norm() > 0)) throw CLI::ValidationError(f, "must not be the zero vector");
  });
  o->default_str(show(field.x()) + "," + show(field.y()) + "," + show(field.z()));
  return o;
}

CLI::Option* Flags::option(const std::string& flags, std::vector<float>& field, const std::string& help,
                           const Range& range) {
  return numbers(flags, 0, "X[,X...]", help, range, false,
                 [&field](const std::vector<double>& v) { field.assign(v.begin(), v.end()); });
}

CLI::Option* Flags::size(const std::string& flags, int& width, int& height, const std::string& help, const Range& range,
                         bool powerOfTwo, bool allowAuto) {
  CLI::Option* o = app_->add_option_function<std::string>(
      flags,
      [&width, &height, range, powerOfTwo, allowAuto, f = longName(flags)](const std::string& text) {
        if (allowAuto && text == "auto") width = height = 0;
        else std::tie(width, height) = parseSize(f, text, range, powerOfTwo);
      },
      help + " (" + (allowAuto ? "auto, " : "") + "N for NxN, or WxH; " + range.text() +
          (powerOfTwo ? ", powers of two" : "") + " per side)");
  o->type_name(allowAuto ? "auto|N|WxH" : "N|WxH");
  o->default_str(width == 0 && height == 0 ? "auto"
                 : width == height        ? std::to_string(width)
                                          : std::to_string(width) + "x" + std::to_string(height));
  return o;
}

void Flags::common(CommonFlags& c, unsigned which) {
  if (which & Common::Threads)
    option("--threads", c.threads, "Worker threads, 0 = all cores; results do not depend on it", Range{0, 4096});
  if (which & Common::Report) text("--report", c.report, "Also write figures and stage timings to this JSON file");
  if (which & Common::Cache) {
    text("--cache-dir", c.cacheDir, "Exemplar analysis cache folder (default: $TEXFAB_CACHE_DIR, else ~/.cache/texfab)");
    flag("--no-cache", c.noCache, "Neither read nor write the analysis cache");
    CLI::Option* o = app_->add_option_function<std::string>(
        "--cache-size", [&c](const std::string& text) { c.cacheBytes = parseBytes("--cache-size", text); },
        "Largest size of the cache folder; the least recently used analyses are removed beyond it");
    o->type_name("BYTES");
    o->default_str("1G");
  }
  if (which & Common::Backend) {
    choice("--backend", c.backend, {{"cpu", Backend::Cpu}, {"vulkan", Backend::Vulkan}, {"auto", Backend::Auto}},
           "Where the synthesis kernels run: cpu, vulkan (a Vulkan device; error without one) or auto (a Vulkan "
           "GPU when there is one, else the CPU; a device that emulates a GPU on the CPU only if --device names it); "
           "the result does not depend on it");
    option("--device", c.device, "Vulkan device index (texfab info --devices lists them)", Range{0, 1024})
        ->default_str("$TEXFAB_VULKAN_DEVICE, else the best");
  }
  if (which & Common::Memory) {
    CLI::Option* o = app_->add_option_function<std::string>(
        "--max-memory", [&c](const std::string& text) { c.maxMemory = parseBytes("--max-memory", text); },
        "Refuse work whose memory estimate exceeds this (e.g. 4G), before it starts");
    o->type_name("BYTES");
    o->default_str(std::to_string(int(kDefaultMemoryShare * 100)) + "% of RAM");
  }
  if (which & Common::Quiet) flag("-q,--quiet", c.quiet, "No progress output (warnings and errors are still printed)");
}

geometry::UpAxis upAxisFor(const UpChoice& choice, const fs::path& model) {
  return choice ? *choice : geometry::conventionalUpAxis(model);
}

CLI::Option* Flags::up(UpChoice& axis) {
  using geometry::UpAxis;
  return choice("--up", axis,
                Names<UpChoice>{{"auto", std::nullopt}, {"x", UpAxis::X}, {"-x", UpAxis::NegX}, {"y", UpAxis::Y},
                                {"-y", UpAxis::NegY}, {"z", UpAxis::Z}, {"-z", UpAxis::NegZ}},
                "The model's up axis (auto: z for STL, as 3-D printing uses, else y as glTF and OBJ do): previews "
                "stand the model on it and look at its front; a 3MF output builds along it");
}

void Flags::camera(render::RenderOptions& o) {
  option("--azimuth", o.azimuthDegrees, "Camera angle around the up axis, degrees (0 = from the model's front)",
         {-3600, 3600});
  option("--elevation", o.elevationDegrees, "Camera angle above the horizon, degrees", {-89.9, 89.9});
  using render::NormalMapFiltering;
  choice("--normal-filtering", o.normalMapFiltering,
         Names<NormalMapFiltering>{
             {"lobes", NormalMapFiltering::Lobes}, {"toksvig", NormalMapFiltering::Toksvig}, {"mip", NormalMapFiltering::Mip}},
         "How normal maps seen from afar shade: lobes, from their fitted normal distributions (Han et al. 2007: "
         "about 3-5 s more for a 1024^2 normal map on a glossy or metallic material); toksvig, from one lobe "
         "widened by the MIP-mapped normal's shortening (Toksvig 2005: no fit, less exact); mip, from the "
         "MIP-mapped normals (bumps then look flat and shiny). A .glb/.gltf that texture writes with a normal map "
         "also carries, unless mip, roughness and anisotropy MIP chains widened by the normals' spread (KTX2, "
         "KHR_texture_basisu and KHR_materials_anisotropy, for viewers that read them; the PNGs stay the fallback)");
  app_->add_flag_function(
      "--no-ndf-filtering", [&o](int64_t) { o.normalMapFiltering = NormalMapFiltering::Mip; },
      "The same as --normal-filtering mip");
  using render::SpecularModel;
  choice("--specular", o.specular,
         Names<SpecularModel>{{"blinn-phong", SpecularModel::BlinnPhong}, {"microfacet", SpecularModel::Microfacet}},
         "The key light's highlight in previews: blinn-phong (normalized, no Fresnel), or microfacet (glTF's "
         "metallic-roughness BRDF: GGX, Smith masking, Schlick's Fresnel, as glTF viewers shade)");
}

void Flags::modelOutput(geometry::MeshWriteOptions& o) {
  using geometry::TextureEncoding;
  flag("--draco", o.draco, "Compress the geometry with Draco (KHR_draco_mesh_compression; .glb and .gltf)");
  const Names<TextureEncoding> formats{{"auto", TextureEncoding::Keep},
                                       {"png", TextureEncoding::Png},
                                       {"jpeg", TextureEncoding::Jpeg},
                                       {"webp", TextureEncoding::Webp}};
  CLI::Option* format = app_->add_option_function<std::string>(
      "--texture-format",
      [&o, formats](const std::string& text) {
        if (text == "ktx2")
          throw CLI::ValidationError("--texture-format", "ktx2 is not available: Debian 12 packages no KTX2/Basis "
                                                         "Universal encoder library");
        for (const auto& [name, v] : formats)
          if (name == text || (text == "jpg" && v == TextureEncoding::Jpeg)) return void(o.textures = v);
        throw CLI::ValidationError("--texture-format", "expected auto, png, jpeg or webp, got '" + text + "'");
      },
      "Texture images: png (lossless), jpeg, webp (glTF: EXT_texture_webp), or auto: images read from a PNG, "
      "JPEG or WebP file keep their bytes, new maps are PNG");
  format->type_name("auto|png|jpeg|webp");
  format->default_str(nameOf(formats, o.textures));
  option("--texture-quality", o.textureQuality, "JPEG and WebP quality", Range{1, 100});
  flag("--embed", o.embed, ".gltf output: buffers and images inside the file as data URIs, not beside it");
}

void checkPrintSize(const geometry::MeshWriteOptions& o, const std::string& output) {
  if ((o.millimetresPerUnit > 0 || o.heightMm > 0) && geometry::meshFormatOf(output) != geometry::MeshFormat::ThreeMf)
    throw UsageError(std::string(o.heightMm > 0 ? "--height" : "--unit") + " sizes a 3MF output, not " + output);
}

CLI::Option* Flags::unit(double& millimetresPerUnit) {
  static const std::pair<const char*, double> units[] = {{"mm", 1.0},  {"cm", 10.0},   {"m", 1000.0},
                                                         {"in", 25.4}, {"ft", 304.8}, {"um", 0.001}};
  CLI::Option* o = app_->add_option_function<std::string>(
      "--unit",
      [&millimetresPerUnit](const std::string& text) {
        for (const auto& [name, mm] : units)
          if (name == text) return void(millimetresPerUnit = mm);
        double mm = 0;
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), mm);
        if (ec != std::errc() || end != text.data() + text.size() || !(mm > 0) || !(mm <= 1e6))
          throw CLI::ValidationError("--unit", "expected mm, cm, m, in, ft, um or millimetres per unit in (0, 1e6], got '" +
                                                   text + "'");
        millimetresPerUnit = mm;
      },
      "The model's length unit: mm, cm, m, in, ft, um, or millimetres per unit (instead of --height)");
  o->type_name("UNIT|MM");
  o->default_str("mm");
  return o;
}

void Flags::printSize(geometry::MeshWriteOptions& o) {
  CLI::Option* units = unit(o.millimetresPerUnit);
  units->description("3MF output: the model's length unit (mm, cm, m, in, ft, um, or millimetres per unit); 3MF is "
                     "written in millimetres");
  CLI::Option* height =
      option("--height", o.heightMm, "3MF output: scale the model to this height in mm along its up axis (--up)",
             positive(1e5));
  height->excludes(units);
  height->default_str("one model unit = 1 mm");
}

// Run ----------------------------------------------------------------------------------------

Run::Run(const std::string& command, const CommonFlags& common)
    : command_(command), common_(common), printer_(std::make_unique<ProgressPrinter>("texfab " + command, common.quiet)) {
  ctx_.threads = common.threads;
  ctx_.progress = [p = printer_.get()](const ProgressEvent& e) { (*p)(e); };
  ctx_.cancel = &cancelFlag();
  if (!common.report.empty()) reportPath_ = outputs_.add(common.report);
  openBackend();
}

void Run::openBackend() {
  ctx_.backend = common_.backend;
  ctx_.device = common_.device;
  if (common_.backend == Backend::Cpu) return;
  std::string line;
  Context probe = ctx_;
  probe.progress = [&line](const ProgressEvent& e) {
    if (e.kind == ProgressEvent::Kind::End && e.stage == "backend") line = e.detail;
  };
  try {
    synthesis::deviceFor(probe);
  } catch (const Cancelled&) {
    throw;
  } catch (const Error& e) {
    throw Error(std::string("--backend vulkan: ") + e.what());
  }
  if (!line.empty()) note("backend: " + line);
}

Run::~Run() = default;

void Run::note(const std::string& message) const { printer_->note(message); }

synthesis::AnalysisCacheSettings Run::analysisCache() const {
  synthesis::AnalysisCacheSettings cache;
  if (!common_.noCache) cache.dir = common_.cacheDir.empty() ? synthesis::defaultCacheDir() : fs::path(common_.cacheDir);
  cache.maxBytes = common_.cacheBytes;
  return cache;
}

void Run::finish() {
  if (reporting()) {
    report_["command"] = command_;
    report_["timings"] = printer_->timings();
    report_["peak_memory_mib"] = peakMemoryMiB();
    writeFileAtomically(reportPath_, [&](std::ostream& out) { out << report_.dump(2) << '\n'; });
  }
  outputs_.commit(ctx_);
}

} // namespace texfab::cli
