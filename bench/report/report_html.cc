// report.json -> HTML. Schema (lengths mm, angles deg; every key optional):
//   scenario {name, file}; intrinsics {estimated, true, error_px, rms_reprojection_px,
//   views_used}; robots {<name>: {camera_robot, planning, servo, split, misaligned_error_mm,
//   truth_position_error_mm, scale, unidentifiable, identifiable_combinations, parameters,
//   identification}}; timing_s {total, intrinsics, planning, servoing, identification, scoring};
//   base_frame {installation, general, constrained, workflow {nominal_kinematics,
//   calibrated_kinematics}}.
// Plots are SVG written here by hand: a log-scale grouped bar chart of the misaligned error per
// axis, dot plots of the parameter deviations (true vs estimated), the PSO best fitness per
// iteration (one polyline per run), and a stacked bar of the timing.
#include "bench/report/report_html.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/report/diagnosis_report.h"

namespace twin {
namespace {

using nlohmann::json;

// ---- Safe access: nullptr for missing, null or non-object parents; never throws. ----

const json* Find(const json* j, const char* key) {
  if (j == nullptr || !j->is_object()) return nullptr;
  auto it = j->find(key);
  if (it == j->end() || it->is_null()) return nullptr;
  return &*it;
}

const json* At(const json* j, std::initializer_list<const char*> keys) {
  for (const char* key : keys) j = Find(j, key);
  return j;
}

std::optional<double> Num(const json* j) {
  if (j == nullptr || !j->is_number()) return std::nullopt;
  double v = j->get<double>();
  if (!std::isfinite(v)) return std::nullopt;
  return v;
}

// A number for a table cell: integers as integers, other numbers formatted, anything else n/a.
std::string NumText(const json* j) {
  if (j == nullptr || !j->is_number()) return "n/a";
  if (j->is_number_unsigned()) return std::to_string(j->get<std::uint64_t>());
  if (j->is_number_integer()) return std::to_string(j->get<std::int64_t>());
  return FormatReportNumber(j->get<double>());
}

std::string NumText(std::optional<double> v) { return v ? FormatReportNumber(*v) : "n/a"; }

// Fixed decimals, for values whose interesting digits sit far behind the leading one (834.31 px,
// a scale of 1.0012).
std::string Fixed(std::optional<double> v, int decimals) {
  if (!v) return "n/a";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, *v);
  return buf;
}

// Any scalar as escaped text; objects and arrays as escaped compact JSON.
std::string ValueText(const json* j) {
  if (j == nullptr) return "n/a";
  if (j->is_string()) return HtmlEscape(j->get<std::string>());
  if (j->is_number()) return NumText(j);
  if (j->is_boolean()) return j->get<bool>() ? "true" : "false";
  return HtmlEscape(j->dump(-1, ' ', false, json::error_handler_t::replace));
}

std::string Str(const json* j) { return j != nullptr && j->is_string() ? j->get<std::string>() : ""; }

// ---- Small writers ----

std::string F(double v) {  // an SVG coordinate
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", std::isfinite(v) ? v : 0.0);
  return buf;
}

void Row(std::ostream& o, const std::vector<std::string>& cells, bool header = false) {
  o << "<tr>";
  for (const std::string& c : cells) o << (header ? "<th>" : "<td>") << c << (header ? "</th>" : "</td>");
  o << "</tr>\n";
}

const char* const kPalette[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};

// Value -> pixel along one axis, linear or log10.
struct Scale {
  double d0 = 0, d1 = 1, r0 = 0, r1 = 1;
  bool log = false;
  double operator()(double v) const {
    double x = log ? std::log10(v) : v;
    return r0 + (x - d0) / (d1 - d0) * (r1 - r0);
  }
};

// Log axis over [lo, hi] > 0: whole decades, at least a quarter decade below the smallest value.
Scale LogScale(double lo, double hi, double r0, double r1) {
  Scale s;
  s.log = true;
  s.d1 = std::ceil(std::log10(hi));
  s.d0 = std::floor(std::log10(lo) - 0.25);
  if (s.d1 <= s.d0) s.d1 = s.d0 + 1;
  if (s.d1 - s.d0 > 14) s.d0 = s.d1 - 14;
  s.r0 = r0;
  s.r1 = r1;
  return s;
}

std::vector<double> NiceTicks(double lo, double hi, int target) {
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi)) return {lo};
  double raw = (hi - lo) / target;
  double p = std::pow(10.0, std::floor(std::log10(raw)));
  double m = raw / p;
  double step = (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10) * p;
  std::vector<double> ticks;
  for (double t = std::ceil(lo / step) * step; t <= hi + step * 1e-9 && ticks.size() < 50; t += step)
    ticks.push_back(std::fabs(t) < step * 1e-9 ? 0.0 : t);
  return ticks;
}

