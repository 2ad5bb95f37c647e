// Helpers of the bench/ tests that edit a valid input file's text into a broken one and find
// the line the parser must report.
#pragma once

#include <algorithm>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

namespace twin::testing {

inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// text with the first occurrence of `from` replaced by `to` (a test failure if absent).
inline std::string Replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t pos = text.find(from);
  if (pos == std::string::npos) {
    ADD_FAILURE() << "test input lacks '" << from << "'";
    return text;
  }
  return text.replace(pos, from.size(), to);
}

/// A shipped scenario's text with its model paths ("../models/...", relative to scenarios/)
/// pointing into the source tree, so an edited copy can be written anywhere.
inline std::string AbsoluteModels(std::string text) {
  for (std::size_t p; (p = text.find("../models/")) != std::string::npos;) {
    text.replace(p, 10, std::string(TWIN_SOURCE_DIR) + "/models/");
  }
  return text;
}

/// 1-based line of the first occurrence of needle in text.
inline int LineOf(const std::string& text, const std::string& needle) {
  const std::size_t pos = text.find(needle);
  EXPECT_NE(pos, std::string::npos) << needle;
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + pos, '\n'));
}

}  // namespace twin::testing
