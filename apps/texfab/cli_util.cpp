// SPDX-License-Identifier: GPL-3.0-or-later
#include "apps/texfab/cli_util.h"

#include "render/image/error.h"
#include "render/image/files.h"
#include "render/image/image_io.h"

#include <sys/resource.h>

#include <charconv>
#include <cstdio>

namespace texfab::cli {

namespace {
int parseInt(const std::string& text, const std::string& what) {
  int value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || text.empty())
    throw Error(what + ": '" + text + "' is not an integer");
  return value;
}
} // namespace

std::pair<int, int> parseSize(const std::string& text, const std::string& what) {
  const size_t x = text.find_first_of("xX");
  const int w = parseInt(text.substr(0, x), what);
  const int h = x == std::string::npos ? w : parseInt(text.substr(x + 1), what);
  if (w < 1 || h < 1 || w > kMaxImageSide || h > kMaxImageSide)
    throw Error(what + ": size " + text + " is out of range (1 to " + std::to_string(kMaxImageSide) + " per side)");
  return {w, h};
}

std::vector<double> parseNumberList(const std::string& text, const std::string& what) {
  std::vector<double> values;
  size_t begin = 0;
  while (begin <= text.size()) {
    const size_t end = std::min(text.find(',', begin), text.size());
    const std::string item = text.substr(begin, end - begin);
    double value = 0;
    const auto [ptr, ec] = std::from_chars(item.data(), item.data() + item.size(), value);
    if (item.empty() || ec != std::errc() || ptr != item.data() + item.size())
      throw Error(what + ": '" + item + "' is not a number");
    values.push_back(value);
    begin = end + 1;
  }
  return values;
}

void Progress::start(std::string stage) {
  stage_ = std::move(stage);
  started_ = std::chrono::steady_clock::now();
}

double Progress::finish(const std::string& detail) {
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  record(stage_, seconds, detail);
  return seconds;
}

void Progress::record(const std::string& stage, double seconds, const std::string& detail) {
  timings_[stage] = seconds;
  if (!quiet_)
    std::fprintf(stderr, "%s: %-10s %7.3f s%s%s\n", command_.c_str(), stage.c_str(), seconds,
                 detail.empty() ? "" : "  ", detail.c_str());
}

void Progress::note(const std::string& message) const {
  if (!quiet_) std::fprintf(stderr, "%s: %s\n", command_.c_str(), message.c_str());
}

double peakMemoryMiB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;  // Linux reports KiB
}

void writeReport(const nlohmann::json& report, const std::filesystem::path& path) {
  writeFileAtomically(path, [&](std::ostream& out) { out << report.dump(2) << '\n'; });
}

} // namespace texfab::cli
