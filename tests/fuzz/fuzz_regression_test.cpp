// SPDX-License-Identifier: GPL-3.0-or-later
// Every fuzz target on its seeds (valid files from the test models: each must load, so the target
// reaches its reader's depths) and on every input in tests/fuzz/regressions/<target>/ (inputs that
// once crashed, hung or broke a contract: each must now load or be refused with texfab::Error).
// Under a sanitizer build (scripts/sanitize.sh) these run under ASan and UBSan.
#include "tests/fuzz/fuzz_targets.h"
#include "tests/test_support.h"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <vector>

namespace fs = std::filesystem;
using texfab::fuzz::FuzzTarget;

namespace {

std::vector<uint8_t> readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::vector<fs::path> filesIn(const fs::path& folder) {
  std::vector<fs::path> files;
  if (fs::is_directory(folder))
    for (const auto& e : fs::directory_iterator(folder))
      if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

std::vector<std::string> targetNames() {
  std::vector<std::string> names;
  for (const FuzzTarget& t : texfab::fuzz::fuzzTargets()) names.push_back(t.name);
  return names;
}

} // namespace

class FuzzTargets : public ::testing::TestWithParam<std::string> {};

TEST_P(FuzzTargets, SeedsLoadAndRegressionInputsNeitherCrashNorEscape) {
  const FuzzTarget& target = *texfab::fuzz::findFuzzTarget(GetParam());
  texfab::test::TempDir dir("texfab-fuzz-seeds");
  target.writeSeeds(dir.path());
  const std::vector<fs::path> seeds = filesIn(dir.path());
  ASSERT_FALSE(seeds.empty());
  for (const fs::path& seed : seeds) {
    bool loaded = false;
    EXPECT_NO_THROW(loaded = target.run(readBytes(seed))) << seed.filename();
    EXPECT_TRUE(loaded) << target.name << ": the seed " << seed.filename() << " does not load";
  }
  for (const fs::path& input : filesIn(fs::path(TEXFAB_SOURCE_DIR) / "tests" / "fuzz" / "regressions" / target.name))
    EXPECT_NO_THROW(target.run(readBytes(input))) << input;
}

INSTANTIATE_TEST_SUITE_P(All, FuzzTargets, ::testing::ValuesIn(targetNames()),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });
