// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The execution context: what every long computation takes as its last parameter
// (`const Context& ctx = {}`) besides its inputs and options: how many threads, which backend runs
// the synthesis kernels, where progress goes, and whether the user has asked to stop. Outputs never
// depend on it (the determinism contract); only speed and reporting do.
//
// Progress follows xatlas's single callback: a computation reports named stages (Stage below);
// the sink decides what to show (a line per stage, a bar on a terminal, timings for a report).

#include "core/error.h"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

namespace texfab {

/// Where the synthesis kernels run. Auto: a Vulkan device when one is present, else the CPU.
enum class Backend : uint8_t { Cpu, Vulkan, Auto };

/// What a long computation reports as it goes: its stages, and warnings as soon as they are known
/// (so that a user reads them before the long work, not after it).
struct ProgressEvent {
  enum class Kind : uint8_t { Begin, Advance, End, Warning };
  Kind kind = Kind::Begin;
  std::string_view stage;   ///< "atlas", "synthesis", "level 3/4", ...
  int depth = 0;            ///< 0 for a job's own stages, 1 for the stages of a step inside one, ...
  double fraction = 0;      ///< Advance: the part done, in [0, 1]
  double seconds = 0;       ///< End: the stage's duration
  std::string_view detail;  ///< End: one line of figures, e.g. "175 charts, utilization 0.77";
                            ///< Warning: the message
};

/// Seconds on the steady clock since `start`: a level's or stage's duration.
inline double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// Receives progress. It may be called from several threads at once: it must be thread-safe.
using ProgressSink = std::function<void(const ProgressEvent&)>;

/// Thrown at the next check once the context's cancel flag is set. Work unwinds, and with it every
/// temporary output is removed.
class Cancelled : public Error {
public:
  Cancelled() : Error("cancelled") {}
};

struct Context {
  int threads = 0;                 ///< worker threads; 0 = all cores
  Backend backend = Backend::Cpu;  ///< where the synthesis kernels run
  int device = -1;                 ///< Vulkan device index; -1: $TEXFAB_VULKAN_DEVICE, else the first
  ProgressSink progress{};         ///< may be empty
  const std::atomic<bool>* cancel = nullptr;  ///< when it becomes true, work stops at its next check
  int depth = 0;                   ///< nesting of the stages reported through this context

  /// The same context for the steps inside a stage: their stages are reported one level deeper.
  Context nested() const {
    Context inner = *this;
    ++inner.depth;
    return inner;
  }
  /// Reports a warning (one line, no "warning:" prefix) to the progress sink, if any.
  void warn(std::string_view message) const {
    if (progress) progress({ProgressEvent::Kind::Warning, {}, depth, 0.0, 0.0, message});
  }
  bool cancelled() const { return cancel && cancel->load(std::memory_order_relaxed); }
  /// Throws Cancelled when the cancel flag is set. Long loops call it between chunks of work.
  void checkCancelled() const {
    if (cancelled()) throw Cancelled();
  }
};

/// One stage of work reported through a context: Begin when constructed, Advance as it goes (at
/// most every 0.1 s), End when finished. A stage destroyed unfinished (by an exception) reports
/// nothing more.
class Stage {
public:
  Stage(const Context& ctx, std::string name);
  Stage(const Stage&) = delete;
  Stage& operator=(const Stage&) = delete;

  /// Reports the part done, in [0, 1] (thread-safe, throttled), and checks for cancellation.
  void advance(double fraction);
  /// Reports `done` of `total` items.
  void advance(int64_t done, int64_t total) { advance(total > 0 ? double(done) / double(total) : 1.0); }
  /// Ends the stage, reporting its duration and `detail`; returns the duration in seconds.
  double finish(const std::string& detail = {});
  /// Seconds since the stage began.
  double seconds() const;
  /// The context for the steps inside this stage (their stages one level deeper).
  Context inner() const { return ctx_.nested(); }

private:
  const Context& ctx_;
  std::string name_;
  std::chrono::steady_clock::time_point start_;
  std::atomic<int64_t> nextReport_{0};  // steady-clock nanoseconds before which Advance is not reported
  bool finished_ = false;
};

/// Says before a long computation about how long it will take, as a finished stage "estimate"
/// whose detail is "about N s (or min) for `what` on T threads"; nothing below 20 s. `cpuSeconds`:
/// the work on one core, spread over ctx.threads (0: all cores).
void reportEstimate(const Context& ctx, double cpuSeconds, const std::string& what);

} // namespace texfab
