#include "bench/report/report_html.h"

#include <cmath>
#include <limits>
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace twin {
namespace {

using nlohmann::json;

json SampleReport() {
  return json::parse(R"({
    "scenario": {"name": "twin_demo", "file": "scenarios/twin_demo.yaml"},
    "intrinsics": {
      "estimated": {"fx": 834.5, "fy": 833.1, "cx": 513.2, "cy": 404.3, "k1": 0.001, "k2": 0,
                    "p1": 0, "p2": 0, "k3": 0},
      "true": {"fx": 834.31, "fy": 833.38, "cx": 513.56, "cy": 403.95, "k1": 0, "k2": 0,
               "p1": 0, "p2": 0, "k3": 0},
      "error_px": {"fx": 0.19, "fy": -0.28, "cx": -0.36, "cy": 0.35},
      "rms_reprojection_px": 0.071, "views_used": 14},
    "robots": {
      "r2": {
        "camera_robot": "r1",
        "planning": {"axes": 4, "positions_per_axis": 3, "best_fitness": 0.0123, "best_run": 1,
                     "fitness_history": [[1.0, 0.5, 0.2, 0.1], [0.8, 0.1, 0.05, 0.0123]],
                     "rejections": {"C1_reach": 12, "C3_visibility": 4}},
        "servo": {"aligned_poses": 11, "failed_poses": 1, "mean_frames_per_pose": 7.4,
                  "max_final_pixel_error_px": 0.42,
                  "failures": [{"axis": 2, "index": 1, "status": "diverged",
                                "reason": "board left the image"}],
                  "images": [{"file": "images/r2_axis0_before.png", "caption": "axis 0 before"},
                             {"file": "images/r2_axis0_after.png", "caption": "axis 0 after"}]},
        "split": {"calibration_axes": [0, 1, 2], "validation_axes": [3]},
        "misaligned_error_mm": {
          "calibration": {"before": 12.5, "after": 0.11, "decrease_percent": 99.1},
          "validation": {"before": 10.2, "after": 0.2, "decrease_percent": 98.0},
          "per_axis": [{"axis": 0, "set": "calibration", "before": 12.5, "after": 0.11},
                       {"axis": 3, "set": "validation", "before": 10.2, "after": 0.2}]},
        "truth_position_error_mm": {"configurations": 50,
          "raw": {"before": {"rms": 4.1, "max": 9.3}, "after": {"rms": 0.31, "max": 0.8}},
          "rigid": {"before": {"rms": 3.0, "max": 6.1}, "after": {"rms": 0.12, "max": 0.3}},
          "similarity": {"before": {"rms": 2.9, "max": 6.0}, "after": {"rms": 0.1, "max": 0.25}}},
        "scale": {"estimated": 1.0012, "true": 1.0},
        "unidentifiable": ["r2.link1.d + r2.link2.d"],
        "identifiable_combinations": {"count": 20, "rms_error": 0.01, "max_error": 0.03},
        "parameters": [
          {"name": "r2.link3.alpha", "unit": "deg", "estimated": 0.098, "true": 0.1},
          {"name": "r2.link2.a", "unit": "mm", "estimated": 0.52, "true": 0.5}],
        "identification": {"method": "ceres", "iterations": 12, "final_cost": 1.5e-07}
      }
    },
    "timing_s": {"total": 120.5, "intrinsics": 10.1, "planning": 20.2, "servoing": 70.3,
                 "identification": 15.0, "diagnosis": 2.5, "scoring": 2.0},
    "base_frame": {"installation": "floor", "general": {"e_tran_mm": 0.5, "e_rot_deg": 0.01},
                   "constrained": {"e_tran_mm": 0.3, "e_rot_deg": 0.008},
                   "workflow": {"nominal_kinematics": {"e_tran_mm": 4.2, "e_rot_deg": 0.2},
                                "calibrated_kinematics": {"e_tran_mm": 0.4, "e_rot_deg": 0.01}}}
  })");
}

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) ++n;
  return n;
}

// Heights of the bars of the misaligned-error chart, in document order.
std::vector<double> BarHeights(const std::string& html) {
  std::vector<double> heights;
  std::regex bar(R"re(<rect class="bar"[^>]*height="([0-9.]+)")re");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), bar); it != std::sregex_iterator(); ++it)
    heights.push_back(std::stod((*it)[1].str()));
  return heights;
}

json OneAxis(double before, double after) {
  json r;
  r["robots"]["r1"]["misaligned_error_mm"]["per_axis"] =
      json::array({{{"axis", 0}, {"set", "calibration"}, {"before", before}, {"after", after}}});
  return r;
}

