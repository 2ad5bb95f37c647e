// Report conventions shared by the tracker reports (bench/runs/tracker_run.cc,
// bench/runs/tracker_identify_run.cc): SI values in report units and point-error statistics.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "calib/procedures/tracker_calibration.h"

namespace twin {

/// A value in report units: m -> mm, rad -> deg, others as they are.
double ReportValue(double v, const std::string& si_unit);
/// The report unit of an SI unit ("m" -> "mm", "rad" -> "deg", others as they are).
std::string ReportUnit(const std::string& si_unit);

/// {rms_mm, mean_mm, max_mm, poses} of point errors.
nlohmann::json PointErrorsJson(const PointErrors& e);

}  // namespace twin
