// SPDX-License-Identifier: GPL-3.0-or-later
// texfab: mesh texturing and fabrication by example. One subcommand per job.
//
// Exit codes: 0 success, 1 usage error (unknown flag, bad value), 2 bad input or failed output
// (the message names the file), 3 internal error (a bug: please report it).

#include "apps/texfab/command.h"
#include "render/image/error.h"

#include <cstdio>
#include <exception>
#include <vector>

int main(int argc, char** argv) {
  using namespace texfab;
  CLI::App app{"texfab: texture meshes by example, cut them, and slice them for full-color printing.\n"
               "Run 'texfab <command> --help' for the options of one command."};
  app.name("texfab");
  app.require_subcommand(1);
  app.set_version_flag("--version", "texfab " TEXFAB_VERSION);

  std::vector<cli::Command> commands{cli::addSynthCommand(app), cli::addStatsCommand(app), cli::addSolidCommand(app),
                                     cli::addInfoCommand(app), cli::addConvertCommand(app),
                                     cli::addRenderCommand(app), cli::addAtlasCommand(app),
                                     cli::addTextureCommand(app),
                                     cli::addSliceCommand(app), cli::addMergeSlicesCommand(app)};

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::string where = "texfab";
    for (const CLI::App* sub : app.get_subcommands()) where += " " + sub->get_name();
    std::fprintf(stderr, "%s: error: %s (see '%s --help')\n", where.c_str(), e.what(), where.c_str());
    return 1;
  }

  for (const cli::Command& command : commands) {
    if (!command.app->parsed()) continue;
    const std::string where = "texfab " + command.app->get_name();
    try {
      command.run();
      return 0;
    } catch (const Error& e) {
      std::fprintf(stderr, "%s: error: %s\n", where.c_str(), e.what());
      return 2;
    } catch (const std::bad_alloc&) {
      std::fprintf(stderr, "%s: error: out of memory\n", where.c_str());
      return 2;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: internal error: %s\n", where.c_str(), e.what());
      return 3;
    }
  }
  return 1;
}
