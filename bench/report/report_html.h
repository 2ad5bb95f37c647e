// The human-readable face of report.json (`twinbench run`): one self-contained HTML page with
// inline CSS and inline SVG plots (no scripts, no external files except the servo PNGs the
// report names by relative path), so it opens offline from the run's output folder.
//
// Every part of the report is optional: a missing or null key, or a value of an unexpected type,
// skips that part (or prints "n/a" for a number); NaN and infinities print "n/a". Nothing throws
// for odd input. All strings from the report are HTML-escaped.
#pragma once

#include <string>
#include <string_view>

#include <nlohmann/json_fwd.hpp>

namespace twin {

/// Escapes & < > " ' for HTML text, attribute values and inline SVG.
std::string HtmlEscape(std::string_view text);

/// A number as the report prints it: about 3 significant digits in fixed notation for
/// 1e-3 <= |v| < 1e6 (e.g. 12.3, 0.0123, 1235), scientific otherwise (1.23e-05), "0" for zero,
/// "n/a" for NaN or infinities.
std::string FormatReportNumber(double value);

/// The HTML page for a report.json document (see the schema in bench/report/report_html.cc). Any JSON
/// value is accepted; a non-object renders an (almost) empty page.
std::string RenderReportHtml(const nlohmann::json& report);

}  // namespace twin
