// The output mark `.twinbench-output` (bench/io/output_files.h) as a file format: one JSON
// object {"written_by": "twinbench", "verb": VERB} and a newline. Compiled into bench_io (the
// output folders' rules), not bench_twin (bench/CMakeLists.txt).
#pragma once

#include <string>

namespace twin {

/// The mark's text for `verb`, newline included.
std::string OutputMarkText(const std::string& verb);

/// The verb a mark's text names, or "" when the text is not a twinbench mark (not JSON, not
/// an object, written by someone else, or without a string verb).
std::string OutputMarkVerb(const std::string& text);

}  // namespace twin
