// Plain-words YAML syntax errors (issue #28 item 4). yaml-cpp reports a missing '}' where it gives
// up, often at the start of the next line ("35:8: end of map flow not found" for a '{' left open on
// line 34). explain_yaml_syntax_error scans the text's flow brackets and quotes (skipping comments
// and quoted text) and, where it finds the construct that was left open or closed wrongly, returns
// the place where the token is missing and a message that says so in plain words.
#pragma once
#include <optional>
#include <string>

namespace turbid::tools {

struct YamlSyntaxHint {
  int line = 0;    // 0-based, as YAML::Mark
  int column = 0;  // 0-based
  std::string message;
};

// text: the whole file; line, column: yaml-cpp's mark (0-based); what: yaml-cpp's message.
std::optional<YamlSyntaxHint> explain_yaml_syntax_error(const std::string& text, int line, int column,
                                                        const std::string& what);

}  // namespace turbid::tools
