#include "bench/report/diagnosis_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>
#include <vector>

#include "bench/report/report_html.h"
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
          {"size_test",
           {{"statistic", c.size_statistic}, {"dof", c.size_dof}, {"p_value", c.size_p_value}}},
          {"detection_limit_mm", std::isfinite(c.detection_limit_m)
                                     ? json(1e3 * c.detection_limit_m)
                                     : json(nullptr)},
          {"blind", std::isinf(c.detection_limit_m)},
          {"visible_size_test",
           {{"statistic", c.visible_size_statistic},
            {"dof", c.visible_size_dof},
            {"p_value", c.visible_size_p_value}}},
          {"max_geometry_correlation", c.max_geometry_correlation},
          {"min_geometry_correlation", c.min_geometry_correlation},
          {"correlated_with", c.correlated_with},
          {"driver", c.driver == TermDriver::kMeasured         ? "measured"
                     : c.driver == TermDriver::kClockLevelling ? "clock_levelling"
                                                               : "clock_unbounded"},
          {"versus_leader_p_value", std::isfinite(c.versus_leader_p_value)
                                        ? json(c.versus_leader_p_value)
                                        : json(nullptr)},
          {"preferred_over", c.preferred_over.empty() ? json(nullptr) : json(c.preferred_over)},
          {"indistinguishable_from", c.indistinguishable_from},
          {"restarted", c.restarted},
          {"accepted", c.accepted},
          {"note", c.note}};
}

// An optional session score's JSON, or null.
json OptionalSession(const std::optional<SessionScore>& s) {
  return s ? SessionScoreJson(*s) : json(nullptr);
}

// One step's entry of steps[]; its second-session keys null without a second session.
json StepJson(const DiscoveryStep& s) {
  return {{"step", s.index},
          {"heldout_rms_before_mm", 1e3 * s.heldout_rms_before_m},
          {"heldout_rms_after_mm", 1e3 * s.heldout_rms_after_m},
          {"candidates", s.candidates.size()},
          {"accepted", s.accepted >= 0 ? json(s.candidates[s.accepted].label) : json(nullptr)},
          {"session_rms_mm", s.session ? json(1e3 * s.session->rms_m) : json(nullptr)},
          {"session_rms_sd_mm", s.session ? json(1e3 * s.session->rms_sd_m) : json(nullptr)},
          {"session_worse", s.session ? json(s.session_worse) : json(nullptr)},
          {"session_worse_halvings",
           s.session ? json(s.session_worse_halvings) : json(nullptr)}};
}

// diagnosis.black_box: the comparator's scores, what it was trained on and its
// hyperparameters; {computed: false, note} where it was not computed.
json BlackBoxJson(const DiscoveryResult& r) {
  const BlackBoxResult& b = r.black_box;
  json j = {{"computed", b.computed},
            {"note", b.note.empty() ? json(nullptr) : json(b.note)},
            {"in_delivered_model", false},
            {"heldout_rms_mm", nullptr},
            {"session_rms_mm", nullptr}};
  if (!b.computed) return j;
  json folds = json::array();
  for (const BlackBoxFold& f : b.folds) {
    folds.push_back({{"fold", f.fold},
                     {"training_points", f.training},
                     {"scored_points", f.scored},
                     {"length_scale", f.length_scale},
                     {"regularisation", f.regularisation}});
  }
  j["model"] = "kernel ridge regression, RBF kernel";
  j["trained_on"] = b.trained_on;
  j["hyperparameter_rule"] = b.hyperparameter_rule;
  j["length_scale"] = Number(b.length_scale);
  j["regularisation"] = Number(b.regularisation);
  j["folds"] = folds;
  j["heldout_rms_mm"] = Number(1e3 * b.heldout_rms_m);
  j["heldout_rms_start_mm"] = Number(1e3 * b.heldout_rms_start_m);
  j["heldout_rms_discovered_mm"] = 1e3 * r.heldout_rms_discovered_m;
  j["session_rms_mm"] = b.session ? json(1e3 * b.session->rms_m) : json(nullptr);
  j["session"] = OptionalSession(b.session);
  return j;
}

}  // namespace

