#include "bench/io/term_spec_text.h"

#include <sstream>
#include <vector>

#include "calib/common/errors.h"

namespace twin {
namespace {

int WholeNumber(const std::string& s, const std::string& what, const std::string& text,
                const std::string& where) {
  std::size_t used = 0;
  int v = 0;
  try {
    v = std::stoi(s, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (s.empty() || used != s.size()) {
    throw InputError(where, "\"" + text + "\": the " + what + " \"" + s +
                                "\" is not a whole number (expected TYPE[:JOINT[:ORDERS]], e.g. "
                                "joint_compliance:2 or transmission_error:4:1,2)");
  }
  return v;
}

}  // namespace

TermSpec ParseTermSpec(const std::string& text, const std::string& where) {
  std::vector<std::string> parts;
  std::stringstream ss(text);
  std::string part;
  while (std::getline(ss, part, ':')) parts.push_back(part);
  if (parts.empty() || parts[0].empty() || parts.size() > 3 || text.back() == ':') {
    throw InputError(where, "\"" + text + "\": expected TYPE[:JOINT[:ORDERS]], e.g. "
                            "joint_compliance:2 or transmission_error:4:1,2");
  }
  TermSpec spec;
  spec.type = parts[0];
  // An empty joint before orders: a whole-robot term with an order (thermal_warmup::30).
  if (parts.size() >= 2 && !(parts.size() == 3 && parts[1].empty())) {
    spec.joint = WholeNumber(parts[1], "joint", text, where) - 1;
  }
  if (parts.size() == 3) {
    std::stringstream os(parts[2]);
    std::string order;
    while (std::getline(os, order, ',')) {
      spec.orders.push_back(WholeNumber(order, "order", text, where));
    }
  }
  return spec;
}

}  // namespace twin
