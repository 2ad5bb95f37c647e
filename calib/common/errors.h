// The project's two kinds of error (DESIGN.md, convention 6): asserts for our own bugs, and
// InputError for bad user input, carrying where it was found (file, key or line) and what was
// expected. The CLI maps InputError to exit code 2.
#pragma once

#include <stdexcept>
#include <string>

namespace twin {

/// Bad user input: a malformed file, an unknown key, a value out of range, an unreachable
/// request. what() is "<where>: <message>" so the user can find and fix the input.
class InputError : public std::runtime_error {
 public:
  /// where: file and key/line (e.g. "models/r1.yaml:12 links[2].alpha"); message: what was
  /// wrong and what was expected.
  InputError(const std::string& where, const std::string& message)
      : std::runtime_error(where.empty() ? message : where + ": " + message),
        where_(where),
        message_(message) {}
  const std::string& where() const { return where_; }
  const std::string& message() const { return message_; }

 private:
  std::string where_;
  std::string message_;
};

}  // namespace twin
