#include "calib/common/text_format.h"

#include <charconv>

namespace twin {

std::string ShortestNumber(double v) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof(buf), v == 0.0 ? 0.0 : v);
  return std::string(buf, res.ptr);
}

}  // namespace twin
