// The `turbid` program's command line as a user meets it (issue #28 items 1-3): command-line
// overrides meet the same checks as the scene's values, values out of range are refused naming the
// option, `--version` exists, an unknown command is named, and the exit codes are the ones
// `turbid --help` and the README list. Runs the built program.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>

namespace {

struct Result {
  int code = -1;
  std::string output;  // stdout and stderr together
};

Result turbid(const std::string& args) {
  const std::string command = std::string(TURBID_BINARY) + " " + args + " 2>&1";
  Result r;
  FILE* p = popen(command.c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buffer{};
  std::size_t n = 0;
  while ((n = fread(buffer.data(), 1, buffer.size(), p)) > 0) r.output.append(buffer.data(), n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

const std::string kScene = std::string(TURBID_SOURCE_DIR) + "/scenes/dam_break_2d.yaml";
const std::string kOut = std::string(TURBID_BUILD_DIR) + "/cli_test_run";

TEST(CommandLine, AnOverriddenSpacingMeetsTheScenesChecks) {
  // 0.5 m is wider than the 0.057 m water column: the same refusal as in the scene file, saying
  // where the value came from (it once printed "scene OK" with one fluid particle).
  const Result r = turbid("check " + kScene + " --spacing 0.5");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("dam_break_2d.yaml:45:28: error: the fluid 'box' is 0.05715 m wide"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("(with --spacing 0.5 from the command line)"), std::string::npos) << r.output;
  EXPECT_EQ(turbid("check " + kScene + " --spacing 0.003").code, 0);
}

TEST(CommandLine, ValuesOutOfRangeAreRefusedNamingTheOption) {
  const struct {
    const char* args;
    int code;
    const char* says;
  } cases[] = {
      {" --end 0", 2, "turbid: --end 0: must be a positive time [s]"},
      {" --spacing 0", 2, "turbid: --spacing 0: must be a positive length [m]"},
      {" --checkpoint-every -1", 2, "turbid: --checkpoint-every -1: must be a time >= 0 [s]"},
      {" --checkpoint-every 1e-300", 2, "asks for 2.5e+299 checkpoints"},
      {" --threads -1", 105, "--threads: Value -1 not in range 0 to 4096"},
  };
  for (const auto& c : cases) {
    const Result r = turbid("run " + kScene + " --quiet --out " + kOut + c.args);
    EXPECT_EQ(r.code, c.code) << c.args << ": " << r.output;
    EXPECT_NE(r.output.find(c.says), std::string::npos) << c.args << ": " << r.output;
  }
}

TEST(CommandLine, TheEndTimeAskedIsTheEndTimeRun) {
  const Result r = turbid("run " + kScene + " --quiet --end 0.001 --out " + kOut);
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(kOut + "/run.json");
  const std::string json((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // The last step lands on the end time (it once went on to the end of a whole larger step).
  EXPECT_NE(json.find("\"simulated_time\": 0.001,"), std::string::npos) << json.substr(0, 2000);
}

TEST(CommandLine, VersionUnknownCommandsAndExitCodes) {
  const Result v = turbid("--version");
  EXPECT_EQ(v.code, 0);
  EXPECT_EQ(v.output.rfind("turbid ", 0), 0u) << v.output;
  const Result bogus = turbid("bogus");
  EXPECT_EQ(bogus.code, 109) << bogus.output;
  EXPECT_NE(bogus.output.find("bogus"), std::string::npos) << bogus.output;
  const Result none = turbid("");
  EXPECT_EQ(none.code, 2) << none.output;
  EXPECT_NE(none.output.find("give a command: run, check or info"), std::string::npos) << none.output;
  const Result help = turbid("--help");
  EXPECT_EQ(help.code, 0);
  for (const char* code : {"Exit codes: 0 done; 1 a run-time error; 2 a scene error", "3 a run that blew up or failed",
                           "130 / 143", "105-114"})
    EXPECT_NE(help.output.find(code), std::string::npos) << code << " in: " << help.output;
}

}  // namespace
