// SPDX-License-Identifier: GPL-3.0-or-later
#include "core/context.h"

#include <algorithm>
#include <cstdio>
#include <thread>

namespace texfab {

namespace {
using Clock = std::chrono::steady_clock;
constexpr int64_t kReportIntervalNs = 100'000'000;

int64_t nanoseconds(Clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}
} // namespace

Stage::Stage(const Context& ctx, std::string name) : ctx_(ctx), name_(std::move(name)), start_(Clock::now()) {
  ctx_.checkCancelled();
  nextReport_ = nanoseconds(start_) + kReportIntervalNs;
  if (ctx_.progress) ctx_.progress({ProgressEvent::Kind::Begin, name_, ctx_.depth, 0.0, 0.0, {}});
}

void Stage::advance(double fraction) {
  ctx_.checkCancelled();
  if (!ctx_.progress) return;
  const int64_t now = nanoseconds(Clock::now());
  int64_t due = nextReport_.load(std::memory_order_relaxed);
  // One thread wins each interval; the others skip.
  if (now < due || !nextReport_.compare_exchange_strong(due, now + kReportIntervalNs)) return;
  ctx_.progress({ProgressEvent::Kind::Advance, name_, ctx_.depth, std::clamp(fraction, 0.0, 1.0), 0.0, {}});
}

void reportEstimate(const Context& ctx, double cpuSeconds, const std::string& what) {
  const int threads = ctx.threads > 0 ? ctx.threads : int(std::max(1u, std::thread::hardware_concurrency()));
  const double seconds = cpuSeconds / threads;
  if (seconds < 20) return;
  char detail[160];
  std::snprintf(detail, sizeof detail, "about %.0f %s for %s on %d thread%s", seconds < 90 ? seconds : seconds / 60,
                seconds < 90 ? "s" : "min", what.c_str(), threads, threads == 1 ? "" : "s");
  Stage(ctx, "estimate").finish(detail);
}

double Stage::seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

double Stage::finish(const std::string& detail) {
  const double s = seconds();
  if (!finished_ && ctx_.progress) ctx_.progress({ProgressEvent::Kind::End, name_, ctx_.depth, 1.0, s, detail});
  finished_ = true;
  return s;
}

} // namespace texfab