json SessionScoreJson(const SessionScore& s) {
  return {{"rms_mm", 1e3 * s.rms_m},
          {"rms_sd_mm", 1e3 * s.rms_sd_m},
          {"rms_min_mm", 1e3 * s.rms_min_m},
          {"rms_max_mm", 1e3 * s.rms_max_m},
          {"halvings", s.halvings}};
}

json DiagnosisJson(const DiscoveryResult& r) {
  json j;
  j["verdict"] = ToString(r.verdict);
  j["reason"] = r.reason;
  j["data"] = ToString(r.data);
  if (!r.data_note.empty()) j["data_note"] = r.data_note;
  j["noise_floor_mm"] = 1e3 * r.noise.sigma_m;
  const bool optical = r.data == DiscoveryData::kOpticalAxes;
  j["noise_floor"] = {{"sigma_mm", 1e3 * r.noise.sigma_m},
                      {optical ? "perpendicular_sigma_mm" : "tracker_sigma_mm",
                       1e3 * r.noise.tracker_sigma_m},
                      {"joint_sigma_deg", r.noise.joint_sigma_rad * 180.0 / 3.14159265358979323846},
                      {"source", r.noise.source},
                      {"repeated_pose_groups", r.noise.repeated_groups},
                      {"repeated_pose_sigma_mm",
                       r.noise.repeat_sigma_m >= 0 ? json(1e3 * r.noise.repeat_sigma_m)
                                                   : json(nullptr)}};
  if (optical) {
    j["noise_floor"]["depth_sigma_mm"] =
        r.noise.depth_sigma_m >= 0 ? json(1e3 * r.noise.depth_sigma_m) : json(nullptr);
  }
  j["residual_test"] = {{"before", TestJson(r.test_before)}, {"after", TestJson(r.test_after)}};
  j["heldout_rms_mm"] = {{"start", 1e3 * r.heldout_rms_start_m},
                         {"discovered", 1e3 * r.heldout_rms_discovered_m},
                         {"rule", r.region_rule}};
  j["region_rule"] = r.region_rule;
  j["steps"] = json::array();
  j["candidates"] = json::array();
  for (const DiscoveryStep& s : r.steps) {
    j["steps"].push_back(StepJson(s));
    for (const CandidateScore& c : s.candidates) j["candidates"].push_back(CandidateJson(c, s.index));
  }
  j["effects_added"] = json::array();
  for (std::size_t k = 0; k < r.effects_added.size(); ++k) {
    j["effects_added"].push_back(CandidateJson(r.effects_added[k], static_cast<int>(k) + 1));
  }
  j["could_hide"] = r.could_hide;
  j["screened"] = json::array();
  for (const CandidateScore& c : r.screened) j["screened"].push_back(CandidateJson(c, 0));
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
  j["session"] = r.session_start ? json({{"start", SessionScoreJson(*r.session_start)},
                                         {"discovered", OptionalSession(r.session_discovered)}})
                                 : json(nullptr);
  j["black_box"] = BlackBoxJson(r);
  return j;
}

