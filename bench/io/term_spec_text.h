// Error terms named on the command line or in a scenario: TYPE[:JOINT[:ORDERS]], e.g.
// "joint_compliance:2", "transmission_error:4:1,2", "thermal_drift" (joints 1-based, orders
// comma-separated). The type, joint range and orders are checked where the term is built
// (MakeErrorTerm); here only the text.
#pragma once

#include <string>

#include "calib/model/error_term.h"

namespace twin {

/// Parses `text`; throws InputError naming `where` for a malformed one.
TermSpec ParseTermSpec(const std::string& text, const std::string& where);

}  // namespace twin
