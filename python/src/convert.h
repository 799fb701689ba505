// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Conversions between Python values and texfab's types: images and numpy arrays, image-like
// arguments (a file or an array), names of choices ("surface", "tile", ...) and the shared
// arguments of every long call (threads, backend, cache folder, progress).

#include "core/context.h"
#include "core/image.h"
#include "geometry/mesh.h"
#include "synthesis/analyze_exemplar.h"
#include "synthesis/synthesize_solid.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <atomic>
#include <functional>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace texfab::python {
namespace py = pybind11;

/// A read-only float32 (H, W, C) view of an image that stays alive as long as the array.
py::array imageArray(std::shared_ptr<const Image> image);
py::array imageArray(Image image);
/// None for a null image.
py::object optionalImageArray(std::shared_ptr<const Image> image);

/// A file path (str or os.PathLike) or an array (H, W) or (H, W, C): uint8 and uint16 are
/// normalized to [0, 1] (and written back at their precision); other dtypes are read as float.
Image toImage(const py::handle& imageLike, const std::string& what);
bool isPath(const py::handle& value);
std::filesystem::path toPath(const py::handle& value);

/// A choice given by name; throws texfab::Error listing the names.
template <class T>
T choose(const std::string& value, const std::string& what, std::initializer_list<std::pair<const char*, T>> names) {
  std::string list;
  for (const auto& [name, v] : names) {
    if (value == name) return v;
    list += (list.empty() ? "" : ", ") + std::string(name);
  }
  throw Error(what + ": expected " + list + ", got '" + value + "'");
}

synthesis::SolidMethod solidMethod(const std::string& name);
/// The solid texture's settings as the functions take them (validated).
synthesis::SolidSynthesisOptions solidOptions(uint32_t seed, const std::string& method, float contrastGain, int refine);
/// (w, h) from an int or a pair.
std::pair<int, int> toSize(const py::handle& value, const std::string& what);

/// The arguments every long call shares, and the context they make. The work runs on a thread of
/// its own while the calling thread waits with the GIL released, every 50 ms looking for Ctrl-C.
/// The progress callback is called with the GIL held; False, an exception or Ctrl-C cancels the
/// work, and the Python exception is raised in the calling thread.
class Call {
public:
  Call(int threads, const std::string& backend, py::object cacheDir, py::object progress);
  const Context& ctx() const { return ctx_; }
  /// The analysis cache (no folder: none), kept within 1 GiB as the command line's default.
  const synthesis::AnalysisCacheSettings& analysisCache() const { return cache_; }
  /// Runs `work` (C++ only: no Python object may be touched) and returns its result.
  template <class F>
  auto run(F&& work) {
    std::optional<decltype(work())> result;
    execute([&] { result.emplace(work()); });
    return std::move(*result);
  }

private:
  struct State {
    py::object progress;
    std::atomic<bool> cancel{false};
    std::unique_ptr<py::error_already_set> error;  // touched with the GIL held only
    void fail(py::error_already_set& e);           // keeps the first error and cancels
  };
  void execute(const std::function<void()>& work);
  std::shared_ptr<State> state_ = std::make_shared<State>();
  Context ctx_;
  synthesis::AnalysisCacheSettings cache_;
};

/// The exemplar's wrap for a choice ("auto": measured on the exemplar, as the command line does).
synthesis::ExemplarWrap chooseWrap(const std::string& choice, const Image& exemplar);
/// The 2-D analysis, through the call's cache.
synthesis::ExemplarAnalysis analyze2d(const Call& call, const Image& exemplar, const synthesis::AnalysisOptions& options);
/// The solid analysis of one exemplar for the three axes, with its tile set for the tiles method,
/// through the call's cache.
synthesis::SolidAnalysis analyzeSolid(const Call& call, const Image& exemplar, synthesis::ExemplarWrap wrap,
                                      synthesis::SolidMethod method, int tileSide);

} // namespace texfab::python
