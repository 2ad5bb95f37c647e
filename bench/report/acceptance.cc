#include "bench/report/acceptance.h"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <algorithm>
#include <cctype>
#include <set>
#include <sstream>
#include <string>

#include "bench/io/model_loader.h"
#include "bench/io/output_files.h"
#include "bench/io/scenario_keys.h"
#include "bench/io/yaml_util.h"
#include "calib/common/errors.h"

namespace twin {
namespace {

// A criterion's keys: its table in bench/io/scenario_keys.cc (the scenario schema's source).
const YamlKeys kCriterionKeys = ScenarioKeyNames("acceptance_criterion");
// Top-level keys of the reports `twinbench run` writes (calibration, handclasp, workflow).
const std::vector<std::string> kTopLevel = {"scenario", "intrinsics", "robots", "timing_s",
                                            "base_frame", "status", "procedure",
    "truth_position_error_mm", "heldout", "identifiable_combinations", "tracker",
    "condition_number", "truth_position_error_mm_physical",
    "truth_position_error_mm_discovered_model", "truth_position_error_mm_covered_region",
    "diagnosis"};
// More criteria than this are no longer a CI verdict but a second report.
constexpr std::size_t kMaxCriteria = 100;

std::string Num(double v) {
  std::ostringstream os;
  os.precision(6);
  os << v;
  return os.str();
}

// A key path split into its components: keys, and array indices as "[i]" -> "i".
std::vector<std::string> SplitPath(const std::string& path) {
  std::vector<std::string> parts;
  std::string cur;
  for (char c : path) {
    if (c == '.' || c == '[') {
      if (!cur.empty()) parts.push_back(cur);
      cur.clear();
    } else if (c != ']') {
      cur += c;
    }
  }
  if (!cur.empty()) parts.push_back(cur);
  return parts;
}

// keys of [A-Za-z0-9_-] joined by '.', array items as [digits]: a.b[0].c, a.b.0.c
bool IsKeyPath(const std::string& p) {
  const auto key_char = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
  };
  std::size_t i = 0;
  bool need_key = true;
  while (i < p.size()) {
    if (need_key) {
      const std::size_t b = i;
      while (i < p.size() && key_char(p[i])) ++i;
      if (i == b) return false;
      need_key = false;
    } else if (p[i] == '.') {
      ++i;
      need_key = true;
    } else if (p[i] == '[') {
      const std::size_t b = ++i;
      while (i < p.size() && std::isdigit(static_cast<unsigned char>(p[i]))) ++i;
      if (i == b || i >= p.size() || p[i] != ']') return false;
      ++i;
    } else {
      return false;
    }
  }
  return !need_key;
}

bool IsIndex(const std::string& s) {
  return !s.empty() && s.size() < 10 &&
         s.find_first_not_of("0123456789") == std::string::npos;
}

std::string Keys(const nlohmann::json& j) {
  std::string out;
  int n = 0;
  for (const auto& [k, v] : j.items()) {
    if (++n > 20) return out + ", ...";
    out += (out.empty() ? "" : ", ") + k;
  }
  return out;
}

std::string XmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default:
        // XML 1.0 allows no control characters but tab, newline, carriage return.
        if (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n' && c != '\r') {
          out += '?';
        } else {
          out += c;
        }
    }
  }
  return out;
}

std::string DefaultName(const AcceptanceCriterion& c) {
  std::string n = c.figure;
  if (c.min) n += " >= " + Num(*c.min);
  if (c.min && c.max) n += " and";
  if (c.max) n += " <= " + Num(*c.max);
  return n;
}

}  // namespace

bool AcceptanceVerdict::passed() const {
  for (const CriterionResult& r : results) {
    if (!r.passed) return false;
  }
  return true;
}

