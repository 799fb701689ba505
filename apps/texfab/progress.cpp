// SPDX-License-Identifier: GPL-3.0-or-later
#include "apps/texfab/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace texfab::cli {

namespace {
bool stderrIsTerminal() {
  const char* term = std::getenv("TERM");
  return ::isatty(STDERR_FILENO) && !(term && std::strcmp(term, "dumb") == 0);
}
} // namespace

ProgressPrinter::ProgressPrinter(std::string prefix, bool quiet)
    : prefix_(std::move(prefix)), quiet_(quiet), terminal_(stderrIsTerminal()) {}

void ProgressPrinter::clearStatus() {
  if (!statusShown_) return;
  std::fputs("\r\033[K", stderr);
  statusShown_ = false;
}

void ProgressPrinter::printLine(const std::string& text) {
  clearStatus();
  std::fprintf(stderr, "%s: %s\n", prefix_.c_str(), text.c_str());
}

void ProgressPrinter::note(const std::string& message) {
  const std::lock_guard lock(mutex_);
  if (!quiet_) printLine(message);
}

void ProgressPrinter::operator()(const ProgressEvent& e) {
  const std::lock_guard lock(mutex_);
  const size_t depth = size_t(std::max(e.depth, 0));
  switch (e.kind) {
  case ProgressEvent::Kind::Warning:
    if (warned_.insert(std::string(e.detail)).second) printLine("warning: " + std::string(e.detail));
    return;
  case ProgressEvent::Kind::Begin:
    stages_.resize(depth + 1);
    stages_[depth] = e.stage;
    [[fallthrough]];
  case ProgressEvent::Kind::Advance: {
    if (quiet_ || !terminal_) return;
    std::string path;
    for (size_t d = 0; d <= depth && d < stages_.size(); ++d) path += (d ? " / " : "") + stages_[d];
    constexpr int kWidth = 24;
    const int filled = int(std::lround(e.fraction * kWidth));
    std::fprintf(stderr, "\r\033[K%s: %s [%s%s] %3d%%", prefix_.c_str(), path.c_str(), std::string(size_t(filled), '#').c_str(),
                 std::string(size_t(kWidth - filled), ' ').c_str(), int(std::lround(e.fraction * 100)));
    std::fflush(stderr);
    statusShown_ = true;
    return;
  }
  case ProgressEvent::Kind::End: {
    std::string key(e.stage);
    if (depth > 0 && depth - 1 < stages_.size()) key = stages_[depth - 1] + "/" + key;
    timings_[key] = (timings_.contains(key) ? timings_[key].get<double>() : 0.0) + e.seconds;
    if (quiet_) return;
    char line[96];
    std::snprintf(line, sizeof line, "%*s%-*s %8.3f s", int(2 * depth), "", int(14 - 2 * std::min<size_t>(depth, 3)),
                  std::string(e.stage).c_str(), e.seconds);
    printLine(e.detail.empty() ? std::string(line) : std::string(line) + "  " + std::string(e.detail));
    return;
  }
  }
}

nlohmann::json ProgressPrinter::timings() const {
  const std::lock_guard lock(mutex_);
  return timings_;
}

} // namespace texfab::cli
