#include "bench/report/study_summary.h"

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "bench/report/study_summary_files.h"
#include "bench/report/study_summary_html.h"
#include "bench/report/trial_record.h"

namespace twin {
namespace {

using json = nlohmann::json;

// Reference values are R's (quantile type 7, t.test, qt, the Wilson interval of prop.test
// without continuity correction), printed to 4-6 digits: compared to 1e-4 or 1e-3.

TEST(StudySummaryTest, StatisticsOfOneToTen) {
  const FigureStats s = ComputeFigureStats({10, 9, 8, 7, 6, 5, 4, 3, 2, 1});
  EXPECT_EQ(s.n, 10);
  EXPECT_DOUBLE_EQ(s.mean, 5.5);
  EXPECT_NEAR(s.std, 3.02765, 1e-5);  // sd(1:10)
  EXPECT_DOUBLE_EQ(s.median, 5.5);
  EXPECT_NEAR(s.p5, 1.45, 1e-12);     // quantile(1:10, 0.05)
  EXPECT_NEAR(s.p95, 9.55, 1e-12);
  EXPECT_EQ(s.min, 1);
  EXPECT_EQ(s.max, 10);
  EXPECT_NEAR(s.ci95_low, 3.334149, 1e-3);  // t.test(1:10)$conf.int; the t table has 4 digits
  EXPECT_NEAR(s.ci95_high, 7.665851, 1e-3);
  const FigureStats one = ComputeFigureStats({2.0});
  EXPECT_EQ(one.std, 0.0);
  EXPECT_TRUE(std::isnan(one.ci95_low));
}

TEST(StudySummaryTest, StudentQuantilesAndWilsonIntervals) {
  EXPECT_NEAR(StudentT975(1), 12.7062, 1e-3);
  EXPECT_NEAR(StudentT975(9), 2.262157, 1e-3);
  EXPECT_NEAR(StudentT975(40), 2.021075, 1e-4);   // the expansion beyond the table
  EXPECT_NEAR(StudentT975(100), 1.983972, 1e-4);
  EXPECT_NEAR(StudentT975(1000), 1.962339, 1e-4);
  double lo, hi;
  WilsonInterval95(68, 100, &lo, &hi);
  EXPECT_NEAR(lo, 0.5833, 1e-3);
  EXPECT_NEAR(hi, 0.7633, 1e-3);
  WilsonInterval95(0, 10, &lo, &hi);
  EXPECT_EQ(lo, 0.0);
  EXPECT_NEAR(hi, 0.2775, 1e-3);
}

json Record(int trial, double est, double tru, double sigma, const char* status = "ok") {
  json f;
  f["robots.r2.truth_position_error_mm.rigid.after.rms"] = 0.1 * (trial + 1);
  f["robots.r2.identification.nonlinear.depth_used"] = trial % 2 == 0;
  f["robots.r2.identifiable_combinations.items[0].estimated"] = est;
  f["robots.r2.identifiable_combinations.items[0].true"] = tru;
  f["robots.r2.identifiable_combinations.items[0].sigma"] = sigma;
  f["robots.r2.parameters[r2.link2.d].estimated"] = est;
  f["robots.r2.parameters[r2.link2.d].true"] = tru;
  return {{"scenario", "s"},
          {"scenario_hash", "h"},
          {"trial", trial},
          {"status", status},
          {"reason", std::string(status) == "ok" ? "" : "boom"},
          {"figures", f},
          {"labels", {{"robots.r2.parameters[r2.link2.d].unit", "mm"}}}};
}

TEST(StudySummaryTest, FiguresCoverageAndParameterErrors) {
  // |estimated - true| / sigma = 0.5, 1.5, 2.5, 0.9 over four ok trials; one failed trial
  // (which would be 0.0) must not count.
  const std::vector<json> records = {Record(0, 1.5, 1.0, 1.0), Record(1, -3.0, 0.0, 2.0),
                                     Record(2, 5.0, 0.0, 2.0), Record(3, 0.9, 0.0, 1.0),
                                     Record(4, 0.0, 0.0, 1.0, "failed")};
  const json s = SummarizeStudy(records);
  EXPECT_EQ(s["trials"]["recorded"], 5);
  EXPECT_EQ(s["trials"]["ok"], 4);
  EXPECT_EQ(s["trials"]["failed"], 1);
  EXPECT_EQ(s["trials"]["failures"][0]["trial"], 4);
  EXPECT_EQ(s["trials"]["failures"][0]["reason"], "boom");
  const json& rigid = s["figures"]["robots.r2.truth_position_error_mm.rigid.after.rms"];
  EXPECT_EQ(rigid["n"], 4);
  EXPECT_NEAR(rigid["mean"].get<double>(), 0.25, 1e-12);  // (0.1 + 0.2 + 0.3 + 0.4) / 4
  // Booleans count as 0 / 1: the mean is the fraction true (trials 0 and 2).
  EXPECT_NEAR(s["figures"]["robots.r2.identification.nonlinear.depth_used"]["mean"].get<double>(),
              0.5, 1e-12);
  const json& c = s["coverage"]["robots.r2"]["combinations"][0];
  EXPECT_EQ(c["n"], 4);
  EXPECT_DOUBLE_EQ(c["within_1_sigma"].get<double>(), 0.5);   // 0.5 and 0.9
  EXPECT_DOUBLE_EQ(c["within_2_sigma"].get<double>(), 0.75);  // and 1.5
  EXPECT_NEAR(c["rms_normalized_error"].get<double>(), std::sqrt((0.25 + 2.25 + 6.25 + 0.81) / 4),
              1e-12);
  EXPECT_EQ(s["coverage"]["robots.r2"]["pooled"]["n"], 4);
  const json& pe = s["parameter_errors"]["robots.r2"]["r2.link2.d"];
  EXPECT_EQ(pe["unit"], "mm");
  EXPECT_EQ(pe["n"], 4);
  EXPECT_NEAR(pe["mean"].get<double>(), (0.5 - 3.0 + 5.0 + 0.9) / 4, 1e-12);
  EXPECT_FALSE(s.contains("detection"));
}

TEST(StudySummaryTest, DetectionTableCountsNamedMissedAndFalse) {
  std::vector<json> records;
  const bool present[] = {true, true, true, false, false};
  const bool named[] = {true, false, true, true, false};
  for (int t = 0; t < 5; ++t) {
    json r = Record(t, 0, 0, 1);
    r["figures"]["discovery.effects[backlash].present"] = present[t];
    r["figures"]["discovery.effects[backlash].named"] = named[t];
    records.push_back(r);
  }
  const json d = SummarizeStudy(records)["detection"]["backlash"];
  EXPECT_EQ(d["trials"], 5);
  EXPECT_EQ(d["named"], 2);
  EXPECT_EQ(d["missed"], 1);
  EXPECT_EQ(d["false"], 1);
}

TEST(StudySummaryTest, CountsTrialsPerRendererAndWarnsWhenThereAreTwo) {
  std::vector<json> records;
  const char* renderers[] = {"osmesa (llvmpipe)", "egl (NVIDIA H100)", "osmesa (llvmpipe)",
                             nullptr};
  for (int t = 0; t < 4; ++t) {
    json r = Record(t, 0, 0, 1);
    r["run"] = {{"timing", {{"timing_s.total", 20.0}}}};
    if (renderers[t]) r["run"]["timing"]["timing_s.cell.renderer"] = renderers[t];
    records.push_back(r);
  }
  const json counts = SummarizeStudy(records)["renderers"];
  EXPECT_EQ(counts.size(), 2u) << counts.dump();
  EXPECT_EQ(counts.value("osmesa (llvmpipe)", 0), 2);
  EXPECT_EQ(counts.value("egl (NVIDIA H100)", 0), 1);

  const std::string dir = ::testing::TempDir() + "/summary_renderers";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::vector<TrialRecord> mixed, one;
  for (int t = 0; t < 4; ++t) {
    mixed.push_back(TrialRecord(records[t]));
    if (t != 1) one.push_back(TrialRecord(records[t]));
  }
  const std::string warning = WriteStudySummaryFiles(dir, mixed).mixed_renderers_warning;
  EXPECT_NE(warning.find("2 GL back ends"), std::string::npos) << warning;
  EXPECT_NE(warning.find("egl (NVIDIA H100): 1 trials"), std::string::npos) << warning;
  EXPECT_NE(warning.find("osmesa (llvmpipe): 2 trials"), std::string::npos) << warning;
  EXPECT_EQ(WriteStudySummaryFiles(dir, one).mixed_renderers_warning, "");
}

TEST(StudySummaryHtmlTest, ShowsDistributionsCoverageAndEscapes) {
  std::vector<json> records = {Record(0, 1.5, 1.0, 1.0), Record(1, -3.0, 0.0, 2.0),
                               Record(2, 5.0, 0.0, 2.0, "failed")};
  records[2]["reason"] = "<bad> & \"quoted\"";
  const std::string html = RenderStudySummaryHtml(SummarizeStudy(records), records);
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_NE(html.find("robots.r2.truth_position_error_mm.rigid.after.rms"), std::string::npos);
  EXPECT_NE(html.find("Coverage check"), std::string::npos);
  EXPECT_NE(html.find("&lt;bad&gt; &amp; &quot;quoted&quot;"), std::string::npos);
  EXPECT_EQ(html.find("<bad>"), std::string::npos);
  // Odd input renders without throwing.
  EXPECT_NE(RenderStudySummaryHtml(json(nullptr), {}).find("</html>"), std::string::npos);
}

}  // namespace
}  // namespace twin
