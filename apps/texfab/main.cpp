// SPDX-License-Identifier: GPL-3.0-or-later
// texfab: mesh texturing by example. One subcommand per job.
//
// Exit codes: 0 success, 1 usage error (unknown command or flag, bad value), 2 bad input or failed
// output (the message names the file), 3 internal error (a bug: please report it), 130 stopped by
// SIGINT or SIGTERM.
//
// Signals: the first SIGINT/SIGTERM sets the cancel flag every command's Context carries; the work
// stops at its next check and unwinds, removing its temporaries. A second one removes the
// registered temporaries and exits at once.

#include "apps/texfab/cli.h"
#include "apps/texfab/command.h"
#include "atlas/pack_charts.h"
#include "core/error.h"
#include "core/files.h"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <exception>
#include <thread>
#include <vector>

namespace texfab::cli {

namespace {
std::atomic<bool> cancelRequested{false};

int signalPipe[2] = {-1, -1};

// The handler only writes a byte (async-signal-safe); a thread reads it and handles the signal as
// ordinary code. (Blocking the signals instead would not do: libraries start threads before main.)
extern "C" void onSignal(int) {
  const int saved = errno;
  const char byte = 1;
  [[maybe_unused]] const ssize_t written = ::write(signalPipe[1], &byte, 1);
  errno = saved;
}

void installSignalHandling() {
  if (::pipe2(signalPipe, O_CLOEXEC) != 0) return;  // no cancel then; the default action stays
  std::thread([] {
    for (int received = 0;;) {
      char byte = 0;
      const ssize_t n = ::read(signalPipe[0], &byte, 1);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return;
      if (++received == 1 && !cancelRequested.exchange(true)) {
        if (::isatty(STDERR_FILENO)) std::fputs("\ntexfab: stopping (interrupt again to quit at once)\n", stderr);
        continue;
      }
      removeRegisteredTemporaries();
      ::_exit(130);
    }
  }).detach();
  struct sigaction action{};
  action.sa_handler = onSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  ::sigaction(SIGINT, &action, nullptr);
  ::sigaction(SIGTERM, &action, nullptr);
}
} // namespace

const std::atomic<bool>& cancelFlag() { return cancelRequested; }

} // namespace texfab::cli

int main(int argc, char** argv) {
  using namespace texfab;
  cli::installSignalHandling();
  CLI::App app{"texfab: texture meshes by example.\n"
               "Run 'texfab <command> --help' for the options of one command."};
  app.name("texfab");
  app.require_subcommand(1);
  app.set_version_flag("--version", "texfab " TEXFAB_VERSION);
  // Pipeline order: the main job first, then its parts, then the tools around them.
  const std::vector<cli::Command> commands{
      cli::addTextureCommand(app), cli::addAtlasCommand(app),       cli::addSynthCommand(app),
      cli::addSolidCommand(app),   cli::addFractureCommand(app),    cli::addCutCommand(app),
      cli::addSliceCommand(app),   cli::addMergeSlicesCommand(app), cli::addRenderCommand(app),
      cli::addStatsCommand(app),   cli::addInfoCommand(app),        cli::addConvertCommand(app)};

  // An unknown command is named (CLI11 would print the top-level help for "texfab cut --help").
  std::string names;
  bool known = false;
  for (const cli::Command& c : commands) {
    names += (names.empty() ? "" : ", ") + c.app->get_name();
    known |= argc > 1 && c.app->get_name() == argv[1];
  }
  if (argc > 1 && argv[1][0] != '-' && !known) {
    std::fprintf(stderr, "texfab: error: unknown command '%s' (commands: %s; see 'texfab --help')\n", argv[1],
                 names.c_str());
    return 1;
  }

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
    } catch (const Cancelled&) {
      std::fprintf(stderr, "%s: stopped\n", where.c_str());
      return 130;
    } catch (const cli::UsageError& e) {
      std::fprintf(stderr, "%s: error: %s (see '%s --help')\n", where.c_str(), e.what(), where.c_str());
      return 1;
    } catch (const atlas::AtlasTooSmall& e) {
      // The flag that sizes the atlas: --interior-resolution for the cut faces', else --resolution.
      const char* flag = e.which() == "interior" ? "--interior-resolution" : "--resolution";
      std::fprintf(stderr, "%s: error: %s; give a larger %s or a simpler mesh\n", where.c_str(), e.what(), flag);
      return 2;
    } catch (const Error& e) {
      std::fprintf(stderr, "%s: error: %s\n", where.c_str(), withOutputNames(e.what()).c_str());
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