namespace {

std::string Esc(const std::string& t) { return HtmlEscape(t); }

std::string Fmt(const json& v, const char* f = "%.4g") {
  if (!v.is_number()) return v.is_null() ? "-" : Esc(v.dump());
  char buf[48];
  std::snprintf(buf, sizeof buf, f, v.get<double>());
  return buf;
}

// Horizontal bars, one per (label, value), scaled to the largest.
std::string Bars(const std::vector<std::pair<std::string, double>>& bars, const char* unit) {
  double top = 0;
  for (const auto& b : bars) top = std::max(top, b.second);
  if (!(top > 0)) top = 1;
  std::ostringstream os;
  const int h = 22;
  os << "<svg width=\"640\" height=\"" << h * bars.size() + 4 << "\">";
  for (std::size_t k = 0; k < bars.size(); ++k) {
    const double w = 380.0 * bars[k].second / top;
    os << "<text x=\"0\" y=\"" << h * k + 15 << "\" font-size=\"12\">" << Esc(bars[k].first)
       << "</text><rect x=\"200\" y=\"" << h * k + 3 << "\" width=\"" << w << "\" height=\""
       << h - 6 << "\" fill=\"#4a7ab5\"/><text x=\"" << 205 + w << "\" y=\"" << h * k + 15
       << "\" font-size=\"12\">" << Fmt(bars[k].second) << " " << unit << "</text>";
  }
  os << "</svg>";
  return os.str();
}

// A residual map: RMS per bin as a polyline with points.
std::string Map(const json& m) {
  const std::vector<double> x = m["bin_centre"], y = m["rms_mm"];
  double ymax = 0;
  for (double v : y) ymax = std::max(ymax, v);
  if (!(ymax > 0)) ymax = 1;
  const double x0 = x.empty() ? 0 : x.front(), x1 = x.empty() ? 1 : x.back();
  const double span = x1 > x0 ? x1 - x0 : 1;
  std::ostringstream os;
  os << "<figure style=\"display:inline-block;margin:4px\"><svg width=\"200\" height=\"110\">"
     << "<rect x=\"20\" y=\"5\" width=\"175\" height=\"85\" fill=\"none\" stroke=\"#999\"/>"
     << "<polyline fill=\"none\" stroke=\"#b5554a\" points=\"";
  for (std::size_t k = 0; k < x.size(); ++k) {
    os << 20 + 175 * (x[k] - x0) / span << "," << 90 - 85 * y[k] / ymax << " ";
  }
  os << "\"/><text x=\"22\" y=\"104\" font-size=\"10\">" << Fmt(x0, "%.3g") << " .. "
     << Fmt(x1, "%.3g") << " " << Esc(m["unit"].get<std::string>()) << "; max "
     << Fmt(ymax, "%.3g") << " mm</text></svg><figcaption style=\"font-size:11px\">residual RMS vs "
     << Esc(m["quantity"].get<std::string>()) << "</figcaption></figure>";
  return os.str();
}

}  // namespace

