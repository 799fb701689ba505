// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/image/context.h"

#include <algorithm>

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

double Stage::seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

double Stage::finish(const std::string& detail) {
  const double s = seconds();
  if (!finished_ && ctx_.progress) ctx_.progress({ProgressEvent::Kind::End, name_, ctx_.depth, 1.0, s, detail});
  finished_ = true;
  return s;
}

} // namespace texfab
