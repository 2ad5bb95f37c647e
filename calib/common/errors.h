// The project's two kinds of error (DESIGN.md, convention 6): checks for our own bugs, and
// InputError for bad user input, carrying where it was found (file, key or line) and what was
// expected. The CLI maps InputError to exit code 2 ("error: ...") and a broken precondition
// (PreconditionError, from TWIN_REQUIRE) to exit code 1 ("internal error: ..."). A value a
// user can put in a file or on the command line is input, checked with InputError where it is
// read or used; a condition that only a caller's mistake in our code can break is a
// precondition, checked with TWIN_REQUIRE. No code turns a PreconditionError into a note.
#pragma once

#include <sstream>
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

/// A broken precondition: a bug in the calling code, never the user's input. Thrown by
/// TWIN_REQUIRE; what() is "<file>:<line>: precondition `<condition>` failed: <message>".
class PreconditionError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

/// Throws PreconditionError naming the failed condition and where it was checked.
[[noreturn]] inline void FailPrecondition(const char* condition, const std::string& message,
                                          const char* file, int line) {
  std::ostringstream os;
  os << file << ":" << line << ": precondition `" << condition << "` failed: " << message;
  throw PreconditionError(os.str());
}

}  // namespace twin

/// Checks a precondition of our own code (not the user's input; that is InputError). On
/// failure throws twin::PreconditionError, which the CLI reports as an internal error, exit 1.
/// `message` is a std::string expression evaluated only on failure.
#define TWIN_REQUIRE(condition, message)                                   \
  do {                                                                     \
    if (!(condition)) {                                                    \
      ::twin::FailPrecondition(#condition, (message), __FILE__, __LINE__); \
    }                                                                      \
  } while (0)
