#include "tools/yaml_syntax.hpp"

#include <cctype>
#include <sstream>
#include <vector>

namespace turbid::tools {

namespace {

struct Open {
  char c;
  int line, column;
};

char closer_of(char open) { return open == '{' ? '}' : ']'; }

std::string at(int line, int column) { return std::to_string(line + 1) + ":" + std::to_string(column + 1); }

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::string cur;
  for (char c : text) {
    if (c == '\n') {
      if (!cur.empty() && cur.back() == '\r') cur.pop_back();
      lines.push_back(cur);
      cur.clear();
    } else {
      cur.push_back(c);
    }
  }
  lines.push_back(cur);
  return lines;
}

// The last character before i that is not a space, or '\0' at the start of the line.
char previous_non_space(const std::string& s, std::size_t i) {
  while (i > 0) {
    --i;
    if (s[i] != ' ' && s[i] != '\t') return s[i];
  }
  return '\0';
}

// Where a line's content (without a comment) ends, and its indentation; -1 for blank or comment lines.
struct Shape {
  int indent = -1;
  bool key = false;  // starts with "name:" or "- " (a new block entry)
};

Shape shape_of(const std::string& s) {
  Shape sh;
  std::size_t i = 0;
  while (i < s.size() && s[i] == ' ') ++i;
  if (i == s.size() || s[i] == '#') return sh;
  sh.indent = int(i);
  if (s[i] == '-' && (i + 1 == s.size() || s[i + 1] == ' ')) {
    sh.key = true;
    return sh;
  }
  std::size_t j = i;
  while (j < s.size() && (std::isalnum(static_cast<unsigned char>(s[j])) || s[j] == '_')) ++j;
  sh.key = j > i && j < s.size() && s[j] == ':' && (j + 1 == s.size() || s[j + 1] == ' ');
  return sh;
}

// The next line after l that has content.
Shape next_content(const std::vector<std::string>& lines, std::size_t l) {
  for (std::size_t k = l + 1; k < lines.size(); ++k) {
    const Shape sh = shape_of(lines[k]);
    if (sh.indent >= 0) return sh;
  }
  return {};
}

// The column just past the line's content, before a comment and trailing spaces.
int content_end(const std::string& s) {
  bool quoted = false;
  char q = 0;
  std::size_t end = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    if (quoted) {
      if (c == q) quoted = false;
      end = i + 1;
      continue;
    }
    if (c == '#' && (i == 0 || s[i - 1] == ' ')) break;
    if (c == '"' || c == '\'') quoted = true, q = c;
    if (c != ' ' && c != '\t') end = i + 1;
  }
  return int(end);
}

bool before_or_at(int l, int c, int line, int column) { return l < line || (l == line && c <= column); }

}  // namespace

std::optional<YamlSyntaxHint> explain_yaml_syntax_error(const std::string& text, int line, int column,
                                                        const std::string& what) {
  const std::vector<std::string> lines = split_lines(text);
  std::vector<Open> stack;
  const std::string tail = " (YAML parser: " + what + ")";
  for (std::size_t l = 0; l < lines.size(); ++l) {
    const std::string& s = lines[l];
    const int L = int(l);
    for (std::size_t i = 0; i < s.size(); ++i) {
      const char c = s[i];
      const int C = int(i);
      if (c == '#' && (i == 0 || s[i - 1] == ' ' || s[i - 1] == '\t')) break;  // a comment
      const char prev = previous_non_space(s, i);
      const bool value_start = prev == '\0' || prev == ':' || prev == ',' || prev == '[' || prev == '{' || prev == '-';
      if ((c == '"' || c == '\'') && (value_start || !stack.empty())) {
        // A quoted scalar: find its end on this line ('' and \" escape).
        std::size_t j = i + 1;
        bool closed = false;
        for (; j < s.size(); ++j) {
          if (c == '"' && s[j] == '\\') {
            ++j;
            continue;
          }
          if (s[j] == c) {
            if (c == '\'' && j + 1 < s.size() && s[j + 1] == '\'') {
              ++j;
              continue;
            }
            closed = true;
            break;
          }
        }
        if (!closed) {
          if (before_or_at(L, C, line, column))
            return YamlSyntaxHint{L, C, std::string("the ") + c + " opened here is not closed on its line: a closing " +
                                            c + " is missing" + tail};
          return std::nullopt;
        }
        i = j;
        continue;
      }
      if ((c == '{' || c == '[') && (value_start || !stack.empty())) {
        stack.push_back({c, L, C});
        continue;
      }
      if ((c == '}' || c == ']') && !stack.empty()) {
        const Open o = stack.back();
        if (closer_of(o.c) == c) {
          stack.pop_back();
          continue;
        }
        if (!before_or_at(L, C, line, column)) return std::nullopt;
        return YamlSyntaxHint{L, C, std::string("this '") + c + "' comes while the '" + o.c + "' opened at " +
                                        at(o.line, o.column) + " is still open: a '" + closer_of(o.c) +
                                        "' is missing before it" + tail};
      }
      if ((c == '}' || c == ']') && stack.empty() && (value_start || prev == '}' || prev == ']')) {
        if (!before_or_at(L, C, line, column)) return std::nullopt;
        return YamlSyntaxHint{L, C, std::string("this '") + c + "' closes nothing: remove it, or add the '" +
                                        (c == '}' ? '{' : '[') + "' it should close" + tail};
      }
    }
    // A bracket still open at the end of a line whose next content line starts a new key at the
    // same or a smaller indentation was never closed: the closer belongs at the end of this line.
    if (!stack.empty()) {
      const Shape here = shape_of(lines[std::size_t(stack.front().line)]);
      const Shape next = next_content(lines, l);
      if (next.indent < 0 || (next.key && next.indent <= here.indent)) {
        const Open o = stack.back();
        const int end = content_end(s);
        if (!before_or_at(L, end, line, column) && next.indent >= 0) return std::nullopt;
        std::string missing;
        for (auto it = stack.rbegin(); it != stack.rend(); ++it) missing.push_back(closer_of(it->c));
        return YamlSyntaxHint{L, end, std::string("the '") + o.c + "' opened at " + at(o.line, o.column) +
                                          " is not closed: '" + missing + "' is missing at the end of line " +
                                          std::to_string(L + 1) + tail};
      }
    }
  }
  // No bracket or quote to blame: the same place, the message in plain words where we know it.
  std::string plain;
  bool tab_indent = false;
  if (line >= 0 && std::size_t(line) < lines.size())
    for (char c : lines[std::size_t(line)]) {
      if (c == '\t') tab_indent = true;
      if (c != ' ' && c != '\t') break;
    }
  if (tab_indent || what.find("tab") != std::string::npos)
    plain = "a tab in the indentation: YAML indents with spaces only";
  else if (what == "illegal map value")
    plain = "a ':' where no key may start: indent this line under the key it belongs to, or quote a text "
            "that holds ': '";
  else if (what == "end of map not found" || what == "end of sequence not found")
    plain = "this line's indentation does not fit the block above it: keys of one map line up, and a list "
            "item starts with '- ' at its map's indentation or deeper";
  else if (what == "illegal block entry")
    plain = "a '- ' list item where a key was expected: a list goes under its key, indented";
  else
    return std::nullopt;
  return YamlSyntaxHint{line, tab_indent ? 0 : column, plain + tail};
}

}  // namespace turbid::tools
