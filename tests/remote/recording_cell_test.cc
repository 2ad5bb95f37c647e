// RecordingCell (bench/runs/recording_cell.h) over a small fake BenchCell: one line per call,
// in order, the responses as the inner cell returned them; and the same calls played back by
// ReplayCell (bench/runs/replay_cell.h), which answers them bit for bit and refuses a call that
// differs from the recorded one.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "bench/runs/recording_cell.h"
#include "bench/runs/replay_cell.h"
#include "calib/common/errors.h"

namespace twin {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// A cell whose answers are made up and distinct per call; it counts the calls.
class FakeCell : public BenchCell {
 public:
  MoveResult MoveTo(int robot, const JointVector& q) override {
    ++calls;
    MoveResult r;
    if (robot == 1) {
      r.status = MoveStatus::kCollision;
      r.reason = "link 3 hit the table {\"quoted\"}";
    }
    r.duration_s = 0.1 * q.size() + 1.0 / 3.0;
    return r;
  }
  JointVector ReadEncoders(int robot) override {
    ++calls;
    JointVector q(6);
    for (int i = 0; i < 6; ++i) q(i) = std::sqrt(2.0) * (i + 1) - robot - 0.0;
    q(5) = -0.0;  // the sign of zero survives the recording
    return q;
  }
  cv::Mat GrabImage() override {
    ++calls;
    cv::Mat image(12, 16, CV_8UC3);
    for (int r = 0; r < image.rows; ++r) {
      for (int c = 0; c < image.cols; ++c) {
        image.at<cv::Vec3b>(r, c) = cv::Vec3b(static_cast<uchar>(7 * r + c),
                                              static_cast<uchar>(200 - r * c), 42);
      }
    }
    images.push_back(image.clone());
    return image;
  }
  cv::Mat GrabImageRegion(const cv::Rect& roi) override {
    ++calls;
    if (roi.x > 100) return cv::Mat();  // misses the frame
    cv::Mat image(roi.height, roi.width, CV_8UC3, cv::Scalar(1, 2, 3));
    images.push_back(image.clone());
    return image;
  }
  MoveResult ExchangeTools() override {
    ++calls;
    return MoveResult{MoveStatus::kNotSettled, "operator did not confirm", 2.5};
  }
  int CameraRobot() override {
    ++calls;
    return 1;
  }
  double ClockSeconds() override {
    ++calls;
    return 12.345678901234567;
  }
  double ReadTemperatureC(int) override {
    ++calls;
    return std::numeric_limits<double>::quiet_NaN();  // no sensor
  }
  TrackerReading MeasureTracker(int robot) override {
    ++calls;
    TrackerReading r;
    r.status = TrackerStatus::kOk;
    r.p_T = Vector3(1.0 / 7.0, -2.0 / 9.0, 3.0 + robot);
    r.time_s = 99.5;
    return r;
  }
  TwinTruth Truth() override {
    ++calls;
    TwinTruth t;
    t.num_robots = 2;
    for (int r = 0; r < kMaxRobots; ++r) {
      t.models[r] = KinematicModel(6);
      t.X_WB[r] = Transform::Identity();
      t.X_WB[r].translation() = Vector3(0.1 * r, 1.0 / 3.0, 0);
      t.X_WF[r] = Transform::Identity();
      t.q_link[r] = JointVector::Constant(6, 0.5);
      t.q_motor[r] = JointVector::Constant(6, 0.25);
      t.p_WTip[r] = Vector3(1, 2, 3);
    }
    t.X_WC = Transform::Identity();
    t.X_WT = Transform::Identity();
    t.time_s = 7.0;
    return t;
  }
  int calls = 0;
  std::vector<cv::Mat> images;  ///< every image returned, in order
};

fs::path TempDir(const std::string& name) {
  const fs::path base = fs::temp_directory_path() /
                        ("twinbench_recording_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(base);
  fs::create_directories(base);
  return base;
}

std::vector<json> Lines(const fs::path& file) {
  std::ifstream in(file);
  std::vector<json> lines;
  std::string line;
  while (std::getline(in, line)) lines.push_back(json::parse(line));
  return lines;
}

JointVector TestJoints() {
  JointVector q(6);
  q << 0.1, -0.2, 1.0 / 3.0, -0.0, 2.718281828459045, -3.141592653589793;
  return q;
}

// The calls of the tests, on any cell; the results in order, as text that shows every bit.
std::vector<std::string> DriveCell(BenchCell& cell) {
  std::vector<std::string> out;
  auto bits = [](double v) {
    std::ostringstream os;
    os << std::hexfloat << v;
    return os.str();
  };
  const MoveResult m0 = cell.MoveTo(0, TestJoints());
  out.push_back(std::string(ToString(m0.status)) + m0.reason + bits(m0.duration_s));
  const MoveResult m1 = cell.MoveTo(1, TestJoints());
  out.push_back(std::string(ToString(m1.status)) + m1.reason + bits(m1.duration_s));
  const JointVector q = cell.ReadEncoders(1);
  std::string qs;
  for (int i = 0; i < q.size(); ++i) qs += bits(q(i)) + " ";
  out.push_back(qs);
  const cv::Mat image = cell.GrabImage();
  out.push_back(std::to_string(image.cols) + "x" + std::to_string(image.rows) + " " +
                std::to_string(cv::sum(image)[0]) + " " + std::to_string(cv::sum(image)[2]));
  const cv::Mat region = cell.GrabImageRegion(cv::Rect(4, 5, 6, 3));
  out.push_back(std::to_string(region.cols) + "x" + std::to_string(region.rows) + " " +
                std::to_string(cv::sum(region)[1]));
  out.push_back(std::to_string(cell.GrabImageRegion(cv::Rect(500, 5, 6, 3)).empty()));
  const MoveResult x = cell.ExchangeTools();
  out.push_back(std::string(ToString(x.status)) + x.reason + bits(x.duration_s));
  out.push_back(std::to_string(cell.CameraRobot()));
  out.push_back(bits(cell.ClockSeconds()));
  out.push_back(std::to_string(std::isnan(cell.ReadTemperatureC(0))));
  const TrackerReading t = cell.MeasureTracker(1);
  out.push_back(std::string(ToString(t.status)) + bits(t.p_T.x()) + bits(t.p_T.y()) +
                bits(t.p_T.z()) + bits(t.time_s));
  const TwinTruth truth = cell.Truth();
  out.push_back(bits(truth.time_s) + bits(truth.X_WB[1].translation().y()) +
                bits(truth.q_motor[1](3)));
  cell.Finish();
  return out;
}

TEST(RecordingCell, OneLinePerCallInOrderWithTheResponsesAsReturned) {
  const fs::path base = TempDir("lines");
  auto fake = std::make_unique<FakeCell>();
  FakeCell& inner = *fake;
  RecordingManifest manifest;
  manifest.scenario_path = "scenarios/x.yaml";
  manifest.scenario_text = "scenario:\n  name: x\n";
  manifest.trial = 3;
  RecordingCell cell(std::move(fake), (base / "R").string(), manifest);
  FakeCell direct;
  const std::vector<std::string> live = DriveCell(cell);
  EXPECT_EQ(live, DriveCell(direct));  // the recording cell passes everything on unchanged
  EXPECT_EQ(inner.calls, 12);
  EXPECT_EQ(cell.exchanges(), 12);

  const std::vector<json> lines = Lines(base / "R" / "exchanges.jsonl");
  ASSERT_EQ(lines.size(), 12u);
  const std::vector<std::string> methods = {
      "MoveTo",    "MoveTo",    "ReadEncoders", "GrabImage", "GrabImage",      "GrabImage",
      "ExchangeTools", "CameraRobot", "ReadClock", "ReadTemperature", "MeasureTracker", "Truth"};
  for (size_t i = 0; i < methods.size(); ++i) {
    EXPECT_EQ(lines[i]["seq"], i + 1);
    EXPECT_EQ(lines[i]["method"], methods[i]) << i;
    EXPECT_TRUE(lines[i]["t_wall_s"].is_number());
    EXPECT_FALSE(lines[i]["request"].contains("session_id"));
  }
  // The request and response as the protocol's JSON, exact.
  EXPECT_EQ(lines[0]["request"]["q_target_rad"][2].get<double>(), 1.0 / 3.0);
  EXPECT_FALSE(lines[0]["request"].contains("robot"));  // 0: a default, left out
  EXPECT_EQ(lines[1]["request"]["robot"], 1);
  EXPECT_EQ(lines[1]["response"]["status"], "MOVE_STATUS_COLLISION");
  EXPECT_EQ(lines[1]["response"]["reason"], "link 3 hit the table {\"quoted\"}");
  EXPECT_EQ(lines[2]["response"]["q_rad"][0].get<double>(), std::sqrt(2.0) - 1);
  // Images: the PNG beside the line, which decodes to the very pixels returned.
  EXPECT_EQ(lines[3]["response"]["image_file"], "images/000004.png");
  EXPECT_FALSE(lines[3]["response"].contains("data"));
  EXPECT_EQ(lines[3]["response"]["width_px"], 16);
  const cv::Mat png = cv::imread((base / "R" / "images" / "000004.png").string());
  ASSERT_FALSE(png.empty());
  ASSERT_EQ(inner.images.size(), 2u);
  EXPECT_EQ(cv::norm(png, inner.images[0], cv::NORM_INF), 0);
  EXPECT_TRUE(fs::exists(base / "R" / "images" / "000005.png"));
  EXPECT_FALSE(fs::exists(base / "R" / "images" / "000006.png"));
  EXPECT_EQ(lines[4]["response"]["x_px"], 4);
  EXPECT_EQ(lines[4]["request"]["region"]["height_px"], 3);
  EXPECT_FALSE(lines[5]["response"].contains("image_file"));  // a region that missed
  EXPECT_EQ(lines[8]["response"]["time_s"].get<double>(), 12.345678901234567);
  EXPECT_FALSE(lines[9]["response"].contains("has_sensor"));  // false: no sensor
  EXPECT_EQ(lines[10]["response"]["x_m"].get<double>(), 1.0 / 7.0);
  EXPECT_EQ(lines[11]["response"]["time_s"].get<double>(), 7.0);

  // recording.json: complete once the run finished.
  std::ifstream in(base / "R" / "recording.json");
  const json m = json::parse(in);
  EXPECT_EQ(m["format"], "twinbench-cell-recording");
  EXPECT_EQ(m["version"], 1);
  EXPECT_EQ(m["protocol"], "twinbench.cell.v1");
  EXPECT_EQ(m["complete"], true);
  EXPECT_EQ(m["exchanges"], 12);
  EXPECT_EQ(m["trial"], 3);
  EXPECT_EQ(m["scenario"]["content"], manifest.scenario_text);
  fs::remove_all(base);
}

TEST(RecordingCell, ReplayAnswersTheSameBitsAndRefusesAnotherCall) {
  const fs::path base = TempDir("replay");
  std::vector<std::string> live;
  {
    RecordingCell cell(std::make_unique<FakeCell>(), (base / "R").string(), RecordingManifest());
    live = DriveCell(cell);
  }
  ReplayCell replay((base / "R").string());
  EXPECT_EQ(DriveCell(replay), live);
  EXPECT_EQ(replay.used(), replay.recorded());

  // Another robot than recorded: refused, naming the line and both calls.
  ReplayCell other((base / "R").string());
  try {
    other.MoveTo(1, TestJoints());
    FAIL() << "a different call was answered";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("exchanges.jsonl:1 (seq 1)"), std::string::npos) << what;
    EXPECT_NE(what.find("MoveTo {\"robot\":1"), std::string::npos) << what;
    EXPECT_NE(what.find("diverged"), std::string::npos) << what;
  }
  // A replay that stops early: Finish says where.
  ReplayCell early((base / "R").string());
  early.MoveTo(0, TestJoints());
  try {
    early.Finish();
    FAIL() << "an unfinished replay passed";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("the replay ended at seq 1 of 12"), std::string::npos)
        << e.what();
  }
  fs::remove_all(base);
}

