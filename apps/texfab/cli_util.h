// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Small pieces every subcommand shares: value parsers, progress lines, reports.

#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

namespace texfab::cli {

/// "WxH" or "N" (square). Throws texfab::Error naming `what`.
std::pair<int, int> parseSize(const std::string& text, const std::string& what);
/// Comma-separated numbers: "0.5" or "1,1,0.5,0".
std::vector<double> parseNumberList(const std::string& text, const std::string& what);

/// Progress on stderr, one line per finished stage: "texfab synth: analysis 0.21 s".
/// Silent when quiet. Also collects the stage timings for the report.
class Progress {
public:
  Progress(std::string command, bool quiet) : command_(std::move(command)), quiet_(quiet) {}
  void start(std::string stage);
  /// Ends the current stage; `detail` is appended to its line.
  double finish(const std::string& detail = {});
  /// A stage timed elsewhere (e.g. reported by a library callback).
  void record(const std::string& stage, double seconds, const std::string& detail = {});
  void note(const std::string& message) const;
  const nlohmann::json& timings() const { return timings_; }

private:
  std::string command_;
  bool quiet_;
  std::string stage_;
  std::chrono::steady_clock::time_point started_;
  nlohmann::json timings_ = nlohmann::json::object();
};

/// Peak resident memory of this process so far, in MiB.
double peakMemoryMiB();

/// Writes a JSON report (write to a temporary file, then rename).
void writeReport(const nlohmann::json& report, const std::filesystem::path& path);

} // namespace texfab::cli
