#include "bench/report/scenario_schema.h"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "bench/io/calibration_config.h"
#include "bench/io/scenario.h"
#include "bench/io/scenario_keys.h"
#include "bench/report/acceptance.h"
#include "bench/runs/handclasp_run.h"
#include "bench/runs/tracker_run.h"
#include "calib/common/errors.h"
#include "cli_run.h"
#include "text_edit.h"

namespace twin {
namespace {

namespace fs = std::filesystem;
using testing::AbsoluteModels;
using testing::LineOf;
using testing::ReadFile;
using testing::Replaced;
using testing::Twinbench;

const std::string kRoot = TWIN_SOURCE_DIR;
const std::string kDemoPath = kRoot + "/scenarios/twin_demo.yaml";

// The demo scenario, edited, written to a temporary file of this test's own (ctest runs the
// tests side by side); returns its path.
std::string WriteScenario(const std::string& name, const std::string& text) {
  const std::string test = ::testing::UnitTest::GetInstance()->current_test_info()->name();
  const fs::path dir = fs::path(::testing::TempDir()) /
                       ("scenario_schema_test_" + test + "_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / (name + ".yaml")).string();
  std::ofstream(path) << text;
  return path;
}

std::string Demo() { return AbsoluteModels(ReadFile(kDemoPath)); }

// The what() of ValidateScenarioSchema's InputError for `text` ("" when it passes).
std::string SchemaError(const std::string& name, const std::string& text) {
  try {
    ValidateScenarioSchema(WriteScenario(name, text));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// The what() of the parser's InputError for `text` ("" when it parses).
std::string ParserError(const std::string& name, const std::string& text) {
  try {
    ParseScenario(text, name + ".yaml", kRoot + "/scenarios");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// A shipped scenario's text (models made absolute, so an edited copy can be written anywhere).
std::string Shipped(const std::string& name) {
  return AbsoluteModels(ReadFile(kRoot + "/scenarios/" + name + ".yaml"));
}

// The what() of the first InputError of the scenario parser and then of the procedure parsers
// of `text` (its calibration, handclasp, tracker_calibration and acceptance sections), as
// `twinbench check` runs them; "" when all parse.
std::string ProcedureError(const std::string& name, const std::string& text) {
  try {
    const Scenario sc = ParseScenario(text, name + ".yaml", kRoot + "/scenarios");
    if (IsPresent(sc.calibration)) ParseCalibrationConfig(sc);
    if (IsPresent(sc.handclasp)) ParseHandclaspConfig(sc);
    if (IsPresent(sc.tracker_calibration)) ValidateTrackerScenario(sc);
    ParseAcceptance(sc);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

::testing::AssertionResult Contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << text << "' lacks '" << part << "'";
}

TEST(ScenarioSchema, EveryShippedScenarioIsFormat2AndValid) {
  int n = 0;
  for (const auto& e : fs::recursive_directory_iterator(kRoot + "/scenarios")) {
    if (e.path().extension() != ".yaml") continue;
    ++n;
    EXPECT_NO_THROW(ValidateScenarioSchema(e.path().string())) << e.path();
    const YAML::Node root = YAML::LoadFile(e.path().string());
    EXPECT_EQ(ScenarioFormatOf(root, e.path().string()), kScenarioFormat) << e.path();
  }
  EXPECT_GE(n, 30);  // scenarios/ and scenarios/discovery/
}

// Each broken file is refused by the schema at the key that is wrong, with its line, and the
// parser refuses it too (the schema restates the parser's rules, it adds none).
TEST(ScenarioSchema, RefusesABrokenScenarioNamingTheKey) {
  const std::string demo = Demo();
  struct Case {
    std::string name, from, to, at, where, expected;  // at: text on the line named
  };
  const std::vector<Case> cases = {
      {"misspelled", "  camera:\n    robot: r1", "  camera:\n    robott: r1", "robott:",
       "scenario.camera.robott", "unknown key 'robott' (allowed: robot, hand_eye,"},
      {"wrong_type", "square_mm: 20", "square_mm: twenty", "twenty", "scenario.board.square_mm",
       "expected a number, got 'twenty'"},
      {"renamed", "  board:\n", "  boards:\n", "boards:", "scenario.boards",
       "unknown key 'boards'"},
      {"enum", "installation: floor", "installation: flor", "flor",
       "scenario.robots[0].installation", "expected one of floor, wall, ceiling, got 'flor'"},
      {"count", "resolution: [1024, 768]", "resolution: [1024]", "[1024]",
       "scenario.camera.resolution", "expected a sequence of 2 items, got a sequence of 1 items"},
      {"two_rotations", "hand_eye: {xyz_mm: [0, 0, 50], rpy_deg: [0, 0, 0]}",
       "hand_eye: {xyz_mm: [0, 0, 50], rpy_deg: [0, 0, 0], zyz_deg: [0, 0, 0]}",
       "rpy_deg: [0, 0, 0], zyz_deg", "scenario.camera.hand_eye",
       "expected exactly one of the keys rpy_deg, zyz_deg, got 2"},
      {"angle", "hand_eye: {xyz_mm: [0, 0, 50], rpy_deg: [0, 0, 0]}",
       "hand_eye: {xyz_mm: [0, 0, 50], rpy_deg: [0, 400, 0]}",
       "400", "scenario.camera.hand_eye.rpy_deg[1]", "expected a value <= 360, got 400"},
  };
  for (const Case& c : cases) {
    const std::string text = Replaced(demo, c.from, c.to);
    const std::string error = SchemaError(c.name, text);
    EXPECT_TRUE(Contains(error, ".yaml:" + std::to_string(LineOf(text, c.at)) + " " + c.where +
                                    ": "))
        << c.name;
    EXPECT_TRUE(Contains(error, c.expected)) << c.name;
    EXPECT_NE(ParserError(c.name, text), "") << c.name << ": the schema is stricter";
  }
}

// A broken procedure section (calibration:, handclasp:, tracker_calibration:, acceptance:).
struct ProcedureCase {
  std::string name, scenario, from, to, at, where, expected;  // at: text on the line named
};

// Issue 41: the procedure sections are checked by the schema key by key, not only as maps.
const std::vector<ProcedureCase>& ProcedureCases() {
  static const std::vector<ProcedureCase> cases = {
      {"planning_key", "paper_reinovo", "      swarm_size: 10", "      swarm_sise: 10",
       "swarm_sise:", "scenario.calibration.planning.swarm_sise",
       "unknown key 'swarm_sise' (allowed: axes, positions_per_axis, swarm_size, iterations,"},
      {"tracker_poses", "tracker_reinovo", "    poses: 100", "    poses: \"many\"", "\"many\"",
       "scenario.tracker_calibration.poses", "expected a whole number, got 'many'"},
      {"handclasp_key", "gan2014_floor_floor", "    constraint: auto\n",
       "    constraint: auto\n    opertor_error_mm: 1\n", "opertor_error_mm",
       "scenario.handclasp.opertor_error_mm",
       "unknown key 'opertor_error_mm' (allowed: rough_base_from_robot1, tips, points, "
       "operator_error_mm, constraint,"},
      {"criterion_figure", "paper_reinovo",
       "- {figure: robots.r2.misaligned_error_mm.validation.after, max: 0.05}",
       "- {max: 0.05}", "{max: 0.05}", "scenario.acceptance[0]",
       "missing required key 'figure'"},
  };
  return cases;
}

TEST(ScenarioSchema, RefusesABrokenProcedureSectionNamingTheKey) {
  std::vector<ProcedureCase> cases = ProcedureCases();
  const std::vector<ProcedureCase> more = {
      {"points_word", "gan2014_floor_floor", "points: auto", "points: many", "many",
       "scenario.handclasp.points", "expected one of auto, got 'many'"},
      {"points_short", "gan2014_floor_floor", "points: auto",
       "points: [[0, 0, 0], [100, 0, 0], [0, 100, 0], [0, 0]]", "points:",
       "scenario.handclasp.points[3]", "expected a sequence of 3 items, got a sequence of 2"},
      {"points_few", "gan2014_floor_floor", "points: auto", "points: [[0, 0, 0]]", "points:",
       "scenario.handclasp.points", "expected a sequence of at least 4 items"},
      {"constraint", "gan2014_floor_floor", "constraint: auto", "constraint: floor",
       "constraint: floor",
       "scenario.handclasp.constraint", "expected one of auto, general, floor_floor,"},
      {"criterion_bound", "paper_reinovo",
       "- {figure: robots.r2.misaligned_error_mm.validation.after, max: 0.05}",
       "- {figure: robots.r2.misaligned_error_mm.validation.after}", "- {figure: robots.r2",
       "scenario.acceptance[0]", "expected at least one of the keys max, min, got none"},
      {"odd_squares", "paper_reinovo", "board_squares: [4, 4]", "board_squares: [5, 4]",
       "board_squares:", "scenario.calibration.board_squares[0]",
       "expected a multiple of 2, got 5"},
      {"servo_gain", "paper_reinovo", "gain: 1.0", "gain: 3", "gain: 3",
       "scenario.calibration.servo.gain", "expected a value <= 2, got 3"},
      {"payload_type", "tracker_reinovo", "payload: {mass_kg: 0.2,", "payload: {mass_kg: [0.2],",
       "payload:", "scenario.tracker_calibration.payload.mass_kg", "expected a number"},
  };
  cases.insert(cases.end(), more.begin(), more.end());
  for (const ProcedureCase& c : cases) {
    const std::string text = Replaced(Shipped(c.scenario), c.from, c.to);
    const std::string error = SchemaError(c.name, text);
    EXPECT_TRUE(Contains(error, ".yaml:" + std::to_string(LineOf(text, c.at)) + " " + c.where +
                                    ": "))
        << c.name;
    EXPECT_TRUE(Contains(error, c.expected)) << c.name;
    // The parsers refuse it too, at the same key (the schema adds no rule of its own).
    EXPECT_TRUE(Contains(ProcedureError(c.name, text), " " + c.where + ": ")) << c.name;
  }
  // The unshipped edits parse: the shipped scenarios are what the cases break.
  for (const char* name : {"paper_reinovo", "tracker_reinovo", "gan2014_floor_floor"}) {
    EXPECT_EQ(ProcedureError(name, Shipped(name)), "") << name;
  }
}

// Values the schema must keep accepting because the parsers accept them: a list of points, a
// criterion with only min, a bound at its limit.
TEST(ScenarioSchema, AcceptsWhatTheProcedureParsersAccept) {
  const std::vector<std::pair<std::string, std::string>> edits = {
      {"gan2014_floor_floor", "points: [[400, 0, 300], [400, 200, 300], [600, 0, 300], "
                              "[600, 200, 500]]"},
      {"paper_reinovo", "gain: 2"},
      {"paper_reinovo", "board_squares: [30, 2]"},
  };
  const std::vector<std::string> from = {"points: auto", "gain: 1.0", "board_squares: [4, 4]"};
  for (std::size_t i = 0; i < edits.size(); ++i) {
    const std::string text = Replaced(Shipped(edits[i].first), from[i], edits[i].second);
    EXPECT_EQ(SchemaError("accepted", text), "") << edits[i].second;
  }
  const std::string min_only = Replaced(
      Shipped("paper_reinovo"), "- {figure: robots.r2.misaligned_error_mm.validation.after, "
                                "max: 0.05}",
      "- {figure: robots.r2.misaligned_error_mm.validation.after, min: 0, name: r2 after}");
  EXPECT_EQ(SchemaError("min_only", min_only), "");
  EXPECT_EQ(ProcedureError("min_only", min_only), "");
}

// The tables drive the procedure parsers: removing a key the shipped scenarios write is
// "missing required key" from the parser exactly where the table says it is required.
TEST(ScenarioSchema, TheProcedureParsersRequireWhatTheTablesRequire) {
  struct Where {
    std::string scenario, section;
    std::vector<std::string> node_path;  // keys and, for "0", a sequence's first item
  };
  const std::vector<Where> places = {
      {"paper_reinovo", "calibration", {"scenario", "calibration"}},
      {"paper_reinovo", "calibration_target", {"scenario", "calibration", "intrinsics_target"}},
      {"paper_reinovo", "calibration_planning", {"scenario", "calibration", "planning"}},
      {"paper_reinovo", "calibration_servo", {"scenario", "calibration", "servo"}},
      {"paper_reinovo", "calibration_scoring", {"scenario", "calibration", "scoring"}},
      {"paper_reinovo", "acceptance_criterion", {"scenario", "acceptance", "0"}},
      {"gan2014_floor_floor", "handclasp", {"scenario", "handclasp"}},
      {"tracker_reinovo", "tracker_calibration", {"scenario", "tracker_calibration"}},
      {"tracker_reinovo", "tracker_payload", {"scenario", "tracker_calibration", "payload"}}};
  int tried = 0, required = 0;
  for (const Where& w : places) {
    const YAML::Node original = YAML::Load(Shipped(w.scenario));
    for (const ScenarioKey& k : ScenarioSectionNamed(w.section).keys) {
      YAML::Node copy = YAML::Clone(original);
      YAML::Node node = copy;
      for (const std::string& p : w.node_path) node.reset(p == "0" ? node[0] : node[p]);
      if (!node[k.key]) continue;
      node.remove(k.key);
      ++tried;
      const std::string error = ProcedureError("removed", YAML::Dump(copy));
      const std::string missing = "missing required key '" + k.key + "'";
      if (k.required) {
        ++required;
        EXPECT_TRUE(Contains(error, missing)) << w.section << "." << k.key;
      } else {  // it may break a rule across keys (calibration_axes > the default axes)
        EXPECT_FALSE(Contains(error, missing)) << w.section << "." << k.key;
      }
    }
  }
  EXPECT_GE(tried, 40);
  EXPECT_GE(required, 10);
}

TEST(ScenarioSchema, Format2TakesQuotedNumbersAsStringsFormat1AsTheParserDoes) {
  const std::string quoted = Replaced(Demo(), "square_mm: 20", "square_mm: \"20\"");
  EXPECT_TRUE(Contains(SchemaError("quoted2", quoted),
                       "scenario.board.square_mm: expected a number, got '20'"));
  const std::string v1 = Replaced(quoted, "format: 2", "");
  EXPECT_EQ(SchemaError("quoted1", v1), "");
  EXPECT_EQ(ParserError("quoted1", v1), "");  // format 1: as the parser has always read it
  const std::string name_v2 = Replaced(Demo(), "name: r1", "name: 12");
  EXPECT_TRUE(Contains(SchemaError("name2", name_v2), "expected a string, got 12"));
}

TEST(ScenarioSchema, ANewerFormatIsRefusedNamingTheVersions) {
  const std::string v3 = Replaced(Demo(), "format: 2", "format: 3\n  new_key: 1");
  for (const std::string& error : {SchemaError("v3", v3), ParserError("v3", v3)}) {
    EXPECT_TRUE(Contains(error, "v3.yaml:")) << error;
    EXPECT_TRUE(Contains(error, "scenario.format: scenario format 3 is newer than this "
                                "twinbench knows (newest: 2)"));
  }
  const std::string v0 = Replaced(Demo(), "format: 2", "format: 0");
  EXPECT_TRUE(Contains(ParserError("v0", v0), "expected a scenario format version >= 1"));
  EXPECT_EQ(ParseScenario(Replaced(Demo(), "format: 2", ""), "v1.yaml", "").format, 1);
  EXPECT_EQ(ParseScenario(Demo(), "v2.yaml", "").format, 2);
}

// The tables drive the parser: every key of a section the demo writes is required by the
// parser exactly where the table says so (removing an optional key still parses).
TEST(ScenarioSchema, TheParserRequiresWhatTheTablesRequire) {
  const YAML::Node demo = YAML::Load(Demo());
  struct Where {
    std::string section;
    std::vector<std::string> node_path;  // keys and, for "0"/"1", sequence items
  };
  const std::vector<Where> places = {{"scenario", {"scenario"}},
                                     {"camera", {"scenario", "camera"}},
                                     {"board", {"scenario", "board"}},
                                     {"robot1", {"scenario", "robots", "0"}},
                                     {"robot2", {"scenario", "robots", "1"}}};
  int tried = 0;
  for (const Where& w : places) {
    for (const ScenarioKey& k : ScenarioSectionNamed(w.section).keys) {
      YAML::Node copy = YAML::Clone(demo);
      YAML::Node node = copy;
      for (const std::string& p : w.node_path) {
        node.reset(p == "0" || p == "1" ? node[std::stoi(p)] : node[p]);
      }
      if (!node[k.key]) continue;
      node.remove(k.key);
      ++tried;
      const std::string error = ParserError("removed", YAML::Dump(copy));
      // The demo has two robots: what two robots require is required.
      if (k.required || k.required_with_robots == 2) {
        EXPECT_TRUE(Contains(error, "missing required key '" + k.key + "'")) << w.section;
      } else {
        EXPECT_EQ(error, "") << w.section << "." << k.key << " is optional in the table";
      }
    }
  }
  EXPECT_GE(tried, 25);
}

// The tables' robot counts drive the parser too: in the one-robot cell
// (scenarios/tracker_single_reinovo.yaml) every key allowed only with two robots is refused at
// its key, and every key required with one robot is required (the schema leaves both to the
// parser: draft-07 conditions are beyond it, and the descriptions say so).
TEST(ScenarioSchema, TheParserFollowsTheTablesRobotCounts) {
  const std::string single = AbsoluteModels(
      ReadFile(std::string(TWIN_SOURCE_DIR) + "/scenarios/tracker_single_reinovo.yaml"));
  const nlohmann::ordered_json properties =
      ScenarioSchema()["definitions"]["scenario"]["properties"];
  EXPECT_EQ(ParserError("single", single), "");
  int only = 0, required = 0;
  for (const ScenarioKey& k : ScenarioSectionNamed("scenario").keys) {
    if (k.only_with_robots == 2) {
      ++only;
      const std::string error = ParserError(
          "added", Replaced(single, "  effects:\n", "  " + k.key + ": {}\n  effects:\n"));
      EXPECT_TRUE(Contains(error, "scenario." + k.key + ": is not allowed with one robot"))
          << k.key << ": " << error;
      EXPECT_TRUE(Contains(properties[k.key]["description"].get<std::string>(),
                           "only with two robots"))
          << k.key;
    }
    if (k.required_with_robots == 1) {
      ++required;
      YAML::Node copy = YAML::Load(single);
      copy["scenario"].remove(k.key);
      EXPECT_TRUE(Contains(ParserError("removed", YAML::Dump(copy)), "lists one robot"))
          << k.key;
    }
  }
  EXPECT_EQ(only, 5);      // camera, board, intrinsics_target, calibration, handclasp
  EXPECT_EQ(required, 1);  // tracker_calibration
}

TEST(ScenarioSchema, IsDraft07WithADefinitionPerSection) {
  const nlohmann::ordered_json schema = ScenarioSchema();
  EXPECT_EQ(schema["$schema"], "http://json-schema.org/draft-07/schema#");
  EXPECT_EQ(schema["additionalProperties"], false);
  for (std::size_t i = 1; i < ScenarioSections().size(); ++i) {
    EXPECT_TRUE(schema["definitions"].contains(ScenarioSections()[i].name));
  }
  const auto& format = schema["definitions"]["scenario"]["properties"]["format"];
  EXPECT_EQ(format["maximum"], kScenarioFormat);
  EXPECT_TRUE(Contains(format["description"].get<std::string>(), "format version"));
}

TEST(ScenarioSchema, YamlToJsonTypesScalarsAndKeepsMarks) {
  std::map<std::string, YAML::Mark> marks;
  const auto j = YamlToJson(YAML::Load("a: 1\nb: 2.5\nc: yes\nd: \"3\"\ne: [x, ~]\nf: 1e5\n"),
                            true, &marks);
  EXPECT_EQ(j.dump(), R"({"a":1,"b":2.5,"c":true,"d":"3","e":["x",null],"f":100000.0})");
  EXPECT_EQ(YamlToJson(YAML::Load("d: \"3\""), false).dump(), R"({"d":3})");
  EXPECT_EQ(marks.at("e[1]").line, 4);
  EXPECT_EQ(YamlToJson(YAML::Load("x: .inf"), false).dump(), R"({"x":".inf"})");
}

// The CLI: `check` reports a violation as one line, exit 2; a format-1 file passes with one
// notice line saying what format 2 changed; a newer one is refused.
TEST(ScenarioSchemaCli, CheckReportsOneLineAndTheFormatNotice) {
  const std::string bad =
      WriteScenario("cli_bad", Replaced(Demo(), "square_mm: 20", "square_mm: twenty"));
  const auto r = Twinbench("check " + bad);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.output.rfind("error: " + bad + ":", 0), 0u) << r.output;
  EXPECT_TRUE(Contains(r.output, " scenario.board.square_mm: expected a number, got 'twenty'\n"));
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;

  const std::string v1 = WriteScenario("cli_v1", Replaced(Demo(), "format: 2", ""));
  const auto old = Twinbench("check " + v1);
  EXPECT_EQ(old.code, 0) << old.output;
  EXPECT_TRUE(Contains(old.output, "notice: " + v1 + ": scenario format 1 (no scenario.format); "
                                   "format 2 adds `format: 2`"));
  const auto v2 = Twinbench("check " + WriteScenario("cli_v2", Demo()));
  EXPECT_EQ(v2.code, 0) << v2.output;
  EXPECT_FALSE(Contains(v2.output, "notice:"));

  const std::string v9 = WriteScenario("cli_v9", Replaced(Demo(), "format: 2", "format: 9"));
  const auto newer = Twinbench("check " + v9);
  EXPECT_EQ(newer.code, 2);
  EXPECT_TRUE(Contains(newer.output, "error: " + v9 + ":"));
  EXPECT_TRUE(Contains(newer.output, "scenario format 9 is newer than this twinbench knows "
                                     "(newest: 2)"));
}

// Issue 41: `twinbench check` refuses a broken procedure section in one line naming the key.
TEST(ScenarioSchemaCli, CheckRefusesABrokenProcedureSectionNamingTheKeyPath) {
  for (const ProcedureCase& c : ProcedureCases()) {
    const std::string text = Replaced(Shipped(c.scenario), c.from, c.to);
    const std::string path = WriteScenario("cli_" + c.name, text);
    const auto r = Twinbench("check " + path);
    EXPECT_EQ(r.code, 2) << c.name << ": " << r.output;
    const std::string head =
        "error: " + path + ":" + std::to_string(LineOf(text, c.at)) + " " + c.where + ": ";
    EXPECT_EQ(r.output.rfind(head, 0), 0u) << c.name << ": " << r.output;
    EXPECT_TRUE(Contains(r.output, head + c.expected)) << c.name;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  }
}

TEST(ScenarioSchemaCli, SchemaVerbWritesTheGeneratedSchema) {
  const auto r = Twinbench("schema");
  EXPECT_EQ(r.code, 0);
  EXPECT_EQ(r.output, ScenarioSchema().dump(2) + "\n");
  const std::string out = (fs::path(::testing::TempDir()) / "schema_out.json").string();
  fs::remove(out);
  EXPECT_EQ(Twinbench("schema --out " + out).code, 0);
  EXPECT_EQ(ReadFile(out), r.output);
  const std::string other = WriteScenario("not_a_schema", "x: 1\n");
  EXPECT_EQ(Twinbench("schema --out " + other).code, 2);  // not written over
  EXPECT_EQ(ReadFile(other), "x: 1\n");
}

}  // namespace
}  // namespace twin