TEST(RecordingCell, RefusesAFolderThatExists) {
  const fs::path base = TempDir("exists");
  fs::create_directories(base / "R");
  EXPECT_THROW(RecordingCell(std::make_unique<FakeCell>(), (base / "R").string(),
                             RecordingManifest()),
               InputError);
  EXPECT_TRUE(fs::is_empty(base / "R"));
  fs::remove_all(base);
}

}  // namespace
}  // namespace twin

namespace twin {
namespace {

// An exchange's image_file names a file of the recording's images/ folder: a path out of it (a
// tampered or hostile recording) is refused naming the line, and never read.
TEST(RecordingFile, ImageFileOutsideTheImagesFolderIsRefused) {
  const auto line = [](const std::string& image_file) {
    return R"({"seq":1,"method":"GrabImage","request":{},"response":{"width_px":2,"image_file":")" +
           image_file + R"("}})";
  };
  EXPECT_EQ(ParseRecordedExchangeLine(line("images/000001.png"), "x:1").image_file,
            "images/000001.png");
  for (const char* bad : {"../secret.png", "/etc/passwd", "images/../../x.png", "images/",
                          "images/..", "images/a/b.png", "other/000001.png", "images\\\\..\\\\x"}) {
    try {
      ParseRecordedExchangeLine(line(bad), "x:1");
      ADD_FAILURE() << bad << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("images/ folder"), std::string::npos) << e.what();
      EXPECT_EQ(e.where(), "x:1");
    }
  }
}

