// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The one layer every subcommand is built on:
//  - Flags binds command-line flags directly to the fields of the library's options structs: the
//    field's value is the default --help shows, every number goes through one parser (finite,
//    in range, named by its flag), choices map names to enums.
//  - CommonFlags are the flags commands share (--threads, --quiet, --report, the analysis cache);
//    a command picks the ones that apply.
//  - Run is a running command: its Context (threads, progress sink, cancel flag), its outputs
//    (checked before any work, committed together at the end) and its --report.
//
// A command (cmd_<name>.cpp) declares its flags and its run function:
//   Command addFooCommand(CLI::App& root) {
//     auto job = std::make_shared<FooJob>();  // paths, the options structs, CommonFlags
//     Flags f(root.add_subcommand("foo", "What foo does"));
//     f.input("model", job->model, "Input mesh");
//     f.option("--gutter", job->options.gutter, "Empty texels between charts", Range{2, 64});
//     f.common(job->common, Common::Threads | Common::Quiet | Common::Report);
//     return {f.app(), [job] { runFoo(*job); }};
//   }
// and runFoo opens a Run, reserves its outputs, reports stages through run.ctx() and calls
// run.finish().

#include "core/context.h"
#include "core/error.h"
#include "core/files.h"
#include "core/memory.h"
#include "geometry/io/mesh_io.h"
#include "geometry/up_axis.h"
#include "render/preview_renderer.h"
#include "synthesis/analyze_exemplar.h"

#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace texfab::cli {

class ProgressPrinter;

/// A command line that asks for something impossible (conflicting or missing flags): exit status 1,
/// where bad input is 2.
class UsageError : public Error {
public:
  using Error::Error;
};

/// The valid range of a number, stated the same way in --help and in errors: "2 to 64".
struct Range {
  double min = -1e300, max = 1e300;
  bool minExclusive = false;  ///< (min, max]: "greater than 0"
  std::string text() const;
  bool contains(double v) const { return (minExclusive ? v > min : v >= min) && v <= max; }
};
inline constexpr double kUnbounded = 1e300;
/// > 0
inline Range positive(double max = kUnbounded) { return {0, max, true}; }

/// Every number given on the command line goes through this: finite, in range (integers: whole),
/// else a CLI::ValidationError naming `flag`.
double parseNumber(const std::string& flag, const std::string& text, const Range& range = {}, bool integer = false);
/// "1,2,3" (exactly `count` numbers, or any number when count is 0).
std::vector<double> parseNumbers(const std::string& flag, const std::string& text, size_t count, const Range& range = {},
                                 bool integer = false);
/// "N" (square) or "WxH", each side in `range`.
std::pair<int, int> parseSize(const std::string& flag, const std::string& text, const Range& range,
                              bool powerOfTwo = false);
/// "512M", "2G", "1.5G", "4096" (bytes); K, M, G, T are powers of 1024.
uint64_t parseBytes(const std::string& flag, const std::string& text);

/// Name/value pairs of an enum, for Flags::choice; the first name of a value is the one shown.
template <class E>
using Names = std::vector<std::pair<std::string, E>>;

template <class E>
const std::string& nameOf(const Names<E>& names, E value) {
  for (const auto& [name, v] : names)
    if (v == value) return name;
  static const std::string unknown = "?";
  return unknown;
}

/// Which common flags a command takes.
namespace Common {
enum : unsigned {
  Threads = 1,  ///< --threads N
  Quiet = 2,    ///< -q,--quiet
  Report = 4,   ///< --report FILE
  Cache = 8,    ///< --cache-dir, --no-cache, --cache-size
  Backend = 16, ///< --backend cpu|vulkan|auto, --device N
  Memory = 32,  ///< --max-memory BYTES
};
}

struct CommonFlags {
  int threads = 0;
  bool quiet = false;
  std::string report;
  std::string cacheDir;  ///< empty: synthesis::defaultCacheDir()
  bool noCache = false;
  uint64_t cacheBytes = uint64_t(1) << 30;
  texfab::Backend backend = texfab::Backend::Cpu;
  int device = -1;  ///< -1: $TEXFAB_VULKAN_DEVICE, else the best device
  uint64_t maxMemory = 0;  ///< bytes the job may plan to use; 0: kDefaultMemoryShare of the machine's
};

/// --up: the model's up axis, or none (auto) for its file's convention.
using UpChoice = std::optional<geometry::UpAxis>;
/// The axis given, else the model file's (geometry::conventionalUpAxis).
geometry::UpAxis upAxisFor(const UpChoice& choice, const std::filesystem::path& model);
/// Throws UsageError when --unit or --height (Flags::printSize) is given for an output that is not 3MF.
void checkPrintSize(const geometry::MeshWriteOptions& options, const std::string& output);

/// Declares the flags of one subcommand, bound to the fields they set.
class Flags {
public:
  explicit Flags(CLI::App* app) : app_(app) {}
  CLI::App* app() const { return app_; }

