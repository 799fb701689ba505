// SPDX-License-Identifier: GPL-3.0-or-later
// The command line as a user meets it, where it used to fail: every numeric flag of every command
// refuses NaN and infinity naming the flag, ranges are stated one way, unknown commands are named,
// outputs are checked before any work and committed together, a signal leaves no temporary, the
// analysis cache is bounded and an unwritable one is said once.
#include "core/crop.h"
#include "core/image_io.h"
#include "tests/test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <future>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

namespace {
namespace fs = std::filesystem;
using texfab::test::CliResult;
using texfab::test::quote;
using texfab::test::readFile;
using texfab::test::runCli;
using texfab::test::TempDir;

const fs::path kSource(TEXFAB_SOURCE_DIR);
const fs::path kModel = kSource / "models" / "meshes" / "elephant.off";
const fs::path kExemplar = kSource / "models" / "exemplars" / "brick.png";

// The commands `texfab --help` lists, in its order.
std::vector<std::string> commands() {
  const CliResult help = runCli("--help");
  std::vector<std::string> names;
  bool inList = false;
  std::istringstream lines(help.out);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("Subcommands:", 0) == 0) inList = true;
    else if (inList && line.size() > 2 && line[0] == ' ' && line[1] == ' ' && line[2] != ' ')
      names.push_back(line.substr(2, line.find(' ', 2) - 2));
  }
  return names;
}

// The flags of a command whose values are numbers, from its --help ("--gutter INT=4 ...").
std::vector<std::string> numericFlags(const std::string& command) {
  static const std::regex option(R"(^\s+(?:-\w,)?(--[\w-]+) ([^\s=]+))");
  static const std::set<std::string> numericTypes = {"INT", "UINT", "FLOAT", "N|WxH", "BYTES"};
  std::vector<std::string> flags;
  std::istringstream lines(runCli(command + " --help").out);
  std::smatch m;
  for (std::string line; std::getline(lines, line);)
    if (std::regex_search(line, m, option) &&
        (numericTypes.count(m[2].str()) || (m[2].str().find(',') != std::string::npos && m[2].str() != "COLOUR")))
      flags.push_back(m[1].str());
  return flags;
}

} // namespace

TEST(Cli, HelpListsTheCommandsInPipelineOrder) {
  const std::vector<std::string> names = commands();
  ASSERT_GE(names.size(), 8u);
  EXPECT_EQ(names.front(), "texture");
  EXPECT_EQ(std::vector<std::string>(names.begin(), names.begin() + 4),
            (std::vector<std::string>{"texture", "atlas", "synth", "solid"}));
}

