// Number formatting shared by the writers of model files, MJCF and reports.
#pragma once

#include <string>

namespace twin {

/// The shortest decimal text that reads back to exactly v ("0.05", not "0.050000000000000003";
/// never "-0").
std::string ShortestNumber(double v);

}  // namespace twin