  /// A required positional argument.
  CLI::Option* input(const std::string& name, std::string& value, const std::string& help);
  /// A text value (file names and the like).
  CLI::Option* text(const std::string& flags, std::string& value, const std::string& help);
  CLI::Option* flag(const std::string& flags, bool& value, const std::string& help);
  /// A number field; its current value is the default shown. `range` is appended to the help.
  template <class T>
    requires std::is_arithmetic_v<T>
  CLI::Option* option(const std::string& flags, T& field, const std::string& help, const Range& range = {}) {
    constexpr bool integer = std::is_integral_v<T>;
    Range within = range;  // and within what T holds
    within.min = std::max(within.min, integer ? double(std::numeric_limits<T>::lowest()) : -double(std::numeric_limits<T>::max()));
    within.max = std::min(within.max, double(std::numeric_limits<T>::max()));
    CLI::Option* o = number(flags, help, within, integer, [&field](double v) { field = T(v); });
    o->type_name(integer ? (std::is_signed_v<T> ? "INT" : "UINT") : "FLOAT");
    o->default_str(show(double(field)));
    return o;
  }
  /// An X,Y,Z vector field (not the zero vector).
  CLI::Option* option(const std::string& flags, Eigen::Vector3f& field, const std::string& help);
  /// A list of numbers, one or more (each in `range`).
  CLI::Option* option(const std::string& flags, std::vector<float>& field, const std::string& help, const Range& range);
  /// `count` comma-separated numbers (any count when 0) handed to `set`; `typeName` shows their
  /// meaning ("X,Y,W,H").
  CLI::Option* numbers(const std::string& flags, size_t count, const std::string& typeName, const std::string& help,
                       const Range& range, bool integer, std::function<void(const std::vector<double>&)> set);
  /// An enum field set by name.
  template <class E>
  CLI::Option* choice(const std::string& flags, E& field, const Names<E>& names, const std::string& help) {
    std::string list;
    for (const auto& [name, v] : names) list += (list.empty() ? "" : "|") + name;
    CLI::Option* o = app_->add_option_function<std::string>(
        flags,
        [&field, names, list, f = longName(flags)](const std::string& text) {
          for (const auto& [name, v] : names)
            if (name == text) return void(field = v);
          throw CLI::ValidationError(f, "expected " + list + ", got '" + text + "'");
        },
        help);
    o->type_name(list);
    o->default_str(nameOf(names, field));
    return o;
  }
  /// A width x height field pair, "N" or "WxH"; with `allowAuto`, also "auto" (0 x 0).
  CLI::Option* size(const std::string& flags, int& width, int& height, const std::string& help, const Range& range,
                    bool powerOfTwo = false, bool allowAuto = false);
  /// --up, the model's up axis for previews.
  CLI::Option* up(UpChoice& axis);
  /// --azimuth and --elevation, where a preview's camera stands, and --no-ndf-filtering.
  void camera(render::RenderOptions& o);
  /// The common flags the command takes (Common::Threads | ...).
  void common(CommonFlags& flags, unsigned which);
  /// How a written model stores its geometry and textures: --draco, --texture-format,
  /// --texture-quality, --embed.
  void modelOutput(geometry::MeshWriteOptions& options);
  /// --unit and --height: the size of a 3MF output (3MF's coordinates are millimetres).
  void printSize(geometry::MeshWriteOptions& options);
  /// --unit: millimetres per model unit, by name (mm, cm, m, in, ft, um) or as a number.
  CLI::Option* unit(double& millimetresPerUnit);

private:
  CLI::Option* number(const std::string& flags, const std::string& help, const Range& range, bool integer,
                      std::function<void(double)> set);
  static std::string longName(const std::string& flags);
  static std::string show(double v);
  CLI::App* app_;
};

/// A running command: the context its library calls take, its outputs and its report.
class Run {
public:
  /// `command` is the subcommand's name ("texture"). Reserves the --report file and opens the
  /// --backend device, so that a missing one is an error before any work.
  Run(const std::string& command, const CommonFlags& common);
  ~Run();
  Run(const Run&) = delete;
  Run& operator=(const Run&) = delete;

  const Context& ctx() const { return ctx_; }
  /// Reserves an output file, checking now that it can be written; returns where to write it.
  std::filesystem::path output(const std::filesystem::path& path) { return outputs_.add(path); }
  OutputSet& outputs() { return outputs_; }
  /// The report (written when --report is given); commands add their blocks.
  nlohmann::json& report() { return report_; }
  bool reporting() const { return !reportPath_.empty(); }
  /// A line of information on stderr (not with --quiet).
  void note(const std::string& message) const;
  /// Refuses work whose memory estimate `bytes` exceeds --max-memory (texfab::checkMemory).
  void checkMemory(double bytes, const std::string& what) const { texfab::checkMemory(bytes, what, common_.maxMemory); }
  /// The analysis cache: --cache-dir (no folder with --no-cache) kept within --cache-size.
  synthesis::AnalysisCacheSettings analysisCache() const;
  /// Writes the report (timings and peak memory added) and commits every output.
  void finish();

private:
  void openBackend();
  std::string command_;
  CommonFlags common_;
  std::unique_ptr<ProgressPrinter> printer_;
  Context ctx_;
  OutputSet outputs_;
  std::filesystem::path reportPath_;  // staged
  nlohmann::json report_ = nlohmann::json::object();
};

/// The flag that requests a cancel (set by SIGINT/SIGTERM; see main.cpp).
const std::atomic<bool>& cancelFlag();

} // namespace texfab::cli
