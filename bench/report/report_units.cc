#include "bench/report/report_units.h"

#include "calib/common/frames.h"

namespace twin {

double ReportValue(double v, const std::string& si_unit) {
  return si_unit == "m" ? 1e3 * v : si_unit == "rad" ? RadToDeg(v) : v;
}

std::string ReportUnit(const std::string& si_unit) {
  return si_unit == "m" ? "mm" : si_unit == "rad" ? "deg" : si_unit;
}

nlohmann::json PointErrorsJson(const PointErrors& e) {
  return {{"rms_mm", 1e3 * e.rms}, {"mean_mm", 1e3 * e.mean}, {"max_mm", 1e3 * e.max},
          {"poses", e.poses}};
}

}  // namespace twin
