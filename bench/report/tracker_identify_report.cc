#include "bench/report/tracker_identify_report.h"

#include <nlohmann/json.hpp>

#include "bench/report/diagnosis_report.h"
#include "bench/report/report_html.h"
#include "bench/report/report_units.h"

namespace twin {
namespace {

using json = nlohmann::json;

// The file, its columns and the rank causes.
json FileJson(const TrackerIdentifyResult& r) {
  const TrackerFile& file = *r.measurements;
  json j;
  j["file"] = r.file;
  j["model"] = r.model;
  j["robot"] = r.robot;
  j["points"] = file.points.size();
  j["distinct_poses"] = file.distinct_poses;
  j["rank_causes"] = r.rank_causes;
  j["columns"] = {{"joints", file.joint_columns},
                  {"sigma", file.has_sigma},
                  {"time", file.has_time},
                  {"temperature", file.has_temperature}};
  j["columns"]["ignored"] = json::array();
  for (const TrackerFileColumn& c : file.ignored) {
    j["columns"]["ignored"].push_back({{"name", c.name}, {"min", c.min}, {"max", c.max}});
  }
  return j;
}

// heldout.session: the second session's scores of the nominal, the geometric and the
// discovered model (null without --validate; discovered null with --no-diagnosis).
json SessionJson(const TrackerCalibrationResult& r, const DiscoveryResult* diagnosis) {
  if (!r.session_nominal || !r.session_geometric) return nullptr;
  const SessionScore& n = *r.session_nominal;
  json j = {{"rule", "the validation file (another session): per halving the tracker pose is "
                     "refitted on a random half of its poses and the other half is scored; "
                     "each model as trained on the measurements file; the same halvings for "
                     "every model"},
            {"points", n.points},
            {"halvings", n.halvings},
            {"nominal", SessionScoreJson(n)},
            {"geometric", SessionScoreJson(*r.session_geometric)},
            {"discovered", nullptr}};
  if (diagnosis && diagnosis->session_discovered) {
    j["discovered"] = SessionScoreJson(*diagnosis->session_discovered);
  }
  return j;
}

// The held-out splits and all points' errors before and after.
void AddHeldOut(const TrackerCalibrationResult& r, const DiscoveryResult* diagnosis,
                json* report) {
  json& j = *report;
  for (const HeldOutSplit& s : r.splits) {
    j["heldout"][s.name] = {{"rule", s.rule},
                            {"training_poses", s.training},
                            {"before", PointErrorsJson(s.before)},
                            {"after", PointErrorsJson(s.after)},
                            {"training_after", PointErrorsJson(s.training_after)},
                            {"worse", s.worse}};
  }
  j["heldout"]["session"] = SessionJson(r, diagnosis);
  j["all_points"] = {{"before", PointErrorsJson(r.all_before)},
                     {"after", PointErrorsJson(r.all_after)}};
}

// The parameters, the identification's figures and the correlations.
void AddIdentification(const IdentificationResult& id, json* report) {
  json& j = *report;
  j["parameters"] = json::array();
  for (const IdentifiedParameter& p : id.parameters) {
    const double est = ReportValue(p.estimated, p.unit), start = ReportValue(p.start, p.unit);
    const double sigma = ReportValue(p.sigma, p.unit);
    const std::string unit = ReportUnit(p.unit);
    j["parameters"].push_back({{"name", p.name}, {"unit", unit}, {"nominal", start},
                               {"estimated", est}, {"correction", est - start},
                               {"sigma", sigma}});
  }
  j["unidentifiable"] = id.observability.unidentifiable;
  j["condition_number"] = id.condition_number();
  j["rank"] = id.observability.rank;
  j["sigma0"] = id.sigma0;
  j["correlations"] = json::array();
  for (const ParameterCorrelation& c : id.correlations) {
    j["correlations"].push_back({{"a", c.a}, {"b", c.b}, {"rho", c.rho}});
  }
}

// The tracker's pose in the robot's base frame.
json TrackerPoseJson(const Transform& X_TB) {
  const Eigen::AngleAxisd aa(X_TB.linear());
  return {{"xyz_mm", {1e3 * X_TB.translation().x(), 1e3 * X_TB.translation().y(),
                      1e3 * X_TB.translation().z()}},
          {"rotation_deg", aa.angle() * 180.0 / 3.14159265358979323846},
          {"rotation_axis", {aa.axis().x(), aa.axis().y(), aa.axis().z()}}};
}

json TrackerIdentifyReportJson(const TrackerIdentifyResult& r) {
  const TrackerCalibrationResult& calibration = *r.calibration;
  json j = FileJson(r);
  AddHeldOut(calibration, r.diagnosis, &j);
  AddIdentification(calibration.identified, &j);
  j["tracker_pose"] = TrackerPoseJson(calibration.X_TB);
  j["declared_terms"] = r.declared_terms;
  if (r.diagnosis) {
    j["diagnosis"] = DiagnosisJson(*r.diagnosis);
  } else {
    j["diagnosis"] = {{"verdict", nullptr}, {"skipped", "--no-diagnosis"}};
  }
  j["warnings"] = calibration.warnings;
  if (r.diagnosis) {
    for (const std::string& w : r.diagnosis->warnings) j["warnings"].push_back(w);
  }
  return j;
}

}  // namespace

TrackerIdentifyReport MakeTrackerIdentifyReport(const TrackerIdentifyResult& result) {
  const json j = TrackerIdentifyReportJson(result);
  TrackerIdentifyReport report;
  report.json_text = j.dump(2) + "\n";
  report.html = "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>identify " +
                result.robot +
                "</title><style>body{font-family:sans-serif}td,th{padding:2px 8px;"
                "text-align:right}</style></head><body><h1>Tracker identification: " +
                HtmlEscape(result.file) + "</h1>" + DiagnosisHtml(j["diagnosis"]) +
                "</body></html>\n";
  return report;
}

}  // namespace twin
