// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The one place texfab decides how work is spread over threads (TBB underneath).
// Work items must write disjoint outputs, so results never depend on the thread count or on
// scheduling.

#include "core/context.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace texfab {

/// Calls fn(begin, end) on disjoint sub-ranges covering [begin, end), on up to `threads` threads
/// (0 = all available). `grain` is the smallest sub-range worth a task.
template <class Fn>
void parallelFor(int begin, int end, int threads, Fn&& fn, int grain = 1) {
  if (end <= begin) return;
  if (threads == 1 || end - begin <= grain) {
    fn(begin, end);
    return;
  }
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<int>(begin, end, grain),
                      [&](const tbb::blocked_range<int>& r) { fn(r.begin(), r.end()); });
  });
}

/// The same on ctx.threads threads; each sub-range first checks for cancellation (Cancelled
/// propagates out of parallelFor).
template <class Fn>
void parallelFor(int begin, int end, const Context& ctx, Fn&& fn, int grain = 1) {
  parallelFor(begin, end, ctx.threads, [&](int b, int e) {
    ctx.checkCancelled();
    fn(b, e);
  }, grain);
}

} // namespace texfab