// Axis tick text: shortest form, no trailing zeros (0.001, 25, 1e-05).
std::string TickText(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// Horizontal grid lines and labels of a y axis; ticks are data values (decades for log).
void YAxis(std::ostream& o, const Scale& y, double x0, double x1, const std::string& label) {
  std::vector<std::pair<double, std::string>> ticks;
  if (y.log) {
    for (int k = static_cast<int>(y.d0); k <= static_cast<int>(y.d1); ++k)
      ticks.emplace_back(std::pow(10.0, k), TickText(std::pow(10.0, k)));
  } else {
    for (double t : NiceTicks(y.d0, y.d1, 5)) ticks.emplace_back(t, TickText(t));
  }
  for (const auto& [v, text] : ticks) {
    double py = y(v);
    o << "<line class=\"grid\" x1=\"" << F(x0) << "\" x2=\"" << F(x1) << "\" y1=\"" << F(py)
      << "\" y2=\"" << F(py) << "\"/><text class=\"tick\" x=\"" << F(x0 - 4) << "\" y=\""
      << F(py + 3) << "\" text-anchor=\"end\">" << text << "</text>\n";
  }
  double mid = (y.r0 + y.r1) / 2;
  o << "<text class=\"label\" transform=\"translate(14," << F(mid)
    << ") rotate(-90)\" text-anchor=\"middle\">" << HtmlEscape(label) << "</text>\n";
}

void Swatch(std::ostream& o, double x, double y, const std::string& colour, const std::string& text) {
  o << "<rect x=\"" << F(x) << "\" y=\"" << F(y - 9) << "\" width=\"10\" height=\"10\" fill=\""
    << colour << "\"/><text class=\"tick\" x=\"" << F(x + 14) << "\" y=\"" << F(y) << "\">"
    << HtmlEscape(text) << "</text>\n";
}

// ---- Plots ----

// (1) Misaligned error per axis, before and after, log y; colour by calibration/validation set.
std::string MisalignedBarChart(const json* per_axis) {
  if (per_axis == nullptr || !per_axis->is_array() || per_axis->empty()) return "";
  struct Bar { std::string axis; bool validation; std::optional<double> before, after; };
  std::vector<Bar> bars;
  double lo = INFINITY, hi = 0;
  for (const json& e : *per_axis) {
    Bar b{NumText(Find(&e, "axis")), Str(Find(&e, "set")) == "validation", Num(Find(&e, "before")),
          Num(Find(&e, "after"))};
    for (auto* v : {&b.before, &b.after}) {
      if (*v && **v > 0) { lo = std::min(lo, **v); hi = std::max(hi, **v); } else { v->reset(); }
    }
    bars.push_back(b);
  }
  if (!(hi > 0)) return "<p class=\"note\">No positive misaligned errors to plot.</p>\n";
  const double left = 70, top = 34, bottom = 46, bar_w = 22;
  const double group = std::clamp(470.0 / bars.size(), 64.0, 110.0);
  const double width = std::max(560.0, left + group * bars.size() + 20), height = 300;
  Scale y = LogScale(lo, hi, height - bottom, top);
  std::ostringstream o;
  o << "<svg class=\"plot\" id=\"misaligned\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << F(width)
    << "\" height=\"" << F(height) << "\" viewBox=\"0 0 " << F(width) << " " << F(height) << "\">\n";
  YAxis(o, y, left, width - 10, "misaligned error [mm] (log)");
  const char* colours[2][2] = {{"#1f77b4", "#9ecae1"}, {"#e6550d", "#fdbe85"}};
  Swatch(o, left, 16, colours[0][0], "calibration before");
  Swatch(o, left + 130, 16, colours[0][1], "calibration after");
  Swatch(o, left + 250, 16, colours[1][0], "validation before");
  Swatch(o, left + 375, 16, colours[1][1], "validation after");
  double base = height - bottom;
  for (std::size_t i = 0; i < bars.size(); ++i) {
    const Bar& b = bars[i];
    double gx = left + group * i + (group - 2 * bar_w) / 2;
    const char* set = b.validation ? "validation" : "calibration";
    for (int k = 0; k < 2; ++k) {
      const std::optional<double>& v = k == 0 ? b.before : b.after;
      double x = gx + k * bar_w;
      if (!v) {
        o << "<text class=\"tick\" x=\"" << F(x + bar_w / 2) << "\" y=\"" << F(base - 4)
          << "\" text-anchor=\"middle\">n/a</text>\n";
        continue;
      }
      double top_y = std::min(base, y(*v));
      o << "<rect class=\"bar\" data-set=\"" << set << "\" data-kind=\"" << (k == 0 ? "before" : "after")
        << "\" x=\"" << F(x) << "\" y=\"" << F(top_y) << "\" width=\"" << F(bar_w - 2) << "\" height=\""
        << F(base - top_y) << "\" fill=\"" << colours[b.validation][k] << "\"><title>axis "
        << HtmlEscape(b.axis) << " (" << set << ") " << (k == 0 ? "before" : "after") << ": "
        << FormatReportNumber(*v) << " mm</title></rect>\n";
    }
    o << "<text class=\"tick\" x=\"" << F(gx + bar_w) << "\" y=\"" << F(base + 14)
      << "\" text-anchor=\"middle\">" << HtmlEscape(b.axis) << "</text>\n";
  }
  o << "<line class=\"axis\" x1=\"" << F(left) << "\" x2=\"" << F(width - 10) << "\" y1=\"" << F(base)
    << "\" y2=\"" << F(base) << "\"/>\n<text class=\"label\" x=\"" << F((left + width) / 2) << "\" y=\""
    << F(height - 8) << "\" text-anchor=\"middle\">axis (before | after)</text>\n</svg>\n";
  return o.str();
}

// (2) One dot-plot panel per unit: true (hollow) vs estimated (filled) deviation from nominal.
struct Param { std::string name; std::optional<double> truth, estimated; };

std::string ParameterPanel(const std::string& unit, const std::vector<Param>& params) {
  double m = 0;
  for (const Param& p : params)
    for (const auto& v : {p.truth, p.estimated}) if (v) m = std::max(m, std::fabs(*v));
  if (m == 0) m = 1;
  m *= 1.1;
  const double label_w = 170, plot_w = 380, right_w = 130, top = 30, row = 18, bottom = 36;
  const double width = label_w + plot_w + right_w, height = top + row * params.size() + bottom;
  Scale x{-m, m, label_w, label_w + plot_w, false};
  std::ostringstream o;
  o << "<svg class=\"plot\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << F(width) << "\" height=\""
    << F(height) << "\" viewBox=\"0 0 " << F(width) << " " << F(height) << "\">\n";
  o << "<circle cx=\"" << F(label_w + 6) << "\" cy=\"12\" r=\"4\" fill=\"white\" stroke=\"#333\"/>"
    << "<text class=\"tick\" x=\"" << F(label_w + 14) << "\" y=\"16\">true</text>"
    << "<circle cx=\"" << F(label_w + 66) << "\" cy=\"12\" r=\"4\" fill=\"#d62728\"/>"
    << "<text class=\"tick\" x=\"" << F(label_w + 74) << "\" y=\"16\">estimated</text>"
    << "<text class=\"tick\" x=\"" << F(label_w + plot_w + 8) << "\" y=\"16\">est - true [" << HtmlEscape(unit)
    << "]</text>\n";
  double y_end = top + row * params.size();
  for (double t : NiceTicks(-m, m, 6)) {
    o << "<line class=\"" << (t == 0 ? "axis" : "grid") << "\" x1=\"" << F(x(t)) << "\" x2=\"" << F(x(t))
      << "\" y1=\"" << F(top) << "\" y2=\"" << F(y_end) << "\"/><text class=\"tick\" x=\"" << F(x(t))
      << "\" y=\"" << F(y_end + 13) << "\" text-anchor=\"middle\">" << TickText(t) << "</text>\n";
  }
  for (std::size_t i = 0; i < params.size(); ++i) {
    const Param& p = params[i];
    double cy = top + row * (i + 0.5);
    o << "<text class=\"tick\" x=\"" << F(label_w - 6) << "\" y=\"" << F(cy + 4) << "\" text-anchor=\"end\">"
      << HtmlEscape(p.name) << "</text>";
    if (p.truth && p.estimated)
      o << "<line class=\"link\" x1=\"" << F(x(*p.truth)) << "\" x2=\"" << F(x(*p.estimated)) << "\" y1=\""
        << F(cy) << "\" y2=\"" << F(cy) << "\"/>";
    if (p.truth)
      o << "<circle cx=\"" << F(x(*p.truth)) << "\" cy=\"" << F(cy) << "\" r=\"4\" fill=\"white\" stroke=\"#333\"/>";
    if (p.estimated)
      o << "<circle cx=\"" << F(x(*p.estimated)) << "\" cy=\"" << F(cy) << "\" r=\"3.5\" fill=\"#d62728\"/>";
    std::string err = p.truth && p.estimated ? FormatReportNumber(*p.estimated - *p.truth) : "n/a";
    o << "<text class=\"tick\" x=\"" << F(label_w + plot_w + 8) << "\" y=\"" << F(cy + 4) << "\">" << err
      << "</text>\n";
  }
  o << "<text class=\"label\" x=\"" << F(label_w + plot_w / 2) << "\" y=\"" << F(height - 6)
    << "\" text-anchor=\"middle\">deviation from nominal [" << HtmlEscape(unit) << "]</text>\n</svg>\n";
  return o.str();
}

std::string ParameterSection(const json* parameters) {
  if (parameters == nullptr || !parameters->is_array() || parameters->empty()) return "";
  std::map<std::string, std::vector<Param>> by_unit;
  std::ostringstream table;
  table << "<details><summary>parameter table</summary><table>\n";
  Row(table, {"parameter", "unit", "true", "estimated", "est - true"}, true);
  for (const json& p : *parameters) {
    Param param{Str(Find(&p, "name")), Num(Find(&p, "true")), Num(Find(&p, "estimated"))};
    std::string unit = Str(Find(&p, "unit"));
    by_unit[unit].push_back(param);
    Row(table, {HtmlEscape(param.name), HtmlEscape(unit), NumText(param.truth), NumText(param.estimated),
                param.truth && param.estimated ? FormatReportNumber(*param.estimated - *param.truth) : "n/a"});
  }
  table << "</table></details>\n";
  std::ostringstream o;
  o << "<h3>Parameter errors (deviation from nominal)</h3>\n";
  for (const char* unit : {"mm", "deg"}) {
    auto it = by_unit.find(unit);
    if (it != by_unit.end()) o << ParameterPanel(it->first, it->second);
  }
  for (const auto& [unit, params] : by_unit)
    if (unit != "mm" && unit != "deg") o << ParameterPanel(unit.empty() ? "?" : unit, params);
  o << table.str();
  return o.str();
}

// (3) PSO best fitness per iteration, one polyline per run; log y when every value is positive.
std::string FitnessPlot(const json* history, const json* best_run) {
  if (history == nullptr || !history->is_array()) return "";
  std::vector<std::vector<std::optional<double>>> runs;
  double lo = INFINITY, hi = -INFINITY;
  std::size_t longest = 0;
  for (const json& run : *history) {
    runs.emplace_back();
    if (!run.is_array()) continue;
    for (const json& v : run) {
      runs.back().push_back(Num(&v));
      if (auto x = runs.back().back()) { lo = std::min(lo, *x); hi = std::max(hi, *x); }
    }
    longest = std::max(longest, runs.back().size());
  }
  if (!(hi >= lo)) return "";
  const double left = 70, top = 30, bottom = 40, width = 600, height = 300;
  Scale y;
  if (lo > 0) {
    y = LogScale(lo, hi, height - bottom, top);
  } else {
    double pad = hi > lo ? (hi - lo) * 0.05 : 1;
    y = Scale{lo - pad, hi + pad, height - bottom, top, false};
  }
  Scale x{0, longest > 1 ? static_cast<double>(longest - 1) : 1.0, left, width - 15, false};
  std::optional<double> best = Num(best_run);
  std::ostringstream o;
  o << "<svg class=\"plot\" id=\"fitness\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << F(width)
    << "\" height=\"" << F(height) << "\" viewBox=\"0 0 " << F(width) << " " << F(height) << "\">\n";
  YAxis(o, y, left, width - 15, y.log ? "best fitness (log)" : "best fitness");
  for (double t : NiceTicks(x.d0, x.d1, 6)) {
    if (t != std::floor(t)) continue;
    o << "<text class=\"tick\" x=\"" << F(x(t)) << "\" y=\"" << F(height - bottom + 14)
      << "\" text-anchor=\"middle\">" << TickText(t) << "</text>";
  }
  o << "<line class=\"axis\" x1=\"" << F(left) << "\" x2=\"" << F(width - 15) << "\" y1=\"" << F(height - bottom)
    << "\" y2=\"" << F(height - bottom) << "\"/><text class=\"label\" x=\"" << F((left + width) / 2) << "\" y=\""
    << F(height - 8) << "\" text-anchor=\"middle\">iteration</text>\n";
  for (std::size_t r = 0; r < runs.size(); ++r) {
    bool is_best = best && static_cast<double>(r) == *best;
    std::string colour = kPalette[r % 10];
    std::string points;
    auto flush = [&] {
      if (!points.empty())
        o << "<polyline class=\"run\" fill=\"none\" stroke=\"" << colour << "\" stroke-width=\""
          << (is_best ? "2.5" : "1.2") << "\" points=\"" << points << "\"><title>run " << r
          << (is_best ? " (best)" : "") << "</title></polyline>\n";
      points.clear();
    };
    for (std::size_t i = 0; i < runs[r].size(); ++i) {
      const auto& v = runs[r][i];
      if (!v || (y.log && *v <= 0)) { flush(); continue; }
      points += F(x(static_cast<double>(i))) + "," + F(y(*v)) + " ";
    }
    flush();
    if (runs.size() <= 10)
      Swatch(o, left + 52.0 * r, 16, colour, "run " + std::to_string(r) + (is_best ? "*" : ""));
  }
  o << "</svg>\n";
  return o.str();
}

// Horizontal stacked bar of the stage timings.
std::string TimingBar(const std::vector<std::pair<std::string, double>>& stages, double total) {
  if (!(total > 0)) return "";
  const double width = 620, bar_w = 600;
  std::ostringstream o;
  o << "<svg class=\"plot\" id=\"timing\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << F(width)
    << "\" height=\"62\" viewBox=\"0 0 " << F(width) << " 62\">\n";
  double x = 10;
  for (std::size_t i = 0; i < stages.size(); ++i) {
    double w = bar_w * stages[i].second / total;
    o << "<rect x=\"" << F(x) << "\" y=\"6\" width=\"" << F(w) << "\" height=\"22\" fill=\"" << kPalette[i % 10]
      << "\"><title>" << HtmlEscape(stages[i].first) << ": " << FormatReportNumber(stages[i].second)
      << " s</title></rect>\n";
    Swatch(o, 10 + 100.0 * i, 50, kPalette[i % 10], stages[i].first);
    x += w;
  }
  o << "</svg>\n";
  return o.str();
}

// ---- Sections ----

std::string PairTable(const json* section, const std::vector<std::pair<const char*, const char*>>& rows) {
  std::ostringstream o;
  o << "<table>\n";
  for (const auto& [key, label] : rows) Row(o, {label, ValueText(Find(section, key))});
  o << "</table>\n";
  return o.str();
}

std::string IntrinsicsSection(const json* intr) {
  if (intr == nullptr || !intr->is_object()) return "";
  std::ostringstream o;
  o << "<section><h2>Camera intrinsics</h2>\n<table>\n";
  Row(o, {"", "estimated", "true", "est - true", "error [px]"}, true);
  const json* est = Find(intr, "estimated");
  const json* tru = Find(intr, "true");
  const json* err = Find(intr, "error_px");
  for (const char* k : {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"}) {
    auto e = Num(Find(est, k)), t = Num(Find(tru, k));
    if (!e && !t && Find(err, k) == nullptr) continue;
    bool pixels = k[0] == 'f' || k[0] == 'c';  // fx fy cx cy in px, 2 decimals; distortion 6
    Row(o, {k, Fixed(e, pixels ? 2 : 6), Fixed(t, pixels ? 2 : 6), e && t ? FormatReportNumber(*e - *t) : "n/a",
            NumText(Find(err, k))});
  }
  o << "</table>\n<p>RMS reprojection error: " << NumText(Find(intr, "rms_reprojection_px"))
    << " px; views used: " << NumText(Find(intr, "views_used")) << "</p></section>\n";
  return o.str();
}

std::string AxisList(const json* axes) {
  if (axes == nullptr || !axes->is_array()) return "n/a";
  std::string s;
  for (const json& a : *axes) s += (s.empty() ? "" : ", ") + ValueText(&a);
  return s.empty() ? "none" : s;
}

std::string RobotSection(const std::string& name, const json& r, int index) {
  std::ostringstream o;
  o << "<section class=\"robot\" id=\"robot-" << index << "\"><h2>Robot " << HtmlEscape(name) << "</h2>\n";
  if (const json* cam = Find(&r, "camera_robot")) o << "<p>Camera robot: " << ValueText(cam) << "</p>\n";
  o << "<div class=\"cards\">\n";
  // Misaligned error, calibration and validation sets.
  const json* mis = Find(&r, "misaligned_error_mm");
  if (mis != nullptr) {
    o << "<div><h3>Misaligned error [mm]</h3><table>\n";
    Row(o, {"set", "before", "after", "decrease [%]"}, true);
    for (const char* set : {"calibration", "validation"}) {
      const json* s = Find(mis, set);
      if (s == nullptr) continue;
      auto before = Num(Find(s, "before")), after = Num(Find(s, "after"));
      std::optional<double> dec = Num(Find(s, "decrease_percent"));
      if (!dec && before && after && *before != 0) dec = 100.0 * (*before - *after) / *before;
      Row(o, {set, NumText(before), NumText(after), NumText(dec)});
    }
    o << "</table>\n<p>calibration axes: " << AxisList(At(&r, {"split", "calibration_axes"}))
      << "; validation axes: " << AxisList(At(&r, {"split", "validation_axes"})) << "</p></div>\n";
  }
  // Position error against the truth, after raw / rigid / similarity alignment.
  // One table of raw / rigid / similarity errors, before and after.
  const auto gauge_table = [&o](const json* gauges) {
    o << "<table>\n";
    Row(o, {"alignment", "RMS before", "RMS after", "max before", "max after"}, true);
    for (const char* kind : {"raw", "rigid", "similarity"}) {
      const json* k = Find(gauges, kind);
      if (k == nullptr) continue;
      Row(o, {kind, NumText(At(k, {"before", "rms"})), NumText(At(k, {"after", "rms"})),
              NumText(At(k, {"before", "max"})), NumText(At(k, {"after", "max"}))});
    }
    o << "</table>";
  };
  if (const json* truth = Find(&r, "truth_position_error_mm")) {
    o << "<div><h3>Position error vs truth [mm]</h3>";
    gauge_table(truth);
    o << "<p>configurations: " << NumText(Find(truth, "configurations"))
      << " (whole joint space)</p></div>\n";
  }
  if (const json* region = Find(&r, "truth_position_error_mm_covered_region")) {
    o << "<div><h3>Position error vs truth over the covered region [mm]</h3>";
    gauge_table(region);
    o << "<table>\n";
    Row(o, {"joint", "lower [deg]", "upper [deg]"}, true);
    if (const json* joints = Find(region, "joint_box_deg"); joints && joints->is_array()) {
      for (const json& j : *joints) {
        Row(o, {NumText(Find(&j, "joint")), NumText(Find(&j, "lower_deg")),
                NumText(Find(&j, "upper_deg"))});
      }
    }
    o << "</table><p>" << NumText(Find(region, "configurations"))
      << " configurations drawn inside the joint ranges of the " << NumText(Find(region, "poses"))
      << " poses the model was identified from</p></div>\n";
  }
  if (const json* scale = Find(&r, "scale")) {
    auto e = Num(Find(scale, "estimated")), t = Num(Find(scale, "true"));
    o << "<div><h3>Scale</h3><table>\n";
    Row(o, {"estimated", Fixed(e, 6)});
    Row(o, {"true", Fixed(t, 6)});
    Row(o, {"error [%]", e && t && *t != 0 ? FormatReportNumber(100 * (*e - *t) / *t) : "n/a"});
    o << "</table></div>\n";
  }
  const json* servo = Find(&r, "servo");
  if (servo != nullptr)
    o << "<div><h3>Visual servo</h3>"
      << PairTable(servo, {{"aligned_poses", "aligned poses"}, {"failed_poses", "failed poses"},
                           {"mean_frames_per_pose", "mean frames / pose"},
                           {"max_final_pixel_error_px", "max final pixel error [px]"}})
      << "</div>\n";
  const json* planning = Find(&r, "planning");
  if (planning != nullptr) {
    o << "<div><h3>Pose planning (PSO)</h3>"
      << PairTable(planning, {{"axes", "axes"}, {"positions_per_axis", "positions / axis"},
                              {"best_fitness", "best fitness"}, {"best_run", "best run"}});
    if (const json* rej = Find(planning, "rejections"); rej != nullptr && rej->is_object() && !rej->empty()) {
      o << "<table>\n";
      Row(o, {"rejection", "count"}, true);
      for (auto it = rej->begin(); it != rej->end(); ++it) Row(o, {HtmlEscape(it.key()), ValueText(&it.value())});
      o << "</table>\n";
    }
    o << "</div>\n";
  }
  o << "</div>\n";
  // Plots.
  std::string bars = MisalignedBarChart(Find(mis, "per_axis"));
  if (!bars.empty()) o << "<h3>Misaligned error per axis</h3>\n" << bars;
  o << ParameterSection(Find(&r, "parameters"));
  std::string fitness = FitnessPlot(Find(planning, "fitness_history"), Find(planning, "best_run"));
  if (!fitness.empty()) o << "<h3>PSO best fitness per iteration</h3>\n" << fitness;
  // Identifiability.
  const json* unid = Find(&r, "unidentifiable");
  const json* combos = Find(&r, "identifiable_combinations");
  if (unid != nullptr || combos != nullptr) {
    o << "<h3>Identifiability</h3>\n";
    if (combos != nullptr)
      o << "<p>identifiable combinations: " << NumText(Find(combos, "count")) << "; RMS error "
        << NumText(Find(combos, "rms_error")) << ", max error " << NumText(Find(combos, "max_error")) << "</p>\n";
    if (unid != nullptr && unid->is_array()) {
      o << "<p>unidentifiable combinations (" << unid->size() << "):</p><ul>\n";
      for (const json& u : *unid) o << "<li><code>" << ValueText(&u) << "</code></li>\n";
      o << "</ul>\n";
    }
  }
  if (const json* ident = Find(&r, "identification"); ident != nullptr && ident->is_object()) {
    o << "<h3>Identification</h3><table>\n";
    for (auto it = ident->begin(); it != ident->end(); ++it) Row(o, {HtmlEscape(it.key()), ValueText(&it.value())});
    o << "</table>\n";
  }
  // Servo failures and images.
  if (const json* fails = Find(servo, "failures"); fails != nullptr && fails->is_array() && !fails->empty()) {
    o << "<h3>Servo failures</h3><table>\n";
    Row(o, {"axis", "index", "status", "reason"}, true);
    for (const json& f : *fails)
      Row(o, {ValueText(Find(&f, "axis")), ValueText(Find(&f, "index")), ValueText(Find(&f, "status")),
              ValueText(Find(&f, "reason"))});
    o << "</table>\n";
  }
  if (const json* images = Find(servo, "images"); images != nullptr && images->is_array() && !images->empty()) {
    o << "<h3>Servo images</h3><div class=\"figures\">\n";
    for (const json& img : *images) {
      std::string file = Str(Find(&img, "file"));
      if (file.empty()) continue;
      std::string caption = HtmlEscape(Str(Find(&img, "caption")));
      o << "<figure><img src=\"" << HtmlEscape(file) << "\" alt=\"" << caption << "\"><figcaption>" << caption
        << "</figcaption></figure>\n";
    }
    o << "</div>\n";
  }
  o << "</section>\n";
  return o.str();
}

std::string TimingSection(const json* timing) {
  if (timing == nullptr || !timing->is_object()) return "";
  std::ostringstream o;
  // The stages of timing_s that add up to its total (report.json), in the run's order.
  static const std::vector<std::string> kStages = {"intrinsics",     "planning",  "servoing",
                                                   "identification", "diagnosis", "scoring"};
  std::vector<std::pair<std::string, double>> stages;
  double sum = 0;
  for (const std::string& k : kStages) {
    if (auto v = Num(Find(timing, k.c_str())); v && *v > 0) { stages.emplace_back(k, *v); sum += *v; }
  }
  std::optional<double> total = Num(Find(timing, "total"));
  double denom = total && *total > sum ? *total : sum;
  if (total && *total > sum * 1.0001 && !stages.empty()) stages.emplace_back("other", *total - sum);
  o << "<section><h2>Timing</h2><table>\n";
  Row(o, {"stage", "time [s]", "share [%]"}, true);
  std::vector<std::string> rows = kStages;
  rows.push_back("total");
  for (const std::string& k : rows) {
    const json* v = Find(timing, k.c_str());
    if (v == nullptr) continue;
    auto s = Num(v);
    Row(o, {k, NumText(v), s && denom > 0 ? FormatReportNumber(100.0 * *s / denom) : "n/a"});
  }
  o << "</table>\n" << TimingBar(stages, denom) << "</section>\n";
  return o.str();
}

std::string BaseFrameSection(const json* base) {
  if (base == nullptr || !base->is_object()) return "";
  std::ostringstream o;
  o << "<section><h2>Base frame</h2>\n";
  if (const json* inst = Find(base, "installation")) o << "<p>Installation: " << ValueText(inst) << "</p>\n";
  o << "<table>\n";
  Row(o, {"solution", "translation error [mm]", "rotation error [deg]"}, true);
  const std::pair<const json*, const char*> rows[] = {
      {Find(base, "general"), "general"},
      {Find(base, "constrained"), "constrained"},
      {At(base, {"workflow", "nominal_kinematics"}), "workflow, nominal kinematics"},
      {At(base, {"workflow", "calibrated_kinematics"}), "workflow, calibrated kinematics"}};
  for (const auto& [s, label] : rows)
    if (s != nullptr) Row(o, {label, NumText(Find(s, "e_tran_mm")), NumText(Find(s, "e_rot_deg"))});
  o << "</table></section>\n";
  return o.str();
}

const char kStyle[] = R"(
body{font-family:system-ui,-apple-system,"Segoe UI",Helvetica,Arial,sans-serif;margin:24px auto;
max-width:1200px;padding:0 16px;color:#222;background:#fafafa}
h1{margin-bottom:4px}h2{border-bottom:2px solid #ccc;padding-bottom:4px;margin-top:32px}
section{background:#fff;border:1px solid #ddd;border-radius:6px;padding:8px 18px 16px;margin:18px 0}
table{border-collapse:collapse;margin:6px 0;font-size:14px}
th,td{border:1px solid #ccc;padding:3px 9px;text-align:right}
th{background:#eef2f7}td:first-child{text-align:left;font-weight:500}
.cards{display:flex;flex-wrap:wrap;gap:18px}.cards>div{min-width:240px}
.note,.meta{color:#666}
svg.plot{display:block;margin:8px 0;background:#fff}
svg .grid{stroke:#e3e3e3;stroke-width:1}svg .axis{stroke:#444;stroke-width:1}
svg .link{stroke:#999;stroke-width:1.5}
svg .tick{font-size:11px;fill:#333}svg .label{font-size:12px;fill:#111}
.figures{display:flex;flex-wrap:wrap;gap:12px}
figure{margin:0;border:1px solid #ddd;padding:6px;background:#fff}
figure img{max-width:360px;display:block}figcaption{font-size:13px;color:#444;margin-top:4px}
code{font-size:13px}
)";

}  // namespace

std::string HtmlEscape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string FormatReportNumber(double value) {
  if (!std::isfinite(value)) return "n/a";
  if (value == 0) return "0";
  double a = std::fabs(value);
  char buf[64];
  if (a >= 1e-3 && a < 1e6) {
    int decimals = std::clamp(2 - static_cast<int>(std::floor(std::log10(a))), 0, 6);
    std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  } else {
    std::snprintf(buf, sizeof buf, "%.2e", value);
  }
  return buf;
}

std::string RenderReportHtml(const json& report) {
  const json* root = &report;
  std::string name = Str(At(root, {"scenario", "name"}));
  std::string file = Str(At(root, {"scenario", "file"}));
  std::ostringstream o;
  o << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>twinbench report"
    << (name.empty() ? "" : " - " + HtmlEscape(name)) << "</title>\n<style>" << kStyle << "</style>\n</head>\n<body>\n";
  o << "<h1>twinbench calibration report</h1>\n<p class=\"meta\">scenario: <b>"
    << (name.empty() ? "n/a" : HtmlEscape(name)) << "</b>" << (file.empty() ? "" : " (" + HtmlEscape(file) + ")")
    << "</p>\n";
  const json* robots = Find(root, "robots");
  if (robots != nullptr && robots->is_object() && !robots->empty()) {
    o << "<p>robots:";
    int i = 0;
    for (auto it = robots->begin(); it != robots->end(); ++it, ++i)
      o << " <a href=\"#robot-" << i << "\">" << HtmlEscape(it.key()) << "</a>";
    o << "</p>\n";
  }
  o << IntrinsicsSection(Find(root, "intrinsics"));
  if (robots != nullptr && robots->is_object()) {
    int i = 0;
    for (auto it = robots->begin(); it != robots->end(); ++it, ++i)
      if (it.value().is_object()) {
        o << RobotSection(it.key(), it.value(), i);
        if (it.value().contains("diagnosis")) {
          o << "<div id=\"diagnosis-" << i << "\"><p class=\"meta\">robot "
            << HtmlEscape(it.key()) << ", model discovery on its aligned poses</p>"
            << DiagnosisHtml(it.value()["diagnosis"]) << "</div>\n";
        }
      }
  }
  o << BaseFrameSection(Find(root, "base_frame"));
  o << TimingSection(Find(root, "timing_s"));
  o << "</body>\n</html>\n";
  return o.str();
}

}  // namespace twin
