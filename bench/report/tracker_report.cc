#include "bench/report/tracker_report.h"

#include <cmath>
#include <sstream>

#include <nlohmann/json.hpp>

#include "bench/report/acceptance.h"
#include "bench/report/diagnosis_report.h"
#include "bench/report/report_units.h"
#include "bench/report/scenario_json.h"

namespace twin {
namespace {

using json = nlohmann::json;

json Stats(const PositionErrorStats& s) { return {{"rms", 1e3 * s.rms}, {"max", 1e3 * s.max}}; }

json RawAndRigid(const GaugeErrors& e) {
  return {{"raw", Stats(e.raw)}, {"rigid", Stats(e.rigid)}};
}

// The tracker's points: poses, attempts, its noise, the temperature reference and the skips.
json TrackerJson(const TrackerRunResult& r) {
  const TrackerProcedureResult& result = *r.procedure;
  json t = {{"poses", result.points.size()}, {"attempts", result.attempts},
            {"sigma_mm", std::isfinite(r.tracker_sigma_m) ? json(1e3 * r.tracker_sigma_m)
                                                          : json(nullptr)}};
  // The robot's temperature sensor (the points carry their change from this first reading).
  t["temperature_reference_C"] = std::isfinite(result.temperature_reference_C)
                                     ? json(result.temperature_reference_C)
                                     : json(nullptr);
  t["skipped"] = json::array();
  for (const TrackerSkip& s : result.skipped) {
    t["skipped"].push_back({{"attempt", s.attempt}, {"reason", s.reason}});
  }
  return t;
}

// The report's head: the scenario, the procedure, the tracker's points and skips, the
// held-out splits and the truth position errors.
json ReportHead(const TrackerRunResult& r) {
  json j;
  j["scenario"] = ScenarioJson(*r.scenario);
  j["procedure"] = "laser-tracker calibration (geometry, tracker pose, reflector offset)";
  j["robot"] = r.robot;
  j["tracker"] = TrackerJson(r);
  for (const HeldOutSplit& s : r.procedure->calibration.splits) {
    j["heldout"][s.name] = {{"rule", s.rule}, {"training_poses", s.training},
                            {"before", PointErrorsJson(s.before)},
                            {"after", PointErrorsJson(s.after)}, {"worse", s.worse}};
  }
  if (!r.truth_available) {
    j["truth"] = TruthUnavailableJson("nothing is scored against it");
    return j;
  }
  const GaugeErrors& before = r.truth.before;
  const GaugeErrors& after = r.truth.after;
  j["truth_position_error_mm"] = {
      {"raw", {{"before", Stats(before.raw)}, {"after", Stats(after.raw)}}},
      {"rigid", {{"before", Stats(before.rigid)}, {"after", Stats(after.rigid)}}}};
  return j;
}

// The geometric parameters against their true values and the declared terms' parameters as
// identified (no truth beside them: a term's parameters are the estimator's, the twin's effect
// need not have the same ones).
void AddParameters(const TrackerRunResult& r, json* report) {
  json& j = *report;
  const IdentificationResult& id = r.procedure->calibration.identified;
  const Eigen::VectorXd& phi0 = r.truth.phi0;
  const Eigen::VectorXd& phi_true = r.truth.phi_true;
  j["parameters"] = json::array();
  for (int i = 0; i < phi0.size(); ++i) {
    const IdentifiedParameter& p = id.parameters[i];
    j["parameters"].push_back({{"name", p.name},
                               {"unit", ReportUnit(p.unit)},
                               {"estimated", ReportValue(p.estimated - phi0(i), p.unit)},
                               {"true", phi_true.size() == phi0.size()
                                            ? json(ReportValue(phi_true(i) - phi0(i), p.unit))
                                            : json(nullptr)},
                               {"sigma", ReportValue(p.sigma, p.unit)}});
  }
  j["declared_term_parameters"] = json::array();
  for (std::size_t i = phi0.size(); i < id.parameters.size(); ++i) {
    const IdentifiedParameter& p = id.parameters[i];
    j["declared_term_parameters"].push_back({{"name", p.name},
                                             {"unit", ReportUnit(p.unit)},
                                             {"estimated", ReportValue(p.estimated, p.unit)},
                                             {"sigma", ReportValue(p.sigma, p.unit)}});
  }
}

// The identifiable combinations against their true values and the identification's figures.
void AddIdentification(const TrackerRunResult& r, json* report) {
  json& j = *report;
  const IdentificationResult& id = r.procedure->calibration.identified;
  json items = json::array();
  for (const TrackerCombinationScore& c : r.truth.combinations) {
    items.push_back({{"index", c.index}, {"estimated", c.estimated}, {"true", c.true_value},
                     {"sigma", c.sigma}, {"within_3_sigma", c.within_3_sigma}});
  }
  j["identifiable_combinations"] = {
      {"count", id.z.size()},
      {"within_3_sigma", r.truth_available ? json(r.truth.within3) : json(nullptr)},
      {"items", items}};
  j["unidentifiable"] = id.observability.unidentifiable;
  j["condition_number"] = id.condition_number();
  j["sigma0"] = id.sigma0;
  j["declared_terms"] = r.declared_terms;
}

// The physical truth's errors of the calibrated (and the discovered) model, when the twin
// reached some of its poses.
void AddPhysicalTruth(const TrackerRunResult& r, json* report) {
  json& j = *report;
  const TrackerPhysicalTruthScores& physical = r.physical;
  if (physical.poses == 0) return;
  j["truth_position_error_mm_physical"] = {
      {"poses", physical.poses},
      {"rule", "the reflector where the twin's physics puts it (every effect) at seeded random "
               "poses, against each model at the same readings"},
      {"calibrated_model", RawAndRigid(physical.calibrated)}};
  if (physical.discovered) {
    j["truth_position_error_mm_physical"]["discovered_model"] = RawAndRigid(*physical.discovered);
    j["truth_position_error_mm_discovered_model"] = RawAndRigid(*physical.discovered);
  }
}

// The whole report.json (before the acceptance verdict).
json TrackerReportJson(const TrackerRunResult& r) {
  json j = ReportHead(r);
  AddParameters(r, &j);
  AddIdentification(r, &j);
  AddPhysicalTruth(r, &j);
  if (r.diagnosis) {
    j["diagnosis"] = DiagnosisJson(*r.diagnosis);
  } else {
    j["diagnosis"] = {{"verdict", nullptr}, {"skipped", r.diagnosis_skipped}};
  }
  j["warnings"] = r.procedure->calibration.warnings;
  for (const std::string& n : r.notes) j["warnings"].push_back(n);
  j["timing_s"] = {{"total", r.total_s}};
  return j;
}

// report.html: the truth errors, the held-out points, the parameters, the unidentifiable
// directions and the diagnosis.
std::string Html(const json& j) {
  std::ostringstream os;
  os << "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>tracker calibration "
     << j["scenario"]["name"].get<std::string>() << "</title><style>body{font-family:sans-serif}"
     << "td,th{padding:2px 8px;text-align:right}</style></head><body><h1>Laser-tracker "
        "calibration: "
     << j["scenario"]["name"].get<std::string>() << "</h1>";
  os << "<h2>Truth position error (200 random configurations) [mm]</h2><table><tr><th>gauge"
        "</th><th>before RMS</th><th>after RMS</th><th>after max</th></tr>";
  for (const char* g : {"raw", "rigid"}) {
    if (!j.contains("truth_position_error_mm")) {
      os << "<tr><td colspan=\"4\">" << j["truth"]["reason"].get<std::string>() << "</td></tr>";
      break;
    }
    const json& t = j["truth_position_error_mm"][g];
    os << "<tr><td>" << g << "</td><td>" << t["before"]["rms"] << "</td><td>" << t["after"]["rms"]
       << "</td><td>" << t["after"]["max"] << "</td></tr>";
  }
  os << "</table><h2>Held-out points [mm]</h2><table><tr><th>split</th><th>poses</th><th>"
        "before RMS</th><th>after RMS</th><th>after max</th><th></th></tr>";
  for (const auto& [name, s] : j["heldout"].items()) {
    os << "<tr><td>" << name << "</td><td>" << s["after"]["poses"] << "</td><td>"
       << s["before"]["rms_mm"] << "</td><td>" << s["after"]["rms_mm"] << "</td><td>"
       << s["after"]["max_mm"] << "</td><td>" << (s["worse"].get<bool>() ? "WORSE" : "")
       << "</td></tr>";
  }
  os << "</table><h2>Parameters (deviation from nominal)</h2><table><tr><th>name</th><th>unit"
        "</th><th>estimated</th><th>true</th><th>sigma</th></tr>";
  for (const json& p : j["parameters"]) {
    os << "<tr><td>" << p["name"].get<std::string>() << "</td><td>" << p["unit"].get<std::string>()
       << "</td><td>" << p["estimated"] << "</td><td>" << p["true"] << "</td><td>" << p["sigma"]
       << "</td></tr>";
  }
  os << "</table><h2>Unidentifiable</h2><ul>";
  for (const json& u : j["unidentifiable"]) os << "<li>" << u.get<std::string>() << "</li>";
  os << "</ul>";
  if (j.contains("diagnosis")) os << DiagnosisHtml(j["diagnosis"]);
  os << "</body></html>\n";
  return os.str();
}

}  // namespace

TrackerReport MakeTrackerReport(const TrackerRunResult& result, const Acceptance& acceptance) {
  json j = TrackerReportJson(result);
  TrackerReport report;
  report.verdict = EvaluateAcceptance(acceptance, &j);
  report.json_text = j.dump(2) + "\n";
  report.html = Html(j);
  return report;
}

}  // namespace twin
