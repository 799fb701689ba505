// SPDX-License-Identifier: GPL-3.0-or-later
#include "python/src/convert.h"

#include "core/image_io.h"
#include "synthesis/solid_tiles.h"

#include <pybind11/stl.h>

#include <chrono>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <thread>

namespace texfab::python {

py::array imageArray(std::shared_ptr<const Image> image) {
  const auto c = py::ssize_t(image->channels), w = py::ssize_t(image->width), h = py::ssize_t(image->height);
  const auto f = py::ssize_t(sizeof(float));
  const float* data = image->pixels.data();
  auto* owner = new std::shared_ptr<const Image>(std::move(image));
  py::capsule base(owner, [](void* p) { delete static_cast<std::shared_ptr<const Image>*>(p); });
  py::array array(py::dtype::of<float>(), {h, w, c}, {w * c * f, c * f, f}, data, base);
  py::detail::array_proxy(array.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return array;
}

py::array imageArray(Image image) { return imageArray(std::make_shared<const Image>(std::move(image))); }

py::object optionalImageArray(std::shared_ptr<const Image> image) {
  return image ? py::object(imageArray(std::move(image))) : py::object(py::none());
}

bool isPath(const py::handle& value) {
  return py::isinstance<py::str>(value) || py::hasattr(value, "__fspath__");
}

std::filesystem::path toPath(const py::handle& value) {
  return std::filesystem::path(py::str(py::module_::import("os").attr("fspath")(value)).cast<std::string>());
}

Image toImage(const py::handle& imageLike, const std::string& what) {
  if (isPath(imageLike)) return readImage(toPath(imageLike));
  const py::array any = py::array::ensure(imageLike);
  if (!any || (any.ndim() != 2 && any.ndim() != 3))
    throw Error(what + ": expected a file or an array of shape (H, W) or (H, W, C)");
  const int h = int(any.shape(0)), w = int(any.shape(1)), c = any.ndim() == 3 ? int(any.shape(2)) : 1;
  if (h < 1 || w < 1 || c < 1 || c > 4) throw Error(what + ": expected 1 to 4 channels and a non-empty image");
  const bool u8 = any.dtype().is(py::dtype::of<uint8_t>()), u16 = any.dtype().is(py::dtype::of<uint16_t>());
  Image image(w, h, c, u8 ? PixelFormat::UInt8 : u16 ? PixelFormat::UInt16 : PixelFormat::Float);
  const auto values = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(any);
  std::memcpy(image.pixels.data(), values.data(), image.pixels.size() * sizeof(float));
  const float scale = u8 ? 1.0f / 255.0f : u16 ? 1.0f / 65535.0f : 1.0f;
  for (float& v : image.pixels) {
    v *= scale;
    if (!std::isfinite(v)) throw Error(what + ": the image holds a NaN or infinite value");
  }
  return image;
}

synthesis::SolidMethod solidMethod(const std::string& name) {
  return choose<synthesis::SolidMethod>(name, "solid_method", {{"lazy", synthesis::SolidMethod::Lazy}, {"tiles", synthesis::SolidMethod::Tiles}});
}

synthesis::SolidSynthesisOptions solidOptions(uint32_t seed, const std::string& method, float contrastGain, int refine) {
  synthesis::SolidSynthesisOptions o;
  o.seed = seed;
  o.method = solidMethod(method);
  o.contrastGain = contrastGain;
  o.refinePasses = refine;
  o.validate();
  return o;
}

std::pair<int, int> toSize(const py::handle& value, const std::string& what) {
  if (py::isinstance<py::int_>(value)) return {value.cast<int>(), value.cast<int>()};
  const auto pair = value.cast<std::vector<int>>();
  if (pair.size() != 2) throw Error(what + ": expected N or (W, H)");
  return {pair[0], pair[1]};
}

Call::Call(int threads, const std::string& backend, py::object cacheDir, py::object progress) {
  ctx_.threads = threads;
  ctx_.backend = choose<Backend>(backend, "backend", {{"cpu", Backend::Cpu}, {"vulkan", Backend::Vulkan}, {"auto", Backend::Auto}});
  ctx_.cancel = &state_->cancel;
  if (cacheDir.is_none()) cache_.dir = synthesis::defaultCacheDir();
  else if (!(py::isinstance<py::bool_>(cacheDir) && !cacheDir.cast<bool>())) cache_.dir = toPath(cacheDir);
  state_->progress = std::move(progress);
  // The sink runs on texfab's threads: it takes the GIL and calls back.
  ctx_.progress = [state = state_](const ProgressEvent& e) {
    if (state->cancel.load()) return;
    py::gil_scoped_acquire gil;
    try {
      if (e.kind == ProgressEvent::Kind::Warning) {
        if (PyErr_WarnEx(PyExc_UserWarning, std::string(e.detail).c_str(), 1) != 0) throw py::error_already_set();
      } else if (!state->progress.is_none()) {
        const double fraction = e.kind == ProgressEvent::Kind::End ? 1.0 : e.fraction;
        const py::object answer = state->progress(std::string(e.stage), fraction);
        if (py::isinstance<py::bool_>(answer) && !answer.cast<bool>()) state->cancel = true;
      }
    } catch (py::error_already_set& error) {
      state->fail(error);
    }
  };
}

void Call::State::fail(py::error_already_set& e) {
  if (!error) error = std::make_unique<py::error_already_set>(std::move(e));
  cancel = true;
}

void Call::execute(const std::function<void()>& work) {
  std::exception_ptr failure;
  {
    py::gil_scoped_release release;
    std::mutex mutex;
    std::condition_variable finished;
    bool done = false;
    std::thread worker([&] {
      try {
        work();
      } catch (...) {
        failure = std::current_exception();
      }
      const std::lock_guard lock(mutex);
      done = true;
      finished.notify_one();
    });
    std::unique_lock lock(mutex);
    while (!finished.wait_for(lock, std::chrono::milliseconds(50), [&] { return done; })) {
      lock.unlock();
      {
        py::gil_scoped_acquire gil;  // Ctrl-C: signals are handled in the main thread only
        if (PyErr_CheckSignals() != 0) {
          py::error_already_set error;
          state_->fail(error);
        }
      }
      lock.lock();
    }
    lock.unlock();
    worker.join();
  }
  // A Python exception (the callback's, Ctrl-C) comes first: the work's Cancelled is its echo.
  if (std::unique_ptr<py::error_already_set> error = std::move(state_->error)) {
    error->restore();
    throw py::error_already_set();
  }
  if (failure) std::rethrow_exception(failure);
}

synthesis::ExemplarWrap chooseWrap(const std::string& choice, const Image& exemplar) {
  using synthesis::ExemplarWrap;
  if (choice == "auto") return synthesis::detectExemplarWrap(exemplar);
  return choose<ExemplarWrap>(choice, "wrap", {{"tile", ExemplarWrap::Tile}, {"clamp", ExemplarWrap::Clamp}});
}

synthesis::ExemplarAnalysis analyze2d(const Call& call, const Image& exemplar, const synthesis::AnalysisOptions& options) {
  synthesis::validateExemplarSize(exemplar);
  return synthesis::analyzeExemplar(exemplar, options, call.analysisCache(), call.ctx());
}

synthesis::SolidAnalysis analyzeSolid(const Call& call, const Image& exemplar, synthesis::ExemplarWrap wrap,
                                      synthesis::SolidMethod method, int tileSide) {
  synthesis::validateSolidExemplars(exemplar, exemplar, exemplar);
  synthesis::SolidAnalysisOptions options;
  options.wrap = wrap;
  synthesis::SolidTileOptions tiles;
  tiles.tileSide = tileSide;
  return synthesis::analyzeSolid(exemplar, exemplar, exemplar, options, method, tiles, call.analysisCache(), call.ctx());
}

} // namespace texfab::python
