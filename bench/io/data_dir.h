// Where twinbench finds the files it ships (models/, scenarios/): the source tree for the
// binary of a build tree, <prefix>/share/twinbench for an installed one (found from the
// executable's own location, so an installed tree can be moved), or TWINBENCH_DATA_DIR.
#pragma once

#include <string>

namespace twin {

/// The data folder, resolved in this order:
///  1. the environment variable TWINBENCH_DATA_DIR, when set and not empty (it must name a
///     folder, else InputError naming the variable);
///  2. the source tree, when this process's executable lies in the build tree's bin/;
///  3. ../share/twinbench beside the executable's folder (the installed layout, from
///     /proc/self/exe), when it holds models/.
/// Otherwise an InputError naming the folder looked at and TWINBENCH_DATA_DIR.
std::string DataDir();

/// DataDir() + "/" + relative, which must exist (InputError naming it otherwise).
std::string DataFile(const std::string& relative);

}  // namespace twin
