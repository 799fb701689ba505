// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Each subcommand lives in cmd_<name>.cpp and registers itself with the root CLI11 app, returning
// what main() runs once the command line has parsed.

#include <CLI/CLI.hpp>

#include <functional>

namespace texfab::cli {

struct Command {
  CLI::App* app = nullptr;    ///< the subcommand, to know which one the user chose
  std::function<void()> run;  ///< does the work; throws texfab::Error on bad input
};

Command addSynthCommand(CLI::App& root);
Command addStatsCommand(CLI::App& root);
Command addSolidCommand(CLI::App& root);
Command addInfoCommand(CLI::App& root);
Command addConvertCommand(CLI::App& root);
Command addRenderCommand(CLI::App& root);
Command addAtlasCommand(CLI::App& root);
Command addTextureCommand(CLI::App& root);
Command addSliceCommand(CLI::App& root);
Command addMergeSlicesCommand(CLI::App& root);

} // namespace texfab::cli