std::string DiagnosisHtml(const json& d) {
  std::ostringstream os;
  os << "<h2>Model discovery</h2>";
  if (!d.contains("verdict") || d["verdict"].is_null()) {
    os << "<p>Skipped (" << Esc(d.value("skipped", std::string("not run"))) << ").</p>";
    return os.str();
  }
  os << "<p><b>" << Esc(d["verdict"].get<std::string>()) << "</b>: "
     << Esc(d["reason"].get<std::string>()) << "</p>";
  const json& nf = d["noise_floor"];
  os << "<p>Noise floor " << Fmt(nf["sigma_mm"]) << " mm per coordinate (" << Esc(nf["source"])
     << "). Residual test of the starting model (" << Esc(d["residual_test"]["before"]["held_out"])
     << "): RMS "
     << Fmt(d["residual_test"]["before"]["rms_mm"]) << " mm, p = "
     << Fmt(d["residual_test"]["before"]["p_value"]) << "; of the discovered model: "
     << Fmt(d["residual_test"]["after"]["rms_mm"]) << " mm, p = "
     << Fmt(d["residual_test"]["after"]["p_value"]) << ".</p>";
  std::vector<std::pair<std::string, double>> bars{
      {"geometric model", d["heldout_rms_mm"]["start"].get<double>()}};
  for (const json& s : d["steps"]) {
    if (!s["accepted"].is_null()) {
      bars.push_back({"+ " + s["accepted"].get<std::string>(), s["heldout_rms_after_mm"]});
    }
  }
  const json& box = d.contains("black_box") ? d["black_box"] : json(nullptr);
  const bool boxed = box.is_object() && box["heldout_rms_mm"].is_number();
  if (boxed) bars.push_back({"black box (comparator)", box["heldout_rms_mm"].get<double>()});
  os << "<h3>Region-disjoint held-out RMS</h3><p>" << Esc(d["region_rule"]) << "</p>"
     << Bars(bars, "mm");
  if (d.contains("session") && d["session"].is_object()) {
    // The second session: the same models, the tracker pose refitted on half its poses.
    std::vector<std::pair<std::string, double>> session{
        {"geometric model", d["session"]["start"]["rms_mm"].get<double>()}};
    for (const json& s : d["steps"]) {
      if (!s["accepted"].is_null() && s["session_rms_mm"].is_number()) {
        session.push_back({"+ " + s["accepted"].get<std::string>() +
                               (s["session_worse"] == true ? " (WORSE)" : ""),
                           s["session_rms_mm"].get<double>()});
      }
    }
    if (boxed && box["session_rms_mm"].is_number()) {
      session.push_back({"black box (comparator)", box["session_rms_mm"].get<double>()});
    }
    os << "<h3>Second session (mean over halvings)</h3>" << Bars(session, "mm");
  }
  os << "<h3>Decision chain</h3><table><tr><th>step</th><th>candidate</th><th>tested</th>"
        "<th>held-out gain [%]</th><th>p</th><th>Holm p</th><th>size p (Wald)</th>"
        "<th>|rho| geometry (least, most)</th><th>accepted</th><th>note</th></tr>";
  for (const json& c : d["candidates"]) {
    os << "<tr><td>" << c["step"] << "</td><td>" << Esc(c["label"]) << "</td><td>"
       << (c["tested"].get<bool>() ? "yes" : "no") << "</td><td>"
       << Fmt(c["heldout_gain_percent"], "%.1f") << "</td><td>" << Fmt(c["p_value"], "%.2g")
       << "</td><td>" << Fmt(c["p_adjusted"], "%.2g") << "</td><td>"
       << Fmt(c["size_test"]["p_value"], "%.2g") << "</td><td>"
       << Fmt(c["min_geometry_correlation"], "%.3f") << ", "
       << Fmt(c["max_geometry_correlation"], "%.3f") << "</td><td>"
       << (c["accepted"].get<bool>() ? "<b>yes</b>" : "") << "</td><td style=\"text-align:left\">"
       << Esc(c["note"]) << "</td></tr>";
  }
  os << "</table>";
  if (d.contains("screened") && d["screened"].is_array() && !d["screened"].empty()) {
    os << "<h3>Candidates screened (the residual is consistent with the noise: fitted on all the "
          "data, none tested or added)</h3><table><tr><th>candidate</th><th>applicable</th>"
          "<th>identifiable</th><th>parameters (estimate &plusmn; 1 sigma)</th>"
          "<th>|rho| geometry (least, most)</th><th>note</th></tr>";
    for (const json& c : d["screened"]) {
      std::string params;
      for (const json& p : c["parameters"]) {
        params += (params.empty() ? "" : "; ") + Esc(p["name"].get<std::string>()) + " " +
                  Fmt(p["estimated"], "%.3g") + " &plusmn; " + Fmt(p["sigma"], "%.2g") + " " +
                  Esc(p["unit"].get<std::string>());
      }
      os << "<tr><td>" << Esc(c["label"]) << "</td><td>"
         << (c["applicable"].get<bool>() ? "yes" : "no") << "</td><td>"
         << (c["identifiable"].get<bool>() ? "yes" : "<b>no</b>") << "</td><td>" << params
         << "</td><td>" << Fmt(c["min_geometry_correlation"], "%.5f") << ", "
         << Fmt(c["max_geometry_correlation"], "%.5f")
         << "</td><td style=\"text-align:left\">" << Esc(c["note"]) << "</td></tr>";
    }
    os << "</table>";
  }
  os << "<h3>Strongest residual correlations</h3><table><tr><th>quantity</th>"
        "<th>component</th><th>r</th></tr>";
  for (const json& e : d["unexplained_evidence"]) {
    os << "<tr><td>" << Esc(e["quantity"]) << "</td><td>" << Esc(e["component"]) << "</td><td>"
       << Fmt(e["r"], "%.3f") << "</td></tr>";
  }
  os << "</table><h3>Residual maps (held out, region-disjoint, final model)</h3><div>";
  for (const json& m : d["residual_maps"]) os << Map(m);
  os << "</div>";
  return os.str();
}

std::string DiagnosisSummary(const DiscoveryResult& r) { return r.BriefReport(); }

}  // namespace twin
