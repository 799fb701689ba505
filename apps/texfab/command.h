// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Each subcommand lives in cmd_<name>.cpp and registers itself with the root CLI11 app (its flags
// through cli.h's Flags), returning what main() runs once the command line has parsed.

#include <CLI/CLI.hpp>

#include <functional>

namespace texfab::cli {

struct Command {
  CLI::App* app = nullptr;    ///< the subcommand, to know which one the user chose
  std::function<void()> run;  ///< does the work; throws texfab::Error on bad input
};

// In pipeline order, as `texfab --help` lists them.
Command addTextureCommand(CLI::App& root);
Command addAtlasCommand(CLI::App& root);
Command addSynthCommand(CLI::App& root);
Command addSolidCommand(CLI::App& root);
Command addFractureCommand(CLI::App& root);
Command addCutCommand(CLI::App& root);
Command addSliceCommand(CLI::App& root);
Command addMergeSlicesCommand(CLI::App& root);
Command addRenderCommand(CLI::App& root);
Command addStatsCommand(CLI::App& root);
Command addInfoCommand(CLI::App& root);
Command addConvertCommand(CLI::App& root);

} // namespace texfab::cli
