// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The command line's progress sink: what a Context's stages and warnings look like on stderr.
// On a terminal the running stage is a bar with a percentage, redrawn in place; otherwise (a log,
// a pipe) each finished stage is one plain line. Both record the stage timings the --report gives.

#include "core/context.h"

#include <nlohmann/json.hpp>

#include <mutex>
#include <set>
#include <string>
#include <vector>

namespace texfab::cli {

class ProgressPrinter {
public:
  /// `prefix` starts every line ("texfab texture"); `quiet` leaves warnings only.
  ProgressPrinter(std::string prefix, bool quiet);
  /// The ProgressSink (thread-safe).
  void operator()(const ProgressEvent& event);
  /// A line of information (not with quiet).
  void note(const std::string& message);
  /// Seconds per finished stage: "atlas", and nested stages as "synthesis/level 2/4"; a stage that
  /// runs several times (one per view) adds up.
  nlohmann::json timings() const;

private:
  void clearStatus();  // on a terminal: erase the bar line
  void printLine(const std::string& text);
  std::string prefix_;
  bool quiet_, terminal_;
  mutable std::mutex mutex_;
  std::vector<std::string> stages_;  // running stage at each depth
  std::set<std::string> warned_;
  bool statusShown_ = false;
  nlohmann::json timings_ = nlohmann::json::object();
};

} // namespace texfab::cli