Acceptance ParseAcceptance(const Scenario& sc) {
  Acceptance a;
  if (!IsPresent(sc.acceptance)) return a;
  const YamlReader r(sc.path);
  const YamlField& f = sc.acceptance;
  if (!f.node.IsSequence() || f.node.size() < 1 || f.node.size() > kMaxCriteria) {
    r.Fail(f, "expected a list of 1 to " + std::to_string(kMaxCriteria) +
                  " criteria {figure: <report.json key path>, max: <number>} (or min:), got " +
                  DescribeNode(f.node));
  }
  for (std::size_t i = 0; i < f.node.size(); ++i) {
    const YamlField item = f.Item(i);
    const YamlMap m(r, item, kCriterionKeys);
    AcceptanceCriterion c;
    c.where = r.Where(item);
    const YamlField figure = m.Get("figure");
    c.figure = r.String(figure);
    if (c.figure.size() > 500 || !IsKeyPath(c.figure)) {
      r.Fail(figure, "expected a report.json key path such as "
                     "robots.r2.truth_position_error_mm.rigid.after.rms (keys joined by '.', "
                     "array items as [i]), got '" + c.figure + "'");
    }
    const std::vector<std::string> parts = SplitPath(c.figure);
    if (std::find(kTopLevel.begin(), kTopLevel.end(), parts[0]) == kTopLevel.end()) {
      r.Fail(figure, "unknown report figure '" + c.figure + "': '" + parts[0] +
                         "' is not a top-level key of report.json (" + JoinNames(kTopLevel) + ")");
    }
    if (parts[0] == "robots" && parts.size() > 1 &&
        std::find(sc.robot_names.begin(), sc.robot_names.end(), parts[1]) ==
            sc.robot_names.end()) {
      r.Fail(figure, "unknown report figure '" + c.figure + "': '" + parts[1] +
                         "' is not a robot of the scenario (" + JoinNames(sc.robot_names) +
                         ")");
    }
    if (const auto v = m.Find("max", false)) c.max = r.Number(*v);
    if (const auto v = m.Find("min", false)) c.min = r.Number(*v);
    if (!c.max && !c.min) r.Fail(item, "expected a bound: max: <number> and/or min: <number>");
    if (c.max && c.min && *c.min > *c.max) {
      r.Fail(*m.Find("min", true), "min " + Num(*c.min) + " is above max " + Num(*c.max));
    }
    if (const auto v = m.Find("name", false)) {
      c.name = r.String(*v);
      if (c.name.empty() || c.name.size() > 200) {
        r.Fail(*v, "expected a test-case name of 1 to 200 characters");
      }
    }
    if (c.name.empty()) c.name = DefaultName(c);
    a.criteria.push_back(std::move(c));
  }
  return a;
}

Acceptance WithoutTruthCriteria(const Acceptance& acceptance, bool quiet) {
  Acceptance kept;
  // The figures a report without truth has as null or not at all: those against the truth (a
  // key with "truth" in it anywhere in the path, a "true" value, the count within 3 sigma of
  // the truth, the intrinsics' error_px, the identifiable combinations' rms_error and
  // max_error, a base frame's errors e_tran_mm and e_rot_deg (eq. 33-34) and their means, the
  // frames they are scored in, the coupled motion's tip-to-tip deviations, the pendant tips'
  // errors) and the twin's own settings (its simulated operator, its tracker noise).
  static const std::set<std::string> kAgainstTruth = {
      "e_tran_mm",    "e_rot_deg",        "mean_e_tran_mm",    "mean_e_rot_deg",
      "deviation_mm", "max_deviation_mm", "pendant_tip_error", "scoring_frame",
      "operator_error_mm"};
  const auto against_truth = [](const std::string& f) {
    const std::vector<std::string> parts = SplitPath(f);
    for (std::size_t i = 0; i < parts.size(); ++i) {
      const std::string& p = parts[i];
      const std::string parent = i > 0 ? parts[i - 1] : "";
      if (p.find("truth") != std::string::npos || p == "true" || kAgainstTruth.count(p) > 0 ||
          p.find("within_3_sigma") != std::string::npos) {
        return true;
      }
      if (parent == "intrinsics" && p == "error_px") return true;
      if (parent == "identifiable_combinations" && (p == "rms_error" || p == "max_error")) {
        return true;
      }
    }
    return f == "tracker.sigma_mm";
  };
  for (const AcceptanceCriterion& c : acceptance.criteria) {
    if (against_truth(c.figure)) {
      if (!quiet) {
        std::printf("acceptance: %s not judged: the cell has no truth (%s)\n", c.figure.c_str(),
                    c.where.c_str());
      }
      continue;
    }
    kept.criteria.push_back(c);
  }
  return kept;
}

nlohmann::json TruthUnavailableJson(const std::string& holds) {
  return {{"available", false},
          {"reason", "the cell offers no truth (a real cell, or serve-cell --no-truth): " + holds}};
}

