#include "bench/report/study_summary_html.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include "bench/report/report_html.h"

namespace twin {
namespace {

using json = nlohmann::json;

std::string F(double v) {  // an SVG coordinate
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", std::isfinite(v) ? v : 0.0);
  return buf;
}

std::string N(const json& j) {
  return j.is_number() ? FormatReportNumber(j.get<double>()) : std::string("n/a");
}

// A fraction as a percentage (null stays null).
json Scaled(const json& fraction) {
  return fraction.is_number() ? json(100.0 * fraction.get<double>()) : json(nullptr);
}

// Headline figures, by the end of their key (every key of the records that ends so is shown).
const char* const kHeadlines[] = {
    "truth_position_error_mm.rigid.after.rms",
    "truth_position_error_mm.similarity.after.rms",
    "truth_position_error_mm.raw.after.rms",
    "truth_position_error_mm_covered_region.rigid.after.rms",
    "truth_position_error_mm_covered_region.similarity.after.rms",
    "misaligned_error_mm.validation.after",
    "misaligned_error_mm.calibration.after",
    "identifiable_combinations.rms_error",
    "servo.mean_frames_per_pose",
    "intrinsics.error_px.fx",
    "intrinsics.error_px.cx",
    "base_frame.general.e_tran_mm",
    "base_frame.general.e_rot_deg",
    "base_frame.constrained.e_tran_mm",
    "base_frame.constrained.e_rot_deg",
    "base_frame.workflow.calibrated_kinematics.e_tran_mm",
    "base_frame.workflow.calibrated_kinematics.e_rot_deg",
};

bool EndsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

std::vector<double> Values(const std::vector<json>& records, const std::string& key) {
  std::vector<double> v;
  for (const json& r : records) {
    if (r.value("status", std::string()) != "ok") continue;
    const auto f = r.find("figures");
    if (f == r.end() || !f->is_object()) continue;
    const auto it = f->find(key);
    if (it != f->end() && it->is_number() && std::isfinite(it->get<double>())) {
      v.push_back(it->get<double>());
    }
  }
  std::sort(v.begin(), v.end());
  return v;
}

// Histogram (left) and empirical CDF (right) of sorted values, with the mean and the p5 /
// median / p95 marked.
std::string DistributionPlot(const std::vector<double>& v, const json& stats) {
  const double W = 560, H = 180, L = 50, R = 10, T = 10, B = 30, gap = 40;
  const double pw = (W - L - R - gap) / 2, ph = H - T - B;
  double lo = v.front(), hi = v.back();
  if (!(hi > lo)) {
    lo -= 0.5 * (std::abs(lo) + 1e-12);
    hi += 0.5 * (std::abs(hi) + 1e-12);
  }
  const int bins = std::clamp(static_cast<int>(std::ceil(std::sqrt(v.size()))), 5, 30);
  std::vector<int> count(bins, 0);
  for (double x : v) {
    count[std::min(bins - 1, static_cast<int>((x - lo) / (hi - lo) * bins))]++;
  }
  const int cmax = *std::max_element(count.begin(), count.end());
  auto X = [&](double x, double x0) { return x0 + (x - lo) / (hi - lo) * pw; };
  std::ostringstream o;
  o << "<svg class=\"plot\" width=\"" << W << "\" height=\"" << H << "\">\n";
  for (int panel = 0; panel < 2; ++panel) {
    const double x0 = L + panel * (pw + gap);
    o << "<line class=\"axis\" x1=\"" << F(x0) << "\" x2=\"" << F(x0 + pw) << "\" y1=\""
      << F(T + ph) << "\" y2=\"" << F(T + ph) << "\"/><line class=\"axis\" x1=\"" << F(x0)
      << "\" x2=\"" << F(x0) << "\" y1=\"" << F(T) << "\" y2=\"" << F(T + ph) << "\"/>\n";
    for (double t : {lo, 0.5 * (lo + hi), hi}) {
      o << "<text class=\"tick\" x=\"" << F(X(t, x0)) << "\" y=\"" << F(T + ph + 14)
        << "\" text-anchor=\"middle\">" << FormatReportNumber(t) << "</text>\n";
    }
    o << "<text class=\"tick\" x=\"" << F(x0 - 4) << "\" y=\"" << F(T + 8)
      << "\" text-anchor=\"end\">" << (panel == 0 ? std::to_string(cmax) : "1") << "</text>"
      << "<text class=\"tick\" x=\"" << F(x0 - 4) << "\" y=\"" << F(T + ph)
      << "\" text-anchor=\"end\">0</text>\n";
    o << "<text class=\"label\" x=\"" << F(x0 + pw / 2) << "\" y=\"" << F(H - 2)
      << "\" text-anchor=\"middle\">" << (panel == 0 ? "histogram (trials)" : "ECDF")
      << "</text>\n";
    if (panel == 0) {
      for (int b = 0; b < bins; ++b) {
        const double bh = cmax > 0 ? ph * count[b] / cmax : 0;
        o << "<rect x=\"" << F(x0 + b * pw / bins + 0.5) << "\" y=\"" << F(T + ph - bh)
          << "\" width=\"" << F(pw / bins - 1) << "\" height=\"" << F(bh)
          << "\" fill=\"#1f77b4\"/>\n";
      }
    } else {
      o << "<polyline fill=\"none\" stroke=\"#1f77b4\" stroke-width=\"1.5\" points=\"";
      for (std::size_t i = 0; i < v.size(); ++i) {
        const double y0 = T + ph - ph * i / v.size(), y1 = T + ph - ph * (i + 1) / v.size();
        o << F(X(v[i], x0)) << "," << F(y0) << " " << F(X(v[i], x0)) << "," << F(y1) << " ";
      }
      o << "\"/>\n";
    }
    auto mark = [&](const char* key, const char* colour) {
      const auto it = stats.find(key);
      if (it == stats.end() || !it->is_number()) return;
      const double x = X(it->get<double>(), x0);
      o << "<line x1=\"" << F(x) << "\" x2=\"" << F(x) << "\" y1=\"" << F(T) << "\" y2=\""
        << F(T + ph) << "\" stroke=\"" << colour << "\" stroke-dasharray=\"4 3\"/>\n";
    };
    mark("p5", "#999");
    mark("median", "#2ca02c");
    mark("p95", "#999");
    mark("mean", "#d62728");
  }
  o << "</svg>\n";
  return o.str();
}

// One robot's per-parameter errors: a horizontal bar from p5 to p95 and the median, per unit.
std::string ParameterErrorPlot(json params, const std::string& unit) {
  std::vector<std::pair<std::string, json*>> rows;
  double lo = 0, hi = 0;
  for (auto& [name, s] : params.items()) {
    if (!s.is_object() || s["unit"] != unit || !s["p5"].is_number() || !s["p95"].is_number()) {
      continue;
    }
    rows.emplace_back(name, &s);
    lo = std::min(lo, s["p5"].get<double>());
    hi = std::max(hi, s["p95"].get<double>());
  }
  if (rows.empty()) return "";
  if (!(hi > lo)) hi = lo + 1;
  const double L = 170, W = 560, rowh = 14, T = 10;
  const double H = T + rowh * rows.size() + 24, pw = W - L - 10;
  auto X = [&](double x) { return L + (x - lo) / (hi - lo) * pw; };
  std::ostringstream o;
  o << "<svg class=\"plot\" width=\"" << W << "\" height=\"" << F(H) << "\">\n";
  o << "<line class=\"axis\" x1=\"" << F(X(0)) << "\" x2=\"" << F(X(0)) << "\" y1=\"" << F(T)
    << "\" y2=\"" << F(H - 22) << "\"/>\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    json& s = *rows[i].second;
    const double y = T + rowh * i + rowh / 2;
    o << "<text class=\"tick\" x=\"" << F(L - 6) << "\" y=\"" << F(y + 4)
      << "\" text-anchor=\"end\">" << HtmlEscape(rows[i].first) << "</text>"
      << "<line x1=\"" << F(X(s["p5"].get<double>())) << "\" x2=\""
      << F(X(s["p95"].get<double>())) << "\" y1=\"" << F(y) << "\" y2=\"" << F(y)
      << "\" stroke=\"#1f77b4\" stroke-width=\"5\"/>";
    if (s["median"].is_number()) {
      o << "<circle cx=\"" << F(X(s["median"].get<double>())) << "\" cy=\"" << F(y)
        << "\" r=\"3\" fill=\"#d62728\"/>";
    }
    o << "\n";
  }
  for (double t : {lo, 0.0, hi}) {
    o << "<text class=\"tick\" x=\"" << F(X(t)) << "\" y=\"" << F(H - 8)
      << "\" text-anchor=\"middle\">" << FormatReportNumber(t) << "</text>\n";
  }
  o << "</svg>\n";
  return o.str();
}

const char kStyle[] = R"(
body{font-family:system-ui,-apple-system,"Segoe UI",Helvetica,Arial,sans-serif;margin:24px auto;
max-width:1200px;padding:0 16px;color:#222;background:#fafafa}
h2{border-bottom:2px solid #ccc;padding-bottom:4px;margin-top:32px}
section{background:#fff;border:1px solid #ddd;border-radius:6px;padding:8px 18px 16px;margin:18px 0}
table{border-collapse:collapse;margin:6px 0;font-size:13px}
th,td{border:1px solid #ccc;padding:3px 8px;text-align:right}
th{background:#eef2f7}td:first-child{text-align:left;font-family:monospace}
.note{color:#555;max-width:900px}
svg.plot{display:block;margin:8px 0;background:#fff}
svg .axis{stroke:#444;stroke-width:1}svg .tick{font-size:11px;fill:#333}
svg .label{font-size:12px;fill:#111}
)";

}  // namespace

std::string RenderStudySummaryHtml(const json& summary_in, const std::vector<json>& records) {
  // A mutable copy: operator[] on it yields null for a missing key (no throw, no assert).
  json summary = summary_in.is_object() ? summary_in : json::object();
  std::ostringstream o;
  json& trials = summary["trials"];
  if (!trials.is_object()) trials = json::object();
  std::string name;
  if (summary["scenario"].is_object() && summary["scenario"]["names"].is_array()) {
    for (const json& n : summary["scenario"]["names"]) {
      if (n.is_string()) name += (name.empty() ? "" : ", ") + n.get<std::string>();
    }
  }
  o << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>study "
    << HtmlEscape(name) << "</title><style>" << kStyle << "</style></head><body>\n";
  o << "<h1>Monte Carlo study: " << HtmlEscape(name) << "</h1>\n<p class=\"note\">";
  if (summary["scenario"].is_object() && summary["scenario"]["hashes"].is_array()) {
    o << "scenario hash";
    for (const json& h : summary["scenario"]["hashes"]) {
      if (h.is_string()) o << " <code>" << HtmlEscape(h.get<std::string>()) << "</code>";
    }
    o << "; ";
  }
  o << N(trials["recorded"]) << " trials recorded (" << N(trials["first"]) << " .. "
    << N(trials["last"]) << "): " << N(trials["ok"]) << " ok, " << N(trials["failed"])
    << " failed. Statistics over the ok trials; "
    << "red dashed line the mean, green the median, grey p5 and p95.</p>\n";
  if (trials["failures"].is_array() && !trials["failures"].empty()) {
    o << "<section><h2>Failed trials</h2><table><tr><th>trial</th><th>reason</th></tr>\n";
    for (json& f : trials["failures"]) {
      o << "<tr><td>" << N(f["trial"]) << "</td><td style=\"text-align:left\">"
        << HtmlEscape(f["reason"].is_string() ? f["reason"].get<std::string>() : "")
        << "</td></tr>\n";
    }
    o << "</table></section>\n";
  }

  json& figures = summary["figures"];
  if (!figures.is_object()) figures = json::object();
  o << "<section><h2>Distributions of the headline figures</h2>\n";
  for (const char* tail : kHeadlines) {
    for (auto& [key, stats] : figures.items()) {
      if (!EndsWith(key, tail) || !stats.is_object()) continue;
      const std::vector<double> v = Values(records, key);
      if (v.empty()) continue;
      o << "<h3><code>" << HtmlEscape(key) << "</code></h3><p class=\"note\">mean "
        << N(stats["mean"]) << " (95 % CI " << N(stats["ci95_mean"][0]) << " .. "
        << N(stats["ci95_mean"][1]) << "), median " << N(stats["median"]) << ", p5 "
        << N(stats["p5"]) << ", p95 " << N(stats["p95"]) << ", n " << N(stats["n"]) << "</p>\n"
        << DistributionPlot(v, stats);
    }
  }
  o << "</section>\n";

  json& coverage = summary["coverage"];
  if (coverage.is_object() && !coverage.empty()) {
    o << "<section><h2>Coverage check of the reported uncertainty</h2>\n<p class=\"note\">For "
         "each identifiable combination (the coordinates the identification estimates; "
         "unidentifiable ones have no uncertainty to check) the fraction of trials in which "
         "the truth lies within the reported 1 sigma and 2 sigma of the estimate. If the "
         "reported uncertainty is honest these are about 68.3 % and 95.4 %; clearly lower "
         "means the identification claims more accuracy than it has (the reported sigma is "
         "too small, or the estimate is biased), clearly higher means it is too cautious. The "
         "RMS normalized error |estimated - true| / sigma is about 1 when honest. With n "
         "trials a fraction scatters by about sqrt(p (1 - p) / n); the pooled interval assumes "
         "independent combinations.</p>\n";
    for (auto& [robot, c] : coverage.items()) {
      if (!c.is_object()) continue;
      json& p = c["pooled"];
      if (!p.is_object()) p = json::object();
      o << "<h3>" << HtmlEscape(robot) << "</h3><p>pooled over " << N(p["n"])
        << " (trial, combination) pairs: within 1 sigma " << N(Scaled(p["within_1_sigma"]))
        << " % (95 % interval "
        << N(p["within_1_sigma_interval95"][0]) << " .. " << N(p["within_1_sigma_interval95"][1])
        << "), within 2 sigma " << N(Scaled(p["within_2_sigma"])) << " % ("
        << N(p["within_2_sigma_interval95"][0]) << " .. " << N(p["within_2_sigma_interval95"][1])
        << "), RMS normalized error " << N(p["rms_normalized_error"]) << "</p>\n";
      o << "<table><tr><th>combination</th><th>trials</th><th>within 1 sigma</th><th>within 2 "
           "sigma</th><th>RMS |e| / sigma</th></tr>\n";
      if (!c["combinations"].is_array()) c["combinations"] = json::array();
      for (json& item : c["combinations"]) {
        o << "<tr><td>" << N(item["index"]) << "</td><td>" << N(item["n"]) << "</td><td>"
          << N(Scaled(item["within_1_sigma"])) << " %</td><td>"
          << N(Scaled(item["within_2_sigma"])) << " %</td><td>"
          << N(item["rms_normalized_error"]) << "</td></tr>\n";
      }
      o << "</table>\n";
    }
    o << "</section>\n";
  }

  json& pe = summary["parameter_errors"];
  if (pe.is_object() && !pe.empty()) {
    o << "<section><h2>Per-parameter error distributions</h2>\n<p class=\"note\">Estimated "
         "minus true deviation from nominal of each named parameter: bar p5 .. p95, dot the "
         "median. Parameters in unidentifiable combinations (kept at nominal) show the "
         "truth's own spread.</p>\n";
    for (auto& [robot, params] : pe.items()) {
      if (!params.is_object()) continue;
      for (const char* unit : {"mm", "deg"}) {
        const std::string plot = ParameterErrorPlot(params, unit);
        if (plot.empty()) continue;
        o << "<h3>" << HtmlEscape(robot) << " [" << unit << "]</h3>\n" << plot;
      }
      o << "<table><tr><th>parameter</th><th>unit</th><th>n</th><th>mean</th><th>std</th>"
           "<th>rms</th><th>p5</th><th>median</th><th>p95</th></tr>\n";
      for (auto& [pname, s] : params.items()) {
        if (!s.is_object()) continue;
        o << "<tr><td>" << HtmlEscape(pname) << "</td><td>"
          << HtmlEscape(s["unit"].is_string() ? s["unit"].get<std::string>() : "") << "</td><td>" << N(s["n"]) << "</td><td>"
          << N(s["mean"]) << "</td><td>" << N(s["std"]) << "</td><td>" << N(s["rms"])
          << "</td><td>" << N(s["p5"]) << "</td><td>" << N(s["median"]) << "</td><td>"
          << N(s["p95"]) << "</td></tr>\n";
      }
      o << "</table>\n";
    }
    o << "</section>\n";
  }

  if (summary["detection"].is_object()) {
    o << "<section><h2>Detection of effects</h2><table><tr><th>effect</th><th>trials</th>"
         "<th>named</th><th>missed</th><th>false</th></tr>\n";
    for (auto& [effect, d] : summary["detection"].items()) {
      if (!d.is_object()) continue;
      o << "<tr><td>" << HtmlEscape(effect) << "</td><td>" << N(d["trials"]) << "</td><td>"
        << N(d["named"]) << "</td><td>" << N(d["missed"]) << "</td><td>" << N(d["false"])
        << "</td></tr>\n";
    }
    o << "</table></section>\n";
  }

  o << "<section><h2>Every figure</h2><table><tr><th>figure</th><th>n</th><th>mean</th>"
       "<th>std</th><th>95 % CI of the mean</th><th>p5</th><th>median</th><th>p95</th></tr>\n";
  for (auto& [key, s] : figures.items()) {
    if (!s.is_object()) continue;
    o << "<tr><td>" << HtmlEscape(key) << "</td><td>" << N(s["n"]) << "</td><td>" << N(s["mean"])
      << "</td><td>" << N(s["std"]) << "</td><td>" << N(s["ci95_mean"][0]) << " .. "
      << N(s["ci95_mean"][1]) << "</td><td>" << N(s["p5"]) << "</td><td>" << N(s["median"])
      << "</td><td>" << N(s["p95"]) << "</td></tr>\n";
  }
  o << "</table></section>\n</body></html>\n";
  return o.str();
}

}  // namespace twin
