// YAML syntax errors point at the mistake, in plain words (issue #28 item 4): yaml-cpp reported a
// '}' missing on line 34 at 35:8 ("end of map flow not found"). Reference: each case's text, where
// the missing or stray token is known by construction.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "tools/scene_reader.hpp"

namespace {

using namespace turbid;

// The message read_scene_string throws for `yaml` ("" if it reads).
std::string error_of(const std::string& yaml) {
  try {
    tools::read_scene_string(yaml, "test.yaml");
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

std::string shipped_scene(const std::string& name) {
  std::ifstream in(std::string(TURBID_SOURCE_DIR) + "/scenes/" + name);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Replaces the first `from` after line `line` (1-based) with `to`; the line must hold it.
std::string edit_line(const std::string& text, int line, const std::string& from, const std::string& to) {
  std::size_t pos = 0;
  for (int l = 1; l < line; ++l) pos = text.find('\n', pos) + 1;
  const std::size_t at = text.find(from, pos);
  EXPECT_LT(at, text.find('\n', pos)) << "line " << line << " has no '" << from << "'";
  return text.substr(0, at) + to + text.substr(at + from.size());
}

int line_holding(const std::string& text, const std::string& what) {
  const std::size_t at = text.find(what);
  EXPECT_NE(at, std::string::npos) << what;
  int line = 1;
  for (std::size_t i = 0; i < at; ++i) line += text[i] == '\n';
  return line;
}

TEST(YamlSyntax, AMissingClosingBraceIsReportedOnItsOwnLine) {
  // The dam break's material line loses its '}'; the next line starts a new key.
  const std::string scene = shipped_scene("dam_break_2d.yaml");
  const int line = line_holding(scene, "  water: {model: newtonian");
  const std::string bad = edit_line(scene, line, "sound_speed: 20}", "sound_speed: 20");
  const std::string e = error_of(bad);
  EXPECT_EQ(e.rfind("test.yaml:" + std::to_string(line) + ":", 0), 0u) << e;
  EXPECT_NE(e.find("the '{' opened at " + std::to_string(line) + ":10 is not closed: '}' is missing at the end of line " +
                   std::to_string(line)),
            std::string::npos)
      << e;
}

TEST(YamlSyntax, AMissingBracketInsideABraceIsNamedAtTheBraceThatComesTooEarly) {
  const std::string e = error_of("name: x\ndimensions: 2\nwalls:\n  - box: {min: [0, 0, max: [1, 1]}\n");
  EXPECT_EQ(e.rfind("test.yaml:4:34: error: invalid YAML: this '}' comes while the '[' opened at 4:16 is still open: "
                    "a ']' is missing before it",
                    0),
            0u)
      << e;
}

TEST(YamlSyntax, AStrayClosingBraceClosesNothing) {
  const std::string e = error_of("name: x\ndimensions: 2\nwalls:\n  - box: {min: [0, 0], max: [1, 1]}}\n");
  EXPECT_EQ(e.rfind("test.yaml:4:36: error: invalid YAML: this '}' closes nothing", 0), 0u) << e;
}

TEST(YamlSyntax, AnOpenQuoteAndATabAreNamed) {
  const std::string q = error_of("name: x\ndimensions: 2\nwalls:\n  - box: {min: [0, 0], max: [1, \"1]}\n");
  EXPECT_EQ(q.rfind("test.yaml:4:33: error: invalid YAML: the \" opened here is not closed on its line", 0), 0u) << q;
  const std::string t = error_of("name: x\ndimensions: 2\nmaterials:\n  water: {density: 1000}\n\tsound: 3\n");
  EXPECT_EQ(t.rfind("test.yaml:5:1: error: invalid YAML: a tab in the indentation", 0), 0u) << t;
}

TEST(YamlSyntax, ABracketLeftOpenOverSeveralLinesIsFoundWhereTheNextKeyStarts) {
  // A flow sequence may span lines; it is the next top-level key that shows it was never closed.
  const std::string e =
      error_of("name: x\ndimensions: 2\ngravity: [0,\n  -9.81\nwalls:\n  - box: {min: [0, 0], max: [1, 1]}\n");
  EXPECT_EQ(e.rfind("test.yaml:4:8: error: invalid YAML: the '[' opened at 3:10 is not closed: ']' is missing at the "
                    "end of line 4",
                    0),
            0u)
      << e;
}

}  // namespace
