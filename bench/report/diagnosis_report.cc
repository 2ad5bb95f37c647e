#include "bench/report/diagnosis_report.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "bench/report/report_units.h"

namespace twin {
namespace {
using nlohmann::json;

json Number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json TestJson(const ResidualTest& t) {
  return {{"held_out", t.held_out},
          {"points", t.points},
          {"rms_mm", 1e3 * t.rms_m},
          {"statistic", Number(t.statistic)},
          {"dof", t.dof},
          {"inflation", t.inflation},
          {"p_value", t.p_value},
          {"result", t.systematic ? "systematic" : "consistent_with_noise"}};
}

json CandidateJson(const CandidateScore& c, int step) {
  json parameters = json::array();
  json sigma = json::array();
  for (const DiscoveredParameter& p : c.parameters) {
    parameters.push_back({{"name", p.name},
                          {"unit", ReportUnit(p.unit)},
                          {"estimated", ReportValue(p.estimated, p.unit)},
                          {"sigma", ReportValue(p.sigma, p.unit)}});
    sigma.push_back(ReportValue(p.sigma, p.unit));
  }
  json orders = json::array();
  for (int h : c.spec.orders) orders.push_back(h);
  return {{"step", step},
          {"term", c.spec.type},
          {"joint", c.spec.joint >= 0 ? json(c.spec.joint + 1) : json(nullptr)},
          {"orders", orders},
          {"label", c.label},
          {"applicable", c.applicable},
          {"identifiable", c.identifiable},
          {"tested", c.tested},
          {"parameters", parameters},
          {"sigma", sigma},
          {"heldout_rms_mm", c.tested ? json(1e3 * c.heldout_rms_m) : json(nullptr)},
          {"heldout_gain_percent", c.tested ? json(c.gain_percent) : json(nullptr)},
          {"p_value", c.tested ? json(c.p_value) : json(nullptr)},
          {"p_adjusted", c.tested ? json(c.p_adjusted) : json(nullptr)},
          {"max_geometry_correlation", c.max_geometry_correlation},
          {"correlated_with", c.correlated_with},
          {"accepted", c.accepted},
          {"note", c.note}};
}

std::string Mm(double m) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4f mm", 1e3 * m);
  return buf;
}

}  // namespace

json DiagnosisJson(const DiscoveryResult& r) {
  json j;
  j["verdict"] = r.verdict;
  j["reason"] = r.reason;
  j["noise_floor_mm"] = 1e3 * r.noise.sigma_m;
  j["noise_floor"] = {{"sigma_mm", 1e3 * r.noise.sigma_m},
                      {"tracker_sigma_mm", 1e3 * r.noise.tracker_sigma_m},
                      {"joint_sigma_deg", r.noise.joint_sigma_rad * 180.0 / 3.14159265358979323846},
                      {"source", r.noise.source},
                      {"repeated_pose_groups", r.noise.repeated_groups},
                      {"repeated_pose_sigma_mm",
                       r.noise.repeat_sigma_m >= 0 ? json(1e3 * r.noise.repeat_sigma_m)
                                                   : json(nullptr)}};
  j["residual_test"] = {{"before", TestJson(r.test_before)}, {"after", TestJson(r.test_after)}};
  j["heldout_rms_mm"] = {{"start", 1e3 * r.heldout_rms_start_m},
                         {"discovered", 1e3 * r.heldout_rms_discovered_m},
                         {"rule", r.region_rule}};
  j["region_rule"] = r.region_rule;
  j["steps"] = json::array();
  j["candidates"] = json::array();
  for (const DiscoveryStep& s : r.steps) {
    j["steps"].push_back(
        {{"step", s.index},
         {"heldout_rms_before_mm", 1e3 * s.heldout_rms_before_m},
         {"heldout_rms_after_mm", 1e3 * s.heldout_rms_after_m},
         {"candidates", s.candidates.size()},
         {"accepted", s.accepted >= 0 ? json(s.candidates[s.accepted].label) : json(nullptr)}});
    for (const CandidateScore& c : s.candidates) j["candidates"].push_back(CandidateJson(c, s.index));
  }
  j["effects_added"] = json::array();
  for (std::size_t k = 0; k < r.effects_added.size(); ++k) {
    j["effects_added"].push_back(CandidateJson(r.effects_added[k], static_cast<int>(k) + 1));
  }
  j["unexplained_evidence"] = json::array();
  for (const ResidualCorrelation& e : r.evidence) {
    j["unexplained_evidence"].push_back(
        {{"quantity", e.quantity}, {"component", e.component}, {"r", e.r}});
  }
  j["residual_maps"] = json::array();
  for (const ResidualMap& m : r.maps) {
    json rms = json::array();
    for (double v : m.rms_m) rms.push_back(1e3 * v);
    j["residual_maps"].push_back({{"quantity", m.quantity},
                                  {"unit", m.unit},
                                  {"bin_centre", m.bin_centre},
                                  {"rms_mm", rms},
                                  {"count", m.count}});
  }
  return j;
}

std::string DiagnosisSummary(const DiscoveryResult& r) {
  std::ostringstream os;
  os << "diagnosis: " << r.verdict << ": " << r.reason << "\n";
  os << "  noise floor " << Mm(r.noise.sigma_m) << " per axis (" << r.noise.source << ")";
  if (r.noise.repeat_sigma_m >= 0) {
    os << "; repeated poses (" << r.noise.repeated_groups << " groups) spread "
       << Mm(r.noise.repeat_sigma_m);
  }
  os << "\n  residual test: held-out RMS " << Mm(r.test_before.rms_m) << ", p = "
     << r.test_before.p_value << " (" << (r.test_before.systematic ? "systematic" : "noise")
     << ")\n";
  for (const DiscoveryStep& s : r.steps) {
    int tested = 0;
    for (const CandidateScore& c : s.candidates) tested += c.tested ? 1 : 0;
    os << "  step " << s.index << ": " << tested << " of " << s.candidates.size()
       << " candidates tested; ";
    const CandidateScore* best = nullptr;
    for (const CandidateScore& c : s.candidates) {
      if (c.tested && (!best || c.gain_percent > best->gain_percent)) best = &c;
    }
    if (best) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "best %s, held-out gain %.1f %%, Holm p = %.3g: %s",
                    best->label.c_str(), best->gain_percent, best->p_adjusted,
                    best->accepted ? "ACCEPTED" : "rejected");
      os << buf;
    } else {
      os << "none testable";
    }
    os << "; region held-out RMS " << Mm(s.heldout_rms_before_m) << " -> "
       << Mm(s.heldout_rms_after_m) << "\n";
  }
  if (r.verdict == "unexplained" && !r.evidence.empty()) {
    os << "  strongest residual correlations:";
    for (std::size_t k = 0; k < r.evidence.size() && k < 4; ++k) {
      char buf[64];
      std::snprintf(buf, sizeof buf, " %s/%s r = %.2f", r.evidence[k].quantity.c_str(),
                    r.evidence[k].component.c_str(), r.evidence[k].r);
      os << (k ? "," : "") << buf;
    }
    os << "\n";
  }
  return os.str();
}

}  // namespace twin