TEST(ReportHtml, FullSampleHasRobotPlotsImagesAndTables) {
  std::string html = RenderReportHtml(SampleReport());
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_NE(html.find("</html>"), std::string::npos);
  EXPECT_NE(html.find("twin_demo"), std::string::npos);
  EXPECT_NE(html.find("Robot r2"), std::string::npos);
  EXPECT_NE(html.find("id=\"misaligned\""), std::string::npos);
  EXPECT_NE(html.find("id=\"fitness\""), std::string::npos);
  EXPECT_NE(html.find("id=\"timing\""), std::string::npos);
  EXPECT_NE(html.find("<tr><td>diagnosis</td><td>2.50</td>"), std::string::npos);  // a stage
  EXPECT_NE(html.find("deviation from nominal [mm]"), std::string::npos);
  EXPECT_NE(html.find("deviation from nominal [deg]"), std::string::npos);
  EXPECT_EQ(Count(html, "<svg"), 5);  // bars, mm panel, deg panel, fitness, timing
  EXPECT_EQ(Count(html, "<polyline class=\"run\""), 2);
  EXPECT_EQ(Count(html, "<rect class=\"bar\""), 4);
  EXPECT_NE(html.find("<img src=\"images/r2_axis0_before.png\""), std::string::npos);
  EXPECT_NE(html.find("<figcaption>axis 0 after</figcaption>"), std::string::npos);
  EXPECT_NE(html.find("board left the image"), std::string::npos);
  EXPECT_NE(html.find("r2.link1.d + r2.link2.d"), std::string::npos);
  EXPECT_NE(html.find("C3_visibility"), std::string::npos);
  EXPECT_NE(html.find("workflow, calibrated kinematics"), std::string::npos);
  EXPECT_NE(html.find("<td>ceres</td>"), std::string::npos);
  EXPECT_NE(html.find("<td>99.1</td>"), std::string::npos);  // decrease percent
  EXPECT_NE(html.find("<td>0.0200</td>"), std::string::npos);  // r2.link2.a est - true
  // Self-contained: no scripts, no external style sheets or fonts.
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("http://"), html.find("http://www.w3.org/2000/svg"));
  EXPECT_EQ(html.find("https://"), std::string::npos);
}

TEST(ReportHtml, EscapesStringsFromTheReport) {
  json r = SampleReport();
  r["robots"]["<b>"] = r["robots"]["r2"];
  r["robots"]["<b>"]["servo"]["images"][0]["file"] = "a\"onerror=\"x.png";
  r["scenario"]["name"] = "A&B <script>";
  std::string html = RenderReportHtml(r);
  EXPECT_NE(html.find("Robot &lt;b&gt;"), std::string::npos);
  EXPECT_EQ(html.find("<b>\n"), std::string::npos);
  EXPECT_EQ(html.find("Robot <b>"), std::string::npos);
  EXPECT_NE(html.find("A&amp;B &lt;script&gt;"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_NE(html.find("src=\"a&quot;onerror=&quot;x.png\""), std::string::npos);
  EXPECT_EQ(HtmlEscape("<a href='x'>&\"</a>"), "&lt;a href=&#39;x&#39;&gt;&amp;&quot;&lt;/a&gt;");
}

TEST(ReportHtml, EmptyOrOddJsonRendersAValidPage) {
  for (const json& j : {json::object(), json(), json::array({1, 2}), json("text"), json(3.5)}) {
    std::string html;
    ASSERT_NO_THROW(html = RenderReportHtml(j));
    EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
    EXPECT_NE(html.find("</body>\n</html>"), std::string::npos);
    EXPECT_EQ(html.find("<svg"), std::string::npos);
  }
  // Wrong types everywhere must not throw either.
  json odd = json::parse(R"({"scenario": 5, "intrinsics": [1], "robots": {"r1": {
      "planning": {"fitness_history": [3, [null, "x"], {"a": 1}], "best_run": "one"},
      "servo": {"failures": [7], "images": [{"file": 3}, "x"]},
      "misaligned_error_mm": {"per_axis": [{"axis": "a", "before": "b"}, 4], "calibration": 2},
      "truth_position_error_mm": {"raw": {"before": 1}}, "parameters": [1, {"unit": 2}],
      "unidentifiable": {"x": 1}, "identification": {"nested": {"a": [1, 2]}}},
      "r2": 12}, "timing_s": {"total": "long"}, "base_frame": {"workflow": 1}})");
  std::string html;
  ASSERT_NO_THROW(html = RenderReportHtml(odd));
  EXPECT_NE(html.find("Robot r1"), std::string::npos);
  EXPECT_NE(html.find("{&quot;a&quot;:[1,2]}"), std::string::npos);
}

