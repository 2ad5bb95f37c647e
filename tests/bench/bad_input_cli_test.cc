// Bad input never passes (issue 14, items 2-3): every class of malformed or absurd input found
// by the systematic test of ~840 cases exits 2 with `error: <file or option>: <what>`, within a
// bounded time, leaving nothing behind; interrupts remove the staging folder; a scenario's
// acceptance section gives exit 0 when met and 3 when missed, with a JUnit file.
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/bench/cli_run.h"
#include "tests/bench/text_edit.h"

namespace twin {
namespace {
namespace fs = std::filesystem;

using testing::ProcessRun;
using testing::ReadFile;
using testing::Replaced;
using testing::TwinbenchArgs;

const std::string kSource = TWIN_SOURCE_DIR;
const std::string kScenarios = kSource + "/scenarios/";

fs::path Fresh(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("twinbench_bad_input_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// A shipped scenario's text with its model paths made absolute, edited, written to dir/file.
std::string WriteScenario(const fs::path& dir, const std::string& file, const std::string& text) {
  const fs::path path = dir / file;
  std::ofstream(path) << testing::AbsoluteModels(text);
  return path.string();
}

// Exit 2 with an `error:` line that names `where` and says `what`, within the time limit.
void ExpectRefused(const ProcessRun& r, const std::string& where, const std::string& what) {
  EXPECT_FALSE(r.timed_out) << r.output;
  EXPECT_TRUE(r.exited) << "signal " << r.signal << ": " << r.output;
  EXPECT_EQ(r.code, 2) << r.output;
  const std::size_t at = r.output.find("error: ");
  ASSERT_NE(at, std::string::npos) << r.output;
  const std::string line = r.output.substr(at, r.output.find('\n', at) - at);
  EXPECT_NE(line.find(where), std::string::npos) << line;
  EXPECT_NE(line.find(what), std::string::npos) << line;
}

void ExpectNothingIn(const fs::path& out) {
  EXPECT_FALSE(fs::exists(out)) << out;
  EXPECT_FALSE(fs::exists(out.string() + ".partial")) << out;
  EXPECT_FALSE(fs::exists(out.string() + ".old")) << out;
}

TEST(BadInputCli, AbsurdScenarioValuesAreRefusedWithFileLineKeyAndLimit) {
  const fs::path dir = Fresh("scenario");
  const std::string demo = ReadFile(kScenarios + "twin_demo.yaml");
  struct Case {
    std::string from, to, key, limit;
  };
  const std::vector<Case> cases = {
      {"fx: 834.31", "fx: 1e-9", "scenario.fx", "fields of view"},
      {"fx: 834.31", "fx: 1e12", "scenario.fx", "fields of view"},
      {"square_mm: 20", "square_mm: 1000", "scenario.board.square_mm", "view at 2 m"},
      {"square_mm: 20", "square_mm: 0.001", "scenario.board.square_mm", "one pixel"},
      {"hand_eye: {xyz_mm: [0, 0, 50]", "hand_eye: {xyz_mm: [0, 0, -5]", "scenario.camera.hand_eye",
       "inside the flange"},
      {"mount: {xyz_mm: [0, 0, 40]", "mount: {xyz_mm: [5, 5, -3]", "scenario.board.mount",
       "inside the flange"},
      {"base_from_robot1: {xyz_mm: [1200", "base_from_robot1: {xyz_mm: [1e9",
       "scenario.robots[1].base_from_robot1", "a few metres"},
      // The intrinsics target: the board's checks, under its own name.
      {"  effects:\n", "  intrinsics_target: {squares: [14, 10], square_mm: 900}\n  effects:\n",
       "scenario.intrinsics_target.square_mm", "view at 2 m"},
      {"  effects:\n",
       "  intrinsics_target: {squares: [14, 10], square_mm: 20, mount: {xyz_mm: [5, 5, -3], "
       "rpy_deg: [0, 0, 0]}}\n  effects:\n",
       "scenario.intrinsics_target.mount", "inside the flange"},
  };
  for (const Case& c : cases) {
    const std::string text = Replaced(demo, c.from, c.to);
    const std::string path = WriteScenario(dir, "s.yaml", text);
    const ProcessRun r = TwinbenchArgs({"check", path}, 60);
    ExpectRefused(r, path + ":" + std::to_string(testing::LineOf(text, c.to)), c.limit);
    EXPECT_NE(r.output.find(c.key.substr(c.key.rfind('.') + 1)), std::string::npos) << r.output;
  }
  // Effects and physics: noise of 1e6 deg, a move that never ends.
  const std::string noisy = Replaced(demo, "effects:\n",
                                     "effects:\n    - {type: encoder_noise, sigma_deg: 1e6}\n");
  ExpectRefused(TwinbenchArgs({"check", WriteScenario(dir, "n.yaml", noisy)}, 60), "n.yaml",
                "sigma_deg");
  const std::string endless =
      Replaced(demo, "  effects:\n",
               "  physics: {max_steps: 1000000000, settle_speed_deg_s: 1e-300}\n  effects:\n");
  const ProcessRun e = TwinbenchArgs({"check", WriteScenario(dir, "e.yaml", endless)}, 60);
  ExpectRefused(e, "e.yaml:", "physics.");
  EXPECT_LT(e.seconds, 30.0);
}

TEST(BadInputCli, MalformedYamlSaysWhatIsWrong) {
  const fs::path dir = Fresh("yaml");
  const std::string text = Replaced(ReadFile(kScenarios + "twin_demo.yaml"), "name: twin_demo",
                                    "name: 'twin_demo");
  const std::string path = WriteScenario(dir, "q.yaml", text);
  ExpectRefused(TwinbenchArgs({"check", path}, 30), path + ":" +
                std::to_string(testing::LineOf(text, "'twin_demo")), "unclosed quote");
}

TEST(BadInputCli, ModelFilesAreBoundedAndPlausible) {
  const fs::path dir = Fresh("models");
  // A link of 1000 km.
  const std::string yaml = Replaced(ReadFile(kSource + "/models/reinovo_r1.yaml"), "a: 0.290",
                                    "a: 1.0e6");
  std::ofstream(dir / "far.yaml") << yaml;
  ExpectRefused(TwinbenchArgs({"info", (dir / "far.yaml").string()}, 30),
                (dir / "far.yaml").string() + ":" + std::to_string(testing::LineOf(yaml, "1.0e6")),
                "robot.links[1].a");
  // URDF: a negative mass, a mass that is text (urdfdom's reason in our message).
  const std::string urdf = ReadFile(kSource + "/models/reinovo_r1.urdf");
  std::ofstream(dir / "neg.urdf") << Replaced(urdf, "<mass value=\"7.5\"/>", "<mass value=\"-7.5\"/>");
  ExpectRefused(TwinbenchArgs({"info", (dir / "neg.urdf").string()}, 30), "neg.urdf:",
                "link 'link2' <mass value>");
  std::ofstream(dir / "text.urdf") << Replaced(urdf, "<mass value=\"7.5\"/>",
                                               "<mass value=\"heavy\"/>");
  ExpectRefused(TwinbenchArgs({"info", (dir / "text.urdf").string()}, 30), "text.urdf:",
                "urdfdom: Inertial: mass [heavy] is not a float");
  // A FIFO as the model: refused at once instead of blocking forever.
  const fs::path fifo = dir / "fifo.yaml";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const ProcessRun f = TwinbenchArgs({"info", fifo.string()}, 30);
  ExpectRefused(f, fifo.string(), "not a regular file");
  EXPECT_LT(f.seconds, 10.0);
  // A directory, a file over the limit.
  ExpectRefused(TwinbenchArgs({"info", dir.string() + "/x.yaml"}, 30), "x.yaml", "no such file");
  {
    std::ofstream big(dir / "big.yaml");
    big << "robot:\n";
    const std::string pad(1 << 16, '#');
    for (int k = 0; k < 80; ++k) big << pad << "\n";
  }
  ExpectRefused(TwinbenchArgs({"info", (dir / "big.yaml").string()}, 30), "big.yaml",
                "larger than the limit");
}

TEST(BadInputCli, OptionsAreCheckedBeforeAnythingRuns) {
  const std::string model = kSource + "/models/reinovo_r1.yaml";
  ExpectRefused(TwinbenchArgs({"fk", model, "--q", "0,0,0,0,0,0,"}, 30), "--q",
                "expected 6 comma-separated numbers");
  ExpectRefused(TwinbenchArgs({"fk", model, "--q", "0,nan,0,0,0,0"}, 30), "--q", "finite");
  ExpectRefused(TwinbenchArgs({"ik", model, "--xyz", "nan,0,0"}, 30), "--xyz", "finite");
  ExpectRefused(TwinbenchArgs({"ik", model, "--xyz", "1e300,0,0"}, 30), "--xyz", "10 m");
  ExpectRefused(TwinbenchArgs({"ik", model, "--xyz", "400,0,300", "--rpy", "1e9,0,0"}, 30),
                "--rpy", "periodic");
  const fs::path dir = Fresh("options");
  for (const std::vector<std::string>& args : std::vector<std::vector<std::string>>{
           {"run", kScenarios + "paper_reinovo.yaml", "--out", ""},
           {"render", kScenarios + "twin_demo.yaml", "--out", ""},
           {"run", kScenarios + "paper_reinovo.yaml", "--out", "/"},
           {"run", kScenarios + "paper_reinovo.yaml", "--out", "."},
           {"export-urdf", model, "--out", ""},
           {"export-urdf", model, "--out", dir.string()}}) {
    const ProcessRun r = TwinbenchArgs(args, 30, dir.string());
    ExpectRefused(r, "--out", "");
  }
  EXPECT_TRUE(fs::is_empty(dir)) << "something was written";
  const ProcessRun bad_flag = TwinbenchArgs({"info", model, "--frobnicate"}, 30);
  ExpectRefused(bad_flag, "command line", "frobnicate");
}

std::string MeasurementsHeader() {
  return "robot,camera_robot,axis,index,set,q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg,du_px,"
         "dv_px,depth_mm,offset_x_mm,offset_y_mm,offset_z_mm,frames,moves\n";
}

TEST(BadInputCli, MeasurementFilesAreBoundedAndNamesSanitised) {
  const fs::path dir = Fresh("measurements");
  const std::string model = kSource + "/models/reinovo_r2.yaml";
  const fs::path out = dir / "out";
  const auto identify = [&](const fs::path& csv, const std::vector<std::string>& extra = {}) {
    std::vector<std::string> args = {"identify", "--model", model, "--measurements", csv.string(),
                                     "--out", out.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    return TwinbenchArgs(args, 60, dir.string());
  };
  // 120,000 rows: refused at the limit, quickly, instead of exhausting memory.
  {
    std::ofstream f(dir / "many.csv");
    f << MeasurementsHeader();
    for (int k = 0; k < 120000; ++k) {
      f << "r2,r1," << k % 5 << "," << k << ",calibration,1,2,3,4,5,6,0,0,400,0,0,0,3,2\n";
    }
  }
  const ProcessRun many = identify(dir / "many.csv");
  ExpectRefused(many, "many.csv:100002", "more than 100000 measurement rows");
  EXPECT_LT(many.seconds, 20.0);
  ExpectNothingIn(out);
  // A huge axis index (each axis is an unknown line).
  {
    std::ofstream f(dir / "axis.csv");
    f << MeasurementsHeader() << "r2,r1,999999,0,calibration,1,2,3,4,5,6,0,0,400,0,0,0,3,2\n";
  }
  ExpectRefused(identify(dir / "axis.csv"), "axis.csv:2 axis", "below 1000");
  // A file beyond 64 MiB is refused before it is read (a sparse file: no 65 MiB written).
  {
    std::ofstream f(dir / "huge.csv");
    f << MeasurementsHeader();
  }
  fs::resize_file(dir / "huge.csv", (std::uintmax_t{65} << 20));
  ExpectRefused(identify(dir / "huge.csv"), "huge.csv", "larger than the limit");
  // Names that become file names: '../evil' from the option or the file is refused.
  {
    std::ofstream f(dir / "evil.csv");
    f << MeasurementsHeader() << "../evil,r1,0,0,calibration,1,2,3,4,5,6,0,0,400,0,0,0,3,2\n";
  }
  ExpectRefused(identify(dir / "evil.csv"), "evil.csv:2 robot", "'../evil'");
  ExpectRefused(identify(dir / "many.csv", {"--robot", "../evil"}), "--robot", "'../evil'");
  ExpectNothingIn(out);
  EXPECT_FALSE(fs::exists(dir / "identified_..")) << "escaped the output folder";
  for (const auto& e : fs::directory_iterator(dir)) {
    EXPECT_EQ(e.path().filename().string().find("evil.yaml"), std::string::npos) << e.path();
  }
}

// A one-trial handclasp of the paper's floor-floor set-up (a few seconds), with `extra` added
// to its handclasp section and `acceptance` as the scenario's acceptance section.
std::string Handclasp(const fs::path& dir, const std::string& file, const std::string& extra,
                      const std::string& acceptance = "") {
  std::string text = ReadFile(kScenarios + "gan2014_floor_floor.yaml");
  text = Replaced(text, "trials: 10", "trials: 1\n    coupled_motion: false" + extra);
  if (!acceptance.empty()) text += "  acceptance:\n" + acceptance;
  return WriteScenario(dir, file, text);
}

TEST(BadInputCli, RefusedProceduresExitTwoNamingTheScenarioAndWriteNothing) {
  const fs::path dir = Fresh("refused");
  // Points nobody can teach (2 m below the floor): the handclasp refuses at teaching.
  std::string text = ReadFile(kScenarios + "gan2014_floor_floor.yaml");
  text = Replaced(text, "points: auto",
                  "points: [[0, 0, -2000], [100, 0, -2000], [0, 100, -2000], [100, 100, -2000]]");
  text = Replaced(text, "trials: 10", "trials: 1");
  const std::string path = WriteScenario(dir, "unteachable.yaml", text);
  const fs::path out = dir / "out";
  const ProcessRun r = TwinbenchArgs({"run", path, "--out", out.string()}, 120);
  ExpectRefused(r, path, "the handclasp procedure refused in trial 1/1");
  EXPECT_NE(r.output.find("teaching"), std::string::npos) << r.output;
  ExpectNothingIn(out);
}

TEST(BadInputCli, AcceptanceGivesExitZeroOrThreeWithJunit) {
  const fs::path dir = Fresh("acceptance");
  const fs::path out = dir / "out", junit = dir / "verdict.xml";
  const std::string met = Handclasp(
      dir, "met.yaml", "", "    - {figure: base_frame.general.e_tran_mm, max: 100}\n"
                           "    - {figure: base_frame.taught_points.count, min: 4}\n");
  const ProcessRun ok = TwinbenchArgs(
      {"run", met, "--out", out.string(), "--junit", junit.string()}, 180);
  ASSERT_TRUE(ok.exited) << ok.output;
  EXPECT_EQ(ok.code, 0) << ok.output;
  EXPECT_NE(ok.output.find("acceptance: passed base_frame.general.e_tran_mm = "),
            std::string::npos) << ok.output;
  const std::string xml = ReadFile(junit.string());
  EXPECT_NE(xml.find("tests=\"2\" failures=\"0\""), std::string::npos) << xml;
  const nlohmann::json rep = nlohmann::json::parse(ReadFile((out / "report.json").string()));
  EXPECT_EQ(rep["acceptance"].size(), 2u);

  const std::string missed = Handclasp(
      dir, "missed.yaml", "", "    - {figure: base_frame.general.e_tran_mm, max: 0.001}\n"
                              "    - {figure: base_frame.taught_points.count, min: 4}\n");
  const ProcessRun fail = TwinbenchArgs(
      {"run", missed, "--out", out.string(), "--junit", junit.string()}, 180);
  ASSERT_TRUE(fail.exited) << fail.output;
  EXPECT_EQ(fail.code, 3) << fail.output;
  EXPECT_NE(fail.output.find("acceptance: FAILED base_frame.general.e_tran_mm = "),
            std::string::npos) << fail.output;
  EXPECT_NE(fail.output.find("> max 0.001 (over by "), std::string::npos) << fail.output;
  const std::string xml3 = ReadFile(junit.string());
  EXPECT_NE(xml3.find("tests=\"2\" failures=\"1\""), std::string::npos) << xml3;
  EXPECT_TRUE(fs::exists(out / "report.json"));  // the run itself completed

  // An unknown figure is bad input: exit 2, nothing written.
  fs::remove_all(out);
  fs::remove(junit);
  const std::string unknown = Handclasp(
      dir, "unknown.yaml", "", "    - {figure: base_frame.general.e_trans_mm, max: 1}\n");
  ExpectRefused(TwinbenchArgs({"run", unknown, "--out", out.string(), "--junit", junit.string()},
                              180),
                unknown, "has no key 'e_trans_mm'");
  ExpectNothingIn(out);
  EXPECT_FALSE(fs::exists(junit));
}

TEST(BadInputCli, InterruptsRemoveTheStagingFolder) {
  // A long run (the paper scenario), interrupted once its staging folder exists: the process
  // ends by the signal and leaves neither the staging folder nor the output.
  for (const int sig : {SIGINT, SIGTERM}) {
    const fs::path dir = Fresh("interrupt" + std::to_string(sig));
    const fs::path out = dir / "out";
    const ProcessRun r = TwinbenchArgs(
        {"run", kScenarios + "paper_reinovo.yaml", "--out", out.string()}, 120, dir.string(),
        [&](pid_t pid) {
          const auto t0 = std::chrono::steady_clock::now();
          while (!fs::exists(out.string() + ".partial") &&
                 std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60)) {
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
          }
          std::this_thread::sleep_for(std::chrono::milliseconds(300));
          kill(pid, sig);
        });
    EXPECT_FALSE(r.timed_out) << r.output;
    EXPECT_EQ(r.signal, sig) << "exited " << r.exited << " code " << r.code << ": " << r.output;
    ExpectNothingIn(out);
    EXPECT_FALSE(fs::exists(dir / "MUJOCO_LOG.TXT"));
  }
}

}  // namespace
}  // namespace twin