AcceptanceVerdict EvaluateAcceptance(const Acceptance& acceptance, nlohmann::json* report) {
  AcceptanceVerdict verdict;
  nlohmann::json results = nlohmann::json::array();
  for (const AcceptanceCriterion& c : acceptance.criteria) {
    const nlohmann::json* node = report;
    std::string walked;
    for (const std::string& part : SplitPath(c.figure)) {
      const std::string here = walked.empty() ? "the report" : "'" + walked + "'";
      if (node->is_object()) {
        if (!node->contains(part)) {
          throw InputError(c.where + " figure",
                           "unknown report figure '" + c.figure + "': " + here +
                               " has no key '" + part + "' (it has: " + Keys(*node) + ")");
        }
        node = &(*node)[part];
      } else if (node->is_array()) {
        if (!IsIndex(part) || std::stoul(part) >= node->size()) {
          throw InputError(c.where + " figure",
                           "unknown report figure '" + c.figure + "': " + here + " is a list of " +
                               std::to_string(node->size()) + " items, no item '" + part + "'");
        }
        node = &(*node)[std::stoul(part)];
      } else {
        throw InputError(c.where + " figure", "unknown report figure '" + c.figure + "': " +
                                                  here + " is a value, it has no '" + part + "'");
      }
      walked += (walked.empty() ? "" : ".") + part;
    }
    CriterionResult res;
    res.criterion = c;
    // A NaN is written as null: no value either (the report is judged before it is written).
    if (node->is_null() || (node->is_number() && !std::isfinite(node->get<double>()))) {
      res.passed = false;
      res.message = c.figure + " has no value (null in the report: not computed)";
    } else if (node->is_number()) {
      const double v = node->get<double>();
      res.value = v;
      std::ostringstream m;
      m << c.figure << " = " << Num(v);
      res.passed = true;
      if (c.max && !(v <= *c.max)) {
        res.passed = false;
        m << " > max " << Num(*c.max) << " (over by " << Num(v - *c.max) << ")";
      } else if (c.min && !(v >= *c.min)) {
        res.passed = false;
        m << " < min " << Num(*c.min) << " (under by " << Num(*c.min - v) << ")";
      } else {
        if (c.max) m << " <= max " << Num(*c.max) << " (margin " << Num(*c.max - v) << ")";
        if (c.min) m << (c.max ? "," : "") << " >= min " << Num(*c.min) << " (margin "
                     << Num(v - *c.min) << ")";
      }
      res.message = m.str();
    } else {
      throw InputError(c.where + " figure",
                       "report figure '" + c.figure + "' is " +
                           (node->is_object() ? "a map (keys: " + Keys(*node) + ")"
                            : node->is_array() ? "a list of " + std::to_string(node->size()) +
                                                     " items"
                                               : "'" + node->dump() + "'") +
                           ", not a number");
    }
    nlohmann::json j = {{"figure", c.figure}, {"name", c.name}, {"passed", res.passed},
                        {"message", res.message}};
    j["value"] = res.value ? nlohmann::json(*res.value) : nlohmann::json(nullptr);
    if (c.max) j["max"] = *c.max;
    if (c.min) j["min"] = *c.min;
    results.push_back(j);
    verdict.results.push_back(std::move(res));
  }
  if (!acceptance.criteria.empty()) (*report)["acceptance"] = results;
  return verdict;
}

std::string JunitXml(const std::string& suite, const AcceptanceVerdict& verdict,
                     double time_s) {
  int failures = 0;
  for (const CriterionResult& r : verdict.results) failures += r.passed ? 0 : 1;
  const std::size_t tests = verdict.results.empty() ? 1 : verdict.results.size();
  const std::string cls = "twinbench." + XmlEscape(suite);
  std::ostringstream x;
  x << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n" << kWrittenByComment << "\n"
    << "<testsuites name=\"twinbench\" tests=\"" << tests << "\" failures=\"" << failures
    << "\" errors=\"0\" time=\"" << Num(time_s) << "\">\n"
    << "  <testsuite name=\"" << XmlEscape(suite) << "\" tests=\"" << tests << "\" failures=\""
    << failures << "\" errors=\"0\" skipped=\"0\" time=\"" << Num(time_s) << "\">\n";
  if (verdict.results.empty()) {
    x << "    <testcase classname=\"" << cls << "\" name=\"run\" time=\"" << Num(time_s)
      << "\"/>\n";
  }
  for (const CriterionResult& r : verdict.results) {
    x << "    <testcase classname=\"" << cls << "\" name=\"" << XmlEscape(r.criterion.name)
      << "\" time=\"0\">\n";
    if (!r.passed) {
      x << "      <failure type=\"acceptance\" message=\"" << XmlEscape(r.message) << "\">"
        << XmlEscape(r.criterion.where + ": " + r.message) << "</failure>\n";
    }
    x << "      <system-out>" << XmlEscape(r.message) << "</system-out>\n    </testcase>\n";
  }
  x << "  </testsuite>\n</testsuites>\n";
  return x.str();
}

void ValidateJunitFile(const std::string& path, const std::string& out_dir) {
  // Files of earlier versions carry no comment but their root element.
  ValidateOutputFile(path, "--junit", {kWrittenByComment, "<testsuites name=\"twinbench\""});
  if (!out_dir.empty() && PathIsWithin(path, out_dir)) {
    throw InputError("--junit", "'" + path + "' lies inside the output folder '" + out_dir +
                                    "', which the run replaces; write it beside the folder");
  }
}

void WriteJunit(const std::string& path, const std::string& suite,
                const AcceptanceVerdict& verdict, double time_s) {
  WriteFileAtomically(path, JunitXml(suite, verdict, time_s));
}

void PrintVerdict(const AcceptanceVerdict& verdict, std::ostream& out) {
  for (const CriterionResult& r : verdict.results) {
    out << "acceptance: " << (r.passed ? "passed " : "FAILED ") << r.message << "\n";
  }
  if (!verdict.results.empty() && !verdict.passed()) {
    int failed = 0;
    for (const CriterionResult& r : verdict.results) failed += r.passed ? 0 : 1;
    out << "acceptance: " << failed << " of " << verdict.results.size()
        << " criteria failed (exit code " << kExitAcceptanceFailed << ")\n";
  }
  out.flush();
}

void PrintVerdict(const AcceptanceVerdict& verdict) {
  std::fflush(stdout);
  PrintVerdict(verdict, std::cout);
}

int VerdictExitCode(const AcceptanceVerdict& verdict) {
  return verdict.passed() ? 0 : kExitAcceptanceFailed;
}

}  // namespace twin