TEST(Cli, UnknownCommandsAreNamed) {
  for (const std::string args : {"bogus", "shatter --help", "explode", "explode --help"}) {
    const CliResult r = runCli(args);
    EXPECT_EQ(r.status, 1) << args;
    const std::string name = args.substr(0, args.find(' '));
    EXPECT_NE(r.err.find("unknown command '" + name + "'"), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(r.errLines(), 1u) << r.err;
    EXPECT_EQ(r.out.find("Subcommands"), std::string::npos) << "top-level help printed for " << args;
  }
}

// Every numeric flag of every command, found in its --help: NaN and infinities are refused at
// parse time with one line naming the flag (the render command once aborted in Embree). Every flag
// gets nan and inf, each command's first flag every spelling; four runs at a time (a start of the
// binary is mostly waiting for its shared libraries to load).
TEST(Cli, EveryNumericFlagRefusesNanAndInfinity) {
  struct Run {
    std::string command, flag, value;
    std::future<CliResult> result;
  };
  std::vector<Run> runs;
  for (const std::string& command : commands()) {
    const std::vector<std::string> flags = numericFlags(command);
    for (const std::string& flag : flags)
      for (const char* value : {"nan", "inf", "-inf", "NaN"})
        if (flag == flags.front() || std::string(value) == "nan" || std::string(value) == "inf")
          runs.push_back({command, flag, value, {}});
  }
  constexpr size_t kInFlight = 4;
  for (size_t i = 0; i < runs.size(); ++i) {
    if (i >= kInFlight) runs[i - kInFlight].result.wait();
    runs[i].result = std::async(std::launch::async, runCli, runs[i].command + " " + runs[i].flag + " " + runs[i].value);
  }
  std::set<std::string> flags;
  for (Run& run : runs) {
    const CliResult r = run.result.get();
    const std::string what = run.command + " " + run.flag + " " + run.value + ": " + r.err;
    EXPECT_EQ(r.status, 1) << what;
    EXPECT_EQ(r.errLines(), 1u) << what;
    EXPECT_NE(r.err.find(run.flag), std::string::npos) << what;
    flags.insert(run.command + " " + run.flag);
  }
  EXPECT_GE(flags.size(), 40u);  // the flags were found
}

TEST(Cli, NumbersOutOfRangeNameTheFlagAndTheRange) {
  struct Case {
    std::string args, flag, range;
  };
  const std::vector<Case> cases = {
      {"synth x.png -o y.png --threads -4", "--threads", "0 to 4096"},
      {"synth x.png -o y.png --jitter 1.5", "--jitter", "0 to 1"},
      {"solid x.png -o y --volume 8 --jitter 5", "--jitter", "0 to 4"},
      {"texture m.off -e x.png -o y.glb --texture-scale -5", "--texture-scale", "at least 0"},
      {"solid x.png -o y --volume 8 --voxel-size 0", "--voxel-size", "greater than 0"},
      {"texture m.off -e x.png -o y.glb --resolution 8", "--resolution", "16 to 16384"},
      {"atlas m.off -o y.glb --resolution 100000", "--resolution", "16 to 16384"},
      {"render m.off -o y.png --spp 0", "--spp", "1 to 4096"},
  };
  for (const Case& c : cases) {
    const CliResult r = runCli(c.args);
    EXPECT_EQ(r.status, 1) << c.args;
    EXPECT_EQ(r.errLines(), 1u) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find(c.flag + ": "), std::string::npos) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find(c.range), std::string::npos) << c.args << ": " << r.err;
  }
  // The help states --resolution's range the same way.
  EXPECT_NE(runCli("texture --help").out.find("16 to 16384"), std::string::npos);
}

// A choice flag names the flag and its values when given another.
TEST(Cli, AnUnknownChoiceNamesTheFlagAndItsValues) {
  const CliResult r = runCli("render m.off -o y.png --normal-filtering shiny");
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.errLines(), 1u) << r.err;
  EXPECT_NE(r.err.find("--normal-filtering: expected lobes|toksvig|mip, got 'shiny'"), std::string::npos) << r.err;
}

