#include "bench/io/csv.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "calib/common/errors.h"

namespace twin {

std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(item);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

double CsvNumber(const std::string& text, const std::string& where) {
  try {
    size_t used = 0;
    const double v = std::stod(text, &used);
    if (used != text.size() || !std::isfinite(v)) throw std::invalid_argument("");
    return v;
  } catch (const std::exception&) {
    throw InputError(where, "expected a finite number, got '" + text + "'");
  }
}

int CsvInteger(const std::string& text, const std::string& where) {
  const double v = CsvNumber(text, where);
  if (v != std::floor(v) || v < 0 || v > 1e6) {
    throw InputError(where, "expected a whole number >= 0, got '" + text + "'");
  }
  return static_cast<int>(v);
}

}  // namespace twin
