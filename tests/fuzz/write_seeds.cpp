// SPDX-License-Identifier: GPL-3.0-or-later
// texfab_fuzz_seeds FOLDER [TARGET...]: writes each target's seed inputs (valid files made from the
// test models) into FOLDER/<target>/; every target when none is named.
#include "tests/fuzz/fuzz_targets.h"

#include "core/error.h"

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
  using namespace texfab::fuzz;
  if (argc < 2) {
    std::fprintf(stderr, "usage: texfab_fuzz_seeds FOLDER [TARGET...]\n");
    return 1;
  }
  try {
    for (const FuzzTarget& t : fuzzTargets()) {
      bool wanted = argc == 2;
      for (int i = 2; i < argc; ++i) wanted = wanted || std::string_view(argv[i]) == t.name;
      if (!wanted) continue;
      const std::filesystem::path folder = std::filesystem::path(argv[1]) / t.name;
      std::filesystem::create_directories(folder);
      t.writeSeeds(folder);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "texfab_fuzz_seeds: %s\n", e.what());
    return 2;
  }
  return 0;
}