TEST(Cli, ABadImageGivesOneLine) {
  TempDir d("texfab-cli");
  std::ofstream(d / "bad.png", std::ios::binary) << "\x89PNG\r\n\x1a\n" << std::string(64, 'x');
  const std::string png = readFile(kExemplar);
  std::ofstream(d / "truncated.png", std::ios::binary) << png.substr(0, png.size() / 2);
  for (const char* name : {"bad.png", "truncated.png"}) {
    const CliResult r = runCli("synth " + quote(d / name) + " -o " + quote(d / "o.png") + " --no-cache");
    EXPECT_EQ(r.status, 2) << name;
    EXPECT_EQ(r.errLines(), 1u) << name << ": " << r.err;
    EXPECT_EQ(r.err.rfind("texfab synth: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(name), std::string::npos) << r.err;
  }
}

TEST(Cli, SingularAndPluralCounts) {
  TempDir d("texfab-cli");
  std::ofstream(d / "tri.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  const CliResult r = runCli("atlas " + quote(d / "tri.obj") + " -o " + quote(d / "a.glb") + " --resolution 64");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find(" 1 chart,"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find(" 1 charts"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(" 1 triangle"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find(" 1 triangles"), std::string::npos) << r.err;
}

// A model that cannot carry the texture is refused before any work.
TEST(Cli, TextureRefusesFormatsWithoutTextures) {
  TempDir d("texfab-cli");
  for (const char* out : {"x.ply", "x.stl", "x.off"}) {
    const CliResult r = runCli("texture " + quote(kModel) + " -e " + quote(kExemplar) + " -o " + quote(d / out));
    EXPECT_EQ(r.status, 1) << out << ": " << r.err;
    EXPECT_NE(r.err.find("cannot carry the texture"), std::string::npos) << r.err;
    EXPECT_TRUE(fs::is_empty(d.path())) << out;
  }
}

// texture's --exemplar-wrap: auto picks clamp on a photograph that does not tile and says so, in
// surface and solid mode; the report names the mode.
TEST(Cli, TextureChoosesTheExemplarWrap) {
  TempDir d("texfab-cli");
  const fs::path photo = kSource / "models" / "exemplars" / "photos" / "rock.png";
  const std::string job = "texture " + quote(kModel) + " -e " + quote(photo) + " --resolution 256 --no-cache";
  const CliResult r = runCli(job + " -o " + quote(d / "a.glb") + " --report " + quote(d / "a.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("exemplar wrap: clamp"), std::string::npos) << r.err;
  EXPECT_EQ(nlohmann::json::parse(readFile(d / "a.json"))["parameters"]["exemplar_wrap"], "clamp");
  // Solid mode on a 48x48 crop: the solid precomputation grows with the exemplar's size.
  texfab::writeImage(texfab::crop(texfab::readImage(photo), 20, 30, 48, 48), d / "rock48.png");
  const CliResult solid = runCli("texture " + quote(kModel) + " -e " + quote(d / "rock48.png") +
                                 " --resolution 256 --no-cache --mode solid -o " + quote(d / "b.glb") + " --report " +
                                 quote(d / "b.json"));
  ASSERT_EQ(solid.status, 0) << solid.err;
  EXPECT_NE(solid.err.find("exemplar wrap: clamp"), std::string::npos) << solid.err;
  EXPECT_EQ(nlohmann::json::parse(readFile(d / "b.json"))["parameters"]["exemplar_wrap"], "clamp");
}

// A box (2 x 6 x 1) with two triangles wound the wrong way and a hole where one triangle is missing.
fs::path flawedBox(const fs::path& dir) {
  const fs::path p = dir / "flawed.obj";
  std::ofstream(p) << "v 0 0 0\nv 2 0 0\nv 2 6 0\nv 0 6 0\nv 0 0 1\nv 2 0 1\nv 2 6 1\nv 0 6 1\n"
                   << "f 1 3 4\nf 1 2 3\n"  // flipped
                   << "f 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\n";  // hole
  return p;
}

// Every command prepares its model with the one preparation, as far as its use needs: texture
// re-orients the surface and keeps the hole, slice closes it with a fan, fracture fills it as a cut
// face; each says so before its long work and in its report.
TEST(Cli, EveryCommandPreparesTheModelAlike) {
  TempDir d("texfab-cli");
  const fs::path model = flawedBox(d.path());
  const std::string in = quote(model) + " -e " + quote(kExemplar) + " --no-cache --seed 2";
  struct Job {
    std::string command, use, closing, longWork;  // longWork: what the job prints once its long work began
  };
  const Job jobs[] = {
      {"texture " + in + " --resolution 128 -o " + quote(d / "t.glb"), "surface", "", "exemplar wrap:"},
      {"slice " + quote(model) + " --height 6 --dpi 25.4 --layer 0.5 -o " + quote(d / "s"), "print",
       "closed 1 hole (3 boundary edges) with fans of triangles", " slice "},
      {"fracture " + in + " --pieces 2 --resolution 128 -o " + quote(d / "f.glb"), "solid",
       "filled 1 hole with 1 triangle", "exemplar wrap:"},
  };
  for (const Job& job : jobs) {
    const CliResult r = runCli(job.command + " --report " + quote(d / "r.json"));
    ASSERT_EQ(r.status, 0) << job.command << "\n" << r.err;
    const nlohmann::json p = nlohmann::json::parse(readFile(d / "r.json"))["model"]["preparation"];
    EXPECT_EQ(p["use"], job.use);
    ASSERT_EQ(p["repairs"].size(), job.closing.empty() ? 1u : 2u) << p.dump();
    EXPECT_EQ(p["repairs"][0], "re-oriented 2 triangles (consistent winding)");
    if (!job.closing.empty()) {
      EXPECT_EQ(p["repairs"][1], job.closing);
    }
    // Said before the long work (the exemplar's analysis, the slices).
    const size_t said = r.err.find("warning: repaired: re-oriented 2 triangles");
    const size_t longWork = r.err.find(job.longWork);
    ASSERT_NE(said, std::string::npos) << r.err;
    ASSERT_NE(longWork, std::string::npos) << r.err;
    EXPECT_LT(said, longWork) << r.err;
  }
}

// Every output location is checked before any work, and outputs appear only together.
TEST(Cli, OutputsAreCheckedBeforeTheWorkAndCommittedTogether) {
  TempDir d("texfab-cli");
  const std::string missing = quote(d / "missing" / "r.json");
  const std::vector<std::string> jobs = {
      "texture " + quote(kModel) + " -e " + quote(kExemplar) + " -o " + quote(d / "out.glb") + " --resolution 256 --no-cache",
      "synth " + quote(kExemplar) + " -o " + quote(d / "out.png") + " --size 64 --no-cache",
      "solid " + quote(kExemplar) + " --plane 0,0,0,1,0,0,0,1,0 --size 16 -o " + quote(d / "out.png") + " --no-cache",
      "atlas " + quote(kModel) + " -o " + quote(d / "out.glb") + " --resolution 256",
  };
  for (const std::string& job : jobs) {
    const CliResult r = runCli(job + " --report " + missing);
    EXPECT_EQ(r.status, 2) << job << ": " << r.err;
    EXPECT_EQ(r.errLines(), 1u) << job << ": " << r.err;  // no stage line: nothing ran
    EXPECT_NE(r.err.find("missing"), std::string::npos) << r.err;
    EXPECT_TRUE(fs::is_empty(d.path())) << job;  // no output, no temporary
  }
  // A second output that cannot be written (a folder in its way) stops the first too.
  fs::create_directory(d / "coords.png");
  const CliResult r = runCli("synth " + quote(kExemplar) + " -o " + quote(d / "out.png") + " --size 64 --no-cache --coords " +
                             quote(d / "coords.png"));
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_FALSE(fs::exists(d / "out.png"));
  fs::remove(d / "coords.png");
  // When all succeed, all are there and nothing else.
  ASSERT_EQ(runCli("synth " + quote(kExemplar) + " -o " + quote(d / "out.png") + " --size 64 --no-cache -q --coords " +
                   quote(d / "coords.exr") + " --report " + quote(d / "r.json")).status,
            0);
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(d.path())) names.insert(e.path().filename().string());
  EXPECT_EQ(names, (std::set<std::string>{"coords.exr", "out.png", "r.json"}));
}

// An output folder that cannot be written says why, in the system's words.
TEST(Cli, AnUnwritableFolderSaysWhy) {
  TempDir d("texfab-cli");
  fs::path folder = d / "readonly";
  fs::create_directory(folder);
  ::chmod(folder.c_str(), 0555);
  if (::access(folder.c_str(), W_OK) == 0) folder = "/proc/self";  // root writes anywhere; procfs refuses it
  const CliResult r = runCli("synth " + quote(kExemplar) + " -o " + quote(folder / "o.png") + " --size 16 --no-cache");
  ::chmod((d / "readonly").c_str(), 0755);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(r.errLines(), 1u) << r.err;
  const bool reason = r.err.find("Permission denied") != std::string::npos ||
                      r.err.find("Operation not permitted") != std::string::npos ||
                      r.err.find("No such file or directory") != std::string::npos ||
                      r.err.find("Read-only file system") != std::string::npos;
  EXPECT_TRUE(reason) << r.err;
}

namespace {

// Starts texfab with `args` (a vector of words, no shell), stderr to `errFile`; returns its pid.
pid_t spawn(const std::vector<std::string>& args, const fs::path& errFile) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int err = ::open(errFile.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(err, STDERR_FILENO);
    std::vector<char*> argv{const_cast<char*>(TEXFAB_CLI)};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(TEXFAB_CLI, argv.data());
    ::_exit(127);
  }
  return pid;
}

int waitFor(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 256 + WTERMSIG(status);  // killed: not a texfab exit
}

std::vector<std::string> leftovers(const fs::path& dir) {
  std::vector<std::string> hidden;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().filename().string().front() == '.') hidden.push_back(e.path().string());
  return hidden;
}

// Waits until texfab has printed its first stage line: its signal handling is in place then (a
// signal before main(), while the libraries load, takes the default action and leaves nothing).
void awaitStart(const fs::path& errFile) {
  for (int i = 0; i < 6000 && (!fs::exists(errFile) || fs::file_size(errFile) == 0); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
}

} // namespace

// SIGINT at any moment of a job (synthesis, encoding, writing) ends it with 130 and no temporary,
// or lets it finish whole; a second signal quits at once, also without temporaries.
TEST(Cli, SignalsLeaveNoTemporaries) {
  TempDir d("texfab-cli");
  const std::vector<std::string> job = {"synth", kExemplar.string(), "-o", (d / "big.png").string(), "--size", "2048",
                                        "--no-cache", "--coords", (d / "big.exr").string()};
  int stopped = 0;
  for (int delayMs : {0, 50, 200, 400, 700, 1000, 1500, 2200, 3000}) {
    fs::remove(d / "err.txt");
    const pid_t pid = spawn(job, d / "err.txt");
    awaitStart(d / "err.txt");
    std::this_thread::sleep_for(std::chrono::milliseconds(delayMs));
    ::kill(pid, SIGINT);
    const int status = waitFor(pid);
    EXPECT_TRUE(status == 130 || status == 0) << delayMs << " ms: " << status << " " << readFile(d / "err.txt");
    EXPECT_TRUE(leftovers(d.path()).empty()) << delayMs << " ms: " << leftovers(d.path()).front();
    if (status == 130) {
      ++stopped;
      EXPECT_FALSE(fs::exists(d / "big.png")) << delayMs << " ms";
      EXPECT_FALSE(fs::exists(d / "big.exr")) << delayMs << " ms";
    }
    fs::remove(d / "big.png");
    fs::remove(d / "big.exr");
  }
  EXPECT_GT(stopped, 0);
  for (int delayMs : {100, 600, 1500}) {
    fs::remove(d / "err.txt");
    const pid_t pid = spawn(job, d / "err.txt");
    awaitStart(d / "err.txt");
    std::this_thread::sleep_for(std::chrono::milliseconds(delayMs));
    ::kill(pid, SIGTERM);
    ::kill(pid, SIGTERM);
    const int status = waitFor(pid);
    EXPECT_TRUE(status == 130 || status == 0) << delayMs << " ms: " << status;
    EXPECT_TRUE(leftovers(d.path()).empty()) << delayMs << " ms";
    fs::remove(d / "big.png");
    fs::remove(d / "big.exr");
  }
}

namespace {

// A job of a command that writes files: its arguments ({} stands for the scratch folder) and the
// outputs it writes there.
struct SignalJob {
  std::string command;
  std::vector<std::string> args;
  std::vector<std::string> outputs;
};

// A 400 x 400 grid (320,000 triangles) as OFF, written once: converting it with Draco takes about a
// second, so a signal after its first stage line finds convert at work (the elephant's write takes
// 20 ms, which scheduling on a loaded machine can outlast).
const fs::path& bigGrid() {
  static const TempDir dir("texfab-cli-grid");
  static const fs::path path = [] {
    constexpr int n = 400;
    std::ofstream off(dir / "grid.off");
    off << "OFF\n" << (n + 1) * (n + 1) << " " << 2 * n * n << " 0\n";
    for (int y = 0; y <= n; ++y)
      for (int x = 0; x <= n; ++x) off << x << " " << y << " " << (x * 7 + y * 13) % 5 << "\n";
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const int a = y * (n + 1) + x, c = a + n + 1;
        off << "3 " << a << " " << a + 1 << " " << c + 1 << "\n3 " << a << " " << c + 1 << " " << c << "\n";
      }
    return dir / "grid.off";
  }();
  return path;
}

std::vector<SignalJob> signalJobs() {
  const std::string model = kModel.string(), exemplar = kExemplar.string();
  return {
      {"synth", {exemplar, "-o", "{}/s.png", "--size", "512", "--no-cache", "--coords", "{}/s.exr"}, {"s.png", "s.exr"}},
      {"solid", {exemplar, "-o", "{}/volume", "--volume", "32", "--no-cache"}, {"volume"}},
      {"atlas", {model, "-o", "{}/a.glb", "--resolution", "512"}, {"a.glb"}},
      {"texture",
       {model, "-e", exemplar, "-o", "{}/t.glb", "--resolution", "256", "--no-cache", "--preview", "{}/t.png"},
       {"t.glb", "t.png"}},
      {"cut", {model, "-e", exemplar, "-o", "{}/c.glb", "--plane", "0,0,0,0,1,0", "--resolution", "256", "--no-cache"}, {"c.glb"}},
      {"fracture", {model, "-e", exemplar, "-o", "{}/f.glb", "--pieces", "3", "--resolution", "256", "--no-cache"}, {"f.glb"}},
      {"slice", {model, "-o", "{}/layers", "--height", "20", "--dpi", "100", "--layer", "0.1", "--preview", "{}/l.png"},
       {"layers", "l.png"}},
      {"render", {model, "-o", "{}/r.png", "--size", "300"}, {"r.png"}},
      {"convert", {bigGrid().string(), "{}/m.glb", "--draco"}, {"m.glb"}},
  };
}

std::vector<std::string> withFolder(const SignalJob& job, const fs::path& folder) {
  std::vector<std::string> args{job.command};
  for (std::string a : job.args) {
    if (const size_t at = a.find("{}"); at != std::string::npos) a.replace(at, 2, folder.string());
    args.push_back(a);
  }
  return args;
}

size_t linesIn(const fs::path& file) {
  const std::string text = readFile(file);
  return size_t(std::count(text.begin(), text.end(), '\n'));
}

} // namespace

// Every command that writes files, stopped by SIGINT or SIGTERM after its first, middle and last
// stage lines (and a few milliseconds into the next stage): it ends with 130 and leaves nothing (no output, no
// temporary), or, if it finished first, with 0 and every output in place.
TEST(Cli, EveryCommandStopsCleanlyAtEveryStage) {
  TempDir d("texfab-cli");
  uint32_t random = 12345;
  for (const SignalJob& job : signalJobs()) {
    SCOPED_TRACE(job.command);
    const fs::path folder = d / job.command;
    fs::create_directories(folder);
    // A whole run: its stage lines (progress without a terminal prints one per finished stage).
    const pid_t whole = spawn(withFolder(job, folder), d / "err.txt");
    ASSERT_EQ(waitFor(whole), 0) << readFile(d / "err.txt");
    const size_t stages = linesIn(d / "err.txt");
    for (const std::string& out : job.outputs) fs::remove_all(folder / out);
    int stopped = 0;
    for (size_t stage : {size_t(0), stages / 2, stages - 1}) {
      fs::remove(d / "err.txt");
      const pid_t pid = spawn(withFolder(job, folder), d / "err.txt");
      awaitStart(d / "err.txt");
      for (int i = 0; i < 60000 && linesIn(d / "err.txt") < stage; ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      random = random * 1103515245u + 12345u;
      std::this_thread::sleep_for(std::chrono::milliseconds((random >> 16) % 40));
      const int signal = stage % 2 ? SIGTERM : SIGINT;
      ::kill(pid, signal);
      const int status = waitFor(pid);
      const std::string where = "after stage " + std::to_string(stage) + " of " + std::to_string(stages) + ", " +
                                (signal == SIGINT ? "SIGINT" : "SIGTERM") + ": ";
      EXPECT_TRUE(status == 130 || status == 0) << where << status << " " << readFile(d / "err.txt");
      const std::vector<std::string> left = leftovers(folder);
      EXPECT_TRUE(left.empty()) << where << left.front();
      for (const std::string& out : job.outputs) {
        EXPECT_EQ(fs::exists(folder / out), status == 0) << where << out;
        fs::remove_all(folder / out);
      }
      stopped += status == 130;
    }
    EXPECT_GT(stopped, 0) << "no signal arrived before the job finished";
  }
}

// Every command whose work can outgrow memory refuses, before any work, a job its estimate says
// will not fit in --max-memory: one line naming the flag, exit 2, no output.
TEST(Cli, EveryLongCommandRefusesWorkBeyondMaxMemory) {
  TempDir d("texfab-cli");
  int commands = 0;
  for (const SignalJob& job : signalJobs()) {
    if (runCli(job.command + " --help").out.find("--max-memory") == std::string::npos) continue;
    ++commands;
    std::vector<std::string> args = withFolder(job, d.path());
    args.insert(args.end(), {"--max-memory", "1K"});
    fs::remove(d / "err.txt");
    const int status = waitFor(spawn(args, d / "err.txt"));
    const std::string err = readFile(d / "err.txt");
    EXPECT_EQ(status, 2) << job.command << ": " << err;
    EXPECT_NE(err.find("allowed (--max-memory)"), std::string::npos) << job.command << ": " << err;
    EXPECT_EQ(err.find("error:"), err.rfind("error:")) << job.command << ": " << err;
    for (const std::string& out : job.outputs) EXPECT_FALSE(fs::exists(d / out)) << job.command << ": " << out;
    EXPECT_TRUE(leftovers(d.path()).empty()) << job.command;
  }
  EXPECT_EQ(commands, 8);  // synth, solid, atlas, texture, cut, fracture, slice, render
  const CliResult stats = runCli("stats " + quote(kExemplar) + " --exemplar " + quote(kExemplar) + " --max-memory 1K");
  EXPECT_EQ(stats.status, 2) << stats.err;
  EXPECT_NE(stats.err.find("measuring a "), std::string::npos) << stats.err;
  EXPECT_EQ(runCli("synth " + quote(kExemplar) + " -o " + quote(d / "o.png") + " --max-memory lots").status, 1);
}

// A disk that fills up (a file size limit, SIGXFSZ ignored, fails writes as a full disk does) while
// the analysis cache and the GLB are written: the cache is skipped with a warning and leaves no file,
// the GLB's write is the one-line error naming the output, and the previous output is untouched.
TEST(Cli, AFullDiskKeepsThePreviousOutputAndNoPartialCache) {
  TempDir d("texfab-cli");
  std::ofstream(d / "e.glb") << "previous";
  const fs::path cache = d / "cache";
  fs::create_directories(cache);
  const std::string command = "bash -c \"trap '' XFSZ; ulimit -f 200; '" + std::string(TEXFAB_CLI) + "' texture " +
                              quote(kModel) + " -e " + quote(kExemplar) + " -o " + quote(d / "e.glb") +
                              " --resolution 512 -q --cache-dir " + quote(cache) + "\" 2>" + quote(d / "err.txt");
  EXPECT_EQ(texfab::test::run(command), 2);
  const std::string err = readFile(d / "err.txt");
  EXPECT_NE(err.find("warning: the analysis cache cannot be written"), std::string::npos) << err;
  EXPECT_NE(err.find("error: " + (d / "e.glb").string() + ": cannot write file: File too large"), std::string::npos) << err;
  EXPECT_EQ(err.find("error:"), err.rfind("error:")) << err;
  EXPECT_EQ(readFile(d / "e.glb"), "previous");
  EXPECT_TRUE(leftovers(d.path()).empty()) << leftovers(d.path()).front();
  EXPECT_TRUE(fs::is_empty(cache));
}

// The analysis cache keeps within --cache-size, dropping the least recently used analysis; a
// cache that cannot be written is said once, and the job still succeeds.
TEST(Cli, AnalysisCacheIsBoundedAndAnUnwritableOneIsSaidOnce) {
  TempDir d("texfab-cli");
  const fs::path cache = d / "cache";
  std::vector<fs::path> exemplars;
  for (const char* name : {"marble.png", "brick.png"}) {  // the first analysis is the larger
    const fs::path e = kSource / "models" / "exemplars" / name;
    if (fs::exists(e)) exemplars.push_back(e);
  }
  ASSERT_GE(exemplars.size(), 2u);
  auto synth = [&](const fs::path& exemplar, const std::string& extra) {
    return runCli("synth " + quote(exemplar) + " -o " + quote(d / "o.png") + " --size 32 -q --cache-dir " + quote(cache) +
                  " " + extra);
  };
  auto cached = [&] {
    std::vector<std::pair<fs::path, uintmax_t>> files;
    for (const auto& e : fs::directory_iterator(cache)) files.emplace_back(e.path(), e.file_size());
    return files;
  };
  ASSERT_EQ(synth(exemplars[0], "").status, 0);
  ASSERT_EQ(cached().size(), 1u);
  const auto [first, size] = cached()[0];
  // Room for one analysis: the second run keeps its own, the least recently used goes.
  ASSERT_EQ(synth(exemplars[1], "--cache-size " + std::to_string(size + size / 2)).status, 0);
  const auto left = cached();
  ASSERT_EQ(left.size(), 1u);
  EXPECT_NE(left[0].first, first);
  ASSERT_EQ(synth(exemplars[0], "--cache-size 1G").status, 0);
  EXPECT_EQ(cached().size(), 2u);
  EXPECT_NE(runCli("synth --help").out.find("--cache-size"), std::string::npos);

  // A cache folder that is a file: said once, as a warning, and the job succeeds.
  std::ofstream(d / "file") << "x";
  const CliResult r = runCli("synth " + quote(exemplars[0]) + " -o " + quote(d / "o.png") + " --size 32 -q --cache-dir " +
                             quote(d / "file" / "cache"));
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.errLines(), 1u) << r.err;
  EXPECT_NE(r.err.find("warning: the analysis cache cannot be written"), std::string::npos) << r.err;
}