// The simulated operator's setting is recorded when the cell has one, and replayed bit for bit;
// a cell without one (a real cell's operator is a person) records nothing, and the replay
// answers false as the live cell did.
// A FakeCell with a simulated operator: it keeps the values set.
class FakeOperatorCell : public FakeCell {
 public:
  bool SetOperatorAlignmentError(double sigma_m) override {
    set.push_back(sigma_m);
    return true;
  }
  std::vector<double> set;
};

TEST(RecordingCell, OperatorErrorIsRecordedOnlyWhereTheCellSimulatesOne) {
  const fs::path base = TempDir("operator");
  {
    auto inner = std::make_unique<FakeOperatorCell>();
    FakeOperatorCell& fake = *inner;
    RecordingCell rec(std::move(inner), (base / "S").string(), RecordingManifest());
    EXPECT_TRUE(rec.SetOperatorAlignmentError(1.0 / 3.0 * 1e-3));
    EXPECT_EQ(fake.set, std::vector<double>{1.0 / 3.0 * 1e-3});
    rec.Finish();
  }
  {
    ReplayCell replay((base / "S").string());
    EXPECT_TRUE(replay.SetOperatorAlignmentError(1.0 / 3.0 * 1e-3));  // the same bits
    replay.Finish();
  }
  {
    ReplayCell replay((base / "S").string());
    EXPECT_THROW(replay.SetOperatorAlignmentError(0.3e-3), InputError);  // another value
  }
  {
    RecordingCell rec(std::make_unique<FakeCell>(), (base / "R").string(), RecordingManifest());
    EXPECT_FALSE(rec.SetOperatorAlignmentError(0.0005));  // FakeCell: no simulated operator
    rec.ReadEncoders(0);
    rec.Finish();
  }
  ReplayCell replay((base / "R").string());
  EXPECT_FALSE(replay.SetOperatorAlignmentError(0.0005));
  replay.ReadEncoders(0);
  replay.Finish();
  fs::remove_all(base);
}

}  // namespace
}  // namespace twin
