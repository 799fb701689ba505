// SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer's entry for every target of fuzz_targets.h: $TEXFAB_FUZZ_TARGET names the target
// (scripts/fuzz.sh sets it), e.g.
//   TEXFAB_FUZZ_TARGET=mesh_obj texfab_fuzz corpus/ seeds/ -runs=1000000
#include "tests/fuzz/fuzz_targets.h"

#include <cstdio>
#include <cstdlib>

namespace {
const texfab::fuzz::FuzzTarget* target = nullptr;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const char* name = std::getenv("TEXFAB_FUZZ_TARGET");
  target = name ? texfab::fuzz::findFuzzTarget(name) : nullptr;
  if (!target) {
    std::fprintf(stderr, "texfab_fuzz: set TEXFAB_FUZZ_TARGET to one of:\n");
    for (const auto& t : texfab::fuzz::fuzzTargets()) std::fprintf(stderr, "  %-16s %s\n", t.name, t.what);
    std::exit(1);
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  target->run({data, size});
  return 0;
}