TEST(ReportHtml, NullNanAndInfinityPrintNotAvailable) {
  json r;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  r["robots"]["r1"]["scale"] = {{"estimated", nan}, {"true", nullptr}};
  r["robots"]["r1"]["misaligned_error_mm"]["calibration"] = {
      {"before", std::numeric_limits<double>::infinity()}, {"after", nullptr}};
  r["intrinsics"]["rms_reprojection_px"] = nan;
  std::string html = RenderReportHtml(r);
  EXPECT_NE(html.find("<td>estimated</td><td>n/a</td>"), std::string::npos);
  EXPECT_NE(html.find("<td>true</td><td>n/a</td>"), std::string::npos);
  EXPECT_NE(html.find("<td>calibration</td><td>n/a</td><td>n/a</td><td>n/a</td>"), std::string::npos);
  EXPECT_NE(html.find("RMS reprojection error: n/a px"), std::string::npos);
  EXPECT_EQ(html.find("nan"), std::string::npos);
  EXPECT_EQ(html.find("inf<"), std::string::npos);
  EXPECT_EQ(FormatReportNumber(nan), "n/a");
  EXPECT_EQ(FormatReportNumber(-std::numeric_limits<double>::infinity()), "n/a");
}

TEST(ReportHtml, FormatsNumbersToAboutThreeSignificantDigits) {
  EXPECT_EQ(FormatReportNumber(0), "0");
  EXPECT_EQ(FormatReportNumber(12.345), "12.3");
  EXPECT_EQ(FormatReportNumber(-0.012345), "-0.0123");
  EXPECT_EQ(FormatReportNumber(1234.5), "1234");
  EXPECT_EQ(FormatReportNumber(1.5e-5), "1.50e-05");
  EXPECT_EQ(FormatReportNumber(2.5e7), "2.50e+07");
}

TEST(ReportHtml, BarHeightsFollowTheValuesOnALogScale) {
  std::vector<double> h = BarHeights(RenderReportHtml(OneAxis(10.0, 0.1)));
  ASSERT_EQ(h.size(), 2u);
  EXPECT_GT(h[0], h[1]);
  EXPECT_GT(h[1], 0);
  h = BarHeights(RenderReportHtml(OneAxis(0.1, 10.0)));  // an (odd) increase plots taller after
  ASSERT_EQ(h.size(), 2u);
  EXPECT_LT(h[0], h[1]);
  // Log scale: 10 -> 1 -> 0.1 are equal steps.
  json r = OneAxis(10.0, 1.0);
  r["robots"]["r1"]["misaligned_error_mm"]["per_axis"].push_back(
      {{"axis", 1}, {"set", "validation"}, {"before", 1.0}, {"after", 0.1}});
  h = BarHeights(RenderReportHtml(r));
  ASSERT_EQ(h.size(), 4u);
  EXPECT_NEAR(h[0] - h[1], h[2] - h[3], 0.2);
  EXPECT_NEAR(h[1], h[2], 1e-9);
  // Missing and non-positive values are not drawn as bars.
  h = BarHeights(RenderReportHtml(OneAxis(5.0, 0.0)));
  EXPECT_EQ(h.size(), 1u);
}

TEST(ReportHtml, ParameterPlotPlacesTrueAndEstimatedOnOneAxis) {
  json r;
  r["robots"]["r1"]["parameters"] = json::array(
      {{{"name", "r1.link1.a"}, {"unit", "mm"}, {"estimated", 1.0}, {"true", -1.0}}});
  std::string html = RenderReportHtml(r);
  std::regex circle(R"re(<circle cx="([0-9.]+)" cy="[0-9.]+" r="[0-9.]+" fill="(white|#d62728)")re");
  std::vector<std::pair<double, std::string>> dots;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), circle); it != std::sregex_iterator(); ++it)
    dots.emplace_back(std::stod((*it)[1].str()), (*it)[2].str());
  ASSERT_EQ(dots.size(), 4u);  // two legend markers, then the true and estimated dots
  EXPECT_EQ(dots[2].second, "white");
  EXPECT_EQ(dots[3].second, "#d62728");
  EXPECT_LT(dots[2].first, dots[3].first);  // true -1 left of estimated +1
  EXPECT_NE(html.find(">2.00</text>"), std::string::npos);  // est - true
}

}  // namespace
}  // namespace twin
