#include "bench/runs/calibration_run.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <random>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "bench/io/calibration_config.h"
#include "bench/io/csv.h"
#include "bench/io/measurements_csv.h"
#include "bench/io/declared_terms.h"
#include "bench/scoring/calibration_scoring.h"
#include "bench/runs/handclasp_run.h"
#include "bench/runs/plan_cache.h"
#include "bench/runs/tracker_run.h"
#include "bench/runs/workflow_run.h"
#include "bench/io/model_loader.h"
#include "bench/io/model_yaml.h"
#include "bench/io/output_files.h"
#include "bench/report/acceptance.h"
#include "bench/report/scenario_schema.h"
#include "bench/report/calibration_report.h"
#include "bench/io/scenario.h"
#include "bench/io/yaml_util.h"
#include "calib/common/clock.h"
#include "calib/common/errors.h"
#include "calib/model/parameters.h"
#include "sim/world/mujoco_handles.h"
#include "sim/cell/twin_cell.h"
#include "sim/render/gl_context.h"

namespace twin {
namespace fs = std::filesystem;
namespace {

// One measurements.csv row per aligned pose (what a hardware cell records).
void AppendRows(const RobotCalibration& rc, const std::string& robot, const std::string& camera,
                int joints, std::ostringstream* csv) {
  for (const AlignedPose& p : rc.aligned) {
    const bool cal = std::find(rc.calibration_axes.begin(), rc.calibration_axes.end(), p.axis) !=
                     rc.calibration_axes.end();
    const bool val = std::find(rc.validation_axes.begin(), rc.validation_axes.end(), p.axis) !=
                     rc.validation_axes.end();
    MeasurementRow r;
    r.robot = robot;
    r.camera_robot = camera;
    r.axis = p.axis;
    r.index = p.index;
    r.set = cal ? "calibration" : val ? "validation" : "unused";
    r.q = p.q_passive;
    r.du_px = p.pixel_error.x;
    r.dv_px = p.pixel_error.y;
    r.depth_m = p.p_C.z();
    r.offset = p.offset;
    r.frames = p.frames;
    r.moves = p.moves;
    r.du0_px = p.first_pixel_error.x;
    r.dv0_px = p.first_pixel_error.y;
    r.pose_rms_px = p.pose_rms_px;
    r.time_s = p.time_s;
    r.temperature_delta_K = p.temperature_delta_K;
    *csv << MeasurementsCsvRow(r, joints) << '\n';
  }
}

void WritePng(const fs::path& path, const cv::Mat& image) {
  if (!cv::imwrite(path.string(), image)) {
    throw InputError(path.string(), "cannot write the image (output folder not writable?)");
  }
}

// Writes a whole text file of the staging folder; a failure (disk full, permissions) names it.
void WriteText(const fs::path& path, const std::string& text) { WriteTextFile(path.string(), text); }

// The servo image with the principal point (red circle) and the detected feature point (green
// circle), as the paper's Fig. 12 shows them.
cv::Mat Annotated(const cv::Mat& image, const PinholeIntrinsics& k, const cv::Point2d& error) {
  cv::Mat out = image.clone();
  const cv::Point2d pp(k.cx, k.cy);
  const int shift = 4;  // sub-pixel drawing
  auto fixed = [&](const cv::Point2d& p) {
    return cv::Point(static_cast<int>(std::lround(p.x * (1 << shift))),
                     static_cast<int>(std::lround(p.y * (1 << shift))));
  };
  cv::circle(out, fixed(pp), 12 << shift, cv::Scalar(0, 0, 255), 2, cv::LINE_AA, shift);
  cv::circle(out, fixed(pp + error), 6 << shift, cv::Scalar(0, 200, 0), 2, cv::LINE_AA, shift);
  return out;
}

// A refused board pose for the report: the board's part of the image magnified kRefusedZoom
// times (nearest neighbour, so the pixels stay visible), a green circle on each detected corner
// and a red line from it towards the pose's reprojection, that offset drawn kRefusedOffsetGain
// times longer (a misplaced corner is a fraction of a pixel off).
constexpr int kRefusedZoom = 6;
constexpr double kRefusedOffsetGain = 20.0;
cv::Mat RefusedPoseFigure(const RefusedPoseImage& im) {
  cv::Rect box = cv::boundingRect(std::vector<cv::Point2f>(im.detected.begin(), im.detected.end()));
  const int margin = std::max(8, box.width / 2);
  box = cv::Rect(box.x - margin - im.origin.x, box.y - margin - im.origin.y,
                 box.width + 2 * margin, box.height + 2 * margin) &
        cv::Rect(cv::Point(0, 0), im.image.size());
  if (box.area() <= 0) return im.image.clone();
  cv::Mat out;
  cv::resize(im.image(box), out, cv::Size(), kRefusedZoom, kRefusedZoom, cv::INTER_NEAREST);
  if (out.channels() == 1) cv::cvtColor(out, out, cv::COLOR_GRAY2BGR);
  const int shift = 4;
  auto at = [&](const cv::Point2d& frame_px) {
    // Frame pixel u (centre u) is crop cell j = u - x0, magnified [j Z, (j + 1) Z), centre
    // (j + 0.5) Z.
    const cv::Point2d local = frame_px - cv::Point2d(im.origin + box.tl()) + cv::Point2d(0.5, 0.5);
    return cv::Point(static_cast<int>(std::lround(local.x * kRefusedZoom * (1 << shift))),
                     static_cast<int>(std::lround(local.y * kRefusedZoom * (1 << shift))));
  };
  for (size_t c = 0; c < im.detected.size() && c < im.reprojected.size(); ++c) {
    const cv::Point2d d = im.detected[c];
    const cv::Point2d tip = d + kRefusedOffsetGain * (im.reprojected[c] - d);
    cv::circle(out, at(d), 5 << shift, cv::Scalar(0, 200, 0), 2, cv::LINE_AA, shift);
    cv::line(out, at(d), at(tip), cv::Scalar(0, 0, 255), 2, cv::LINE_AA, shift);
  }
  return out;
}

// A Cell that forwards to another and adds up where the time goes (the benchmark's split of
// servoing into rendering and motion). It forwards every method of Cell: one left out would
// answer with Cell's default (no sensor, no tracker) while the cell behind has it.
class TimedCell : public Cell {
 public:
  explicit TimedCell(Cell& cell) : cell_(cell) {}
  MoveResult MoveTo(int robot, const JointVector& q) override {
    const auto t0 = Clock::now();
    MoveResult r = cell_.MoveTo(robot, q);
    move_s += SecondsSince(t0);
    ++moves;
    return r;
  }
  JointVector ReadEncoders(int robot) override { return cell_.ReadEncoders(robot); }
  cv::Mat GrabImage() override {
    const auto t0 = Clock::now();
    cv::Mat image = cell_.GrabImage();
    grab_s += SecondsSince(t0);
    ++frames;
    return image;
  }
  cv::Mat GrabImageRegion(const cv::Rect& roi) override {
    const auto t0 = Clock::now();
    cv::Mat image = cell_.GrabImageRegion(roi);
    grab_s += SecondsSince(t0);
    ++frames;
    ++region_frames;
    pixels += static_cast<double>(image.total());
    return image;
  }
  MoveResult ExchangeTools() override { return cell_.ExchangeTools(); }
  int CameraRobot() override { return cell_.CameraRobot(); }
  MoveResult MountTarget(BracketTarget target) override { return cell_.MountTarget(target); }
  double ClockSeconds() override { return cell_.ClockSeconds(); }
  double ReadTemperatureC(int robot) override { return cell_.ReadTemperatureC(robot); }
  MoveResult JogTipToContact(int jogged_robot) override {
    return cell_.JogTipToContact(jogged_robot);
  }
  TrackerReading MeasureTracker(int robot) override { return cell_.MeasureTracker(robot); }

  double move_s = 0, grab_s = 0;
  int moves = 0, frames = 0, region_frames = 0;
  double pixels = 0;  // of the region frames

 private:
  Cell& cell_;
};

// Model discovery per calibrated robot: estimator side (its aligned poses, the nominal board
// model, the stated noise), before any truth is read. A robot whose poses do not allow it
// (fewer than 3 axes) is reported as skipped; the calibration stands.
std::map<int, RobotDiagnosisResult> DiagnoseRobots(const Scenario& sc,
                                                   const CalibrationConfig& config,
                                                   const OpticalAxisResult& result, bool quiet,
                                                   Clock::time_point t_start) {
  std::map<int, RobotDiagnosisResult> out;  // robot index -> its diagnosis
  for (const RobotCalibration& rc : result.robots) {
    const std::string name = sc.robot_names[rc.robot];
    if (!config.diagnosis.enabled) {
      out[rc.robot].skipped = config.diagnosis_skip_reason;
      continue;
    }
    DiscoveryOptions d = config.discovery;
    d.axis_source = sc.path + " scenario.calibration.diagnosis (robot " + name + ")";
    // The stated encoder noise is per reading; each sample's joints are the mean of
    // servo.encoder_readings readings.
    d.joint_sigma_rad /= std::sqrt(static_cast<double>(config.options.servo.encoder_readings));
    if (!quiet) {
      d.progress = [&, name](const std::string& line) {
        std::printf("[%7.1f s] %s: %s\n", SecondsSince(t_start), name.c_str(), line.c_str());
        std::fflush(stdout);
      };
    }
    // The told payload: the weighed board as a point mass at the feature point, the origin of
    // the board model's tool link (BoardRobotModel), so that gravity terms see it.
    KinematicModel model = rc.nominal;
    if (config.board_mass_kg > 0.0) {
      AddPointMass(config.board_mass_kg, Vector3::Zero(), &model.tool());
    }
    // Declared effects (declared: true) are in the model from the start, by type and joint.
    std::vector<std::string> notes;
    const RobotModel start = DeclaredModel(sc, rc.robot, model, &notes);
    RobotDiagnosisResult& r = out[rc.robot];
    r.declared_terms.clear();
    for (const auto& t : start.terms) r.declared_terms.push_back(TermLabel(t->spec()));
    try {
      r.result = DiscoverOpticalAxisModel(start, rc.samples, d);
    } catch (const InputError& e) {
      r.skipped = e.what();
    }
  }
  return out;
}

// Writes a robot's servo images into staging (each kept pose before and after the servo,
// annotated, then each refused board pose magnified) and returns their files and captions.
std::vector<ReportImage> WriteServoImages(const RobotCalibration& rc, const std::string& name,
                                          const PinholeIntrinsics& ei, const fs::path& staging) {
  std::vector<ReportImage> images;
  for (const ServoImages& im : rc.images) {
    for (const bool after : {false, true}) {
      const std::string file = "servo_" + name + "_axis" + std::to_string(im.axis) + "_" +
                               (after ? "after" : "before") + ".png";
      const cv::Point2d e = after ? im.error_after : im.error_before;
      WritePng(staging / file, Annotated(after ? im.after : im.before, ei, e));
      std::ostringstream caption;
      caption.precision(3);
      caption << name << ", axis " << im.axis << ", position " << im.index << ", "
              << (after ? "after" : "before") << " the visual servo: (du, dv) = (" << e.x
              << ", " << e.y << ") px";
      images.push_back({file, caption.str()});
    }
  }
  for (const RefusedPoseImage& im : rc.refused_images) {
    const std::string file = "servo_" + name + "_axis" + std::to_string(im.axis) + "_position" +
                             std::to_string(im.index) + "_refused.png";
    WritePng(staging / file, RefusedPoseFigure(im));
    std::ostringstream caption;
    caption.precision(3);
    caption << name << ", axis " << im.axis << ", position " << im.index
            << ": board pose refused, corners reprojected with RMS " << im.rms_px
            << " px (green: detected corners, red: the pose's reprojection; the board "
            << "magnified " << kRefusedZoom << " times, the offsets a further "
            << kRefusedOffsetGain << " times)";
    images.push_back({file, caption.str()});
  }
  return images;
}

// The visual servo's figures over a robot's aligned poses.
ServoFigures ServoFiguresOf(const RobotCalibration& rc) {
  ServoFigures f;
  for (const AlignedPose& p : rc.aligned) {
    f.frames += p.frames;
    f.region_frames += p.region_frames;
    f.full_frame_fallbacks += p.full_frame_fallbacks;
    f.max_final_pixel_error_px = std::max({f.max_final_pixel_error_px, std::abs(p.pixel_error.x),
                                           std::abs(p.pixel_error.y)});
  }
  return f;
}

// The truth errors over the region the delivered model's poses covered (their joint-space box):
// what the calibration can vouch for, beside the whole joint space. Nothing without such poses.
std::optional<CoveredRegionScore> ScoreCoveredRegion(const RobotCalibration& rc,
                                                     const KinematicModel& true_model,
                                                     const CalibrationConfig& config) {
  std::vector<JointVector> used;
  for (const AlignedPose& p : rc.aligned) {
    const bool cal = std::find(rc.calibration_axes.begin(), rc.calibration_axes.end(),
                               p.axis) != rc.calibration_axes.end();
    if (rc.refit || cal) used.push_back(p.q_passive);
  }
  if (used.empty()) return std::nullopt;
  CoveredRegionScore covered;
  covered.poses = used.size();
  covered.box = CoveredJointBox(used);
  covered.score = ScoreRegion(rc.nominal, rc.identified, true_model, covered.box,
                              config.scoring_configurations, config.scoring_seed);
  return covered;
}

// What scoring a robot against truth needs besides its calibration.
struct RobotScoringInputs {
  const Scenario& sc;
  const CalibrationConfig& config;
  const TwinTruth* truth;           ///< read after the procedure ended; null: a cell without
  const PinholeIntrinsics& ei;      ///< estimated intrinsics (the servo images' annotation)
  const std::map<int, RobotDiagnosisResult>& diagnoses;  ///< model discovery per robot
  const fs::path& staging;          ///< where the servo images go
};

// One robot's scores against truth (its servo images written into staging), beside its
// calibration: the delivered and nominal models, the covered region, the calibration-set
// model after a refit, and its diagnosis.
RobotStageResult ScoreRobotStage(const RobotCalibration& rc, const RobotScoringInputs& in) {
  RobotStageResult s;
  s.name = in.sc.robot_names[rc.robot];
  s.camera_robot = in.sc.robot_names[rc.camera_robot];
  const CalibrationConfig& config = in.config;
  s.observability = rc.refit                    ? rc.refit_result.observability
                    : rc.method == "linearized" ? rc.linearized.observability
                                                : rc.nonlinear.observability;
  s.servo = ServoFiguresOf(rc);
  s.images = WriteServoImages(rc, s.name, in.ei, in.staging);
  const auto d = in.diagnoses.find(rc.robot);
  if (d != in.diagnoses.end()) s.diagnosis = d->second;
  if (!in.truth) {  // a cell without truth: the estimates alone
    s.score = EstimatesWithoutTruth(rc.nominal, rc.identified, s.observability,
                                    config.scoring_configurations, config.scoring_seed);
    return s;
  }
  const KinematicModel true_model =
      BoardRobotModel(in.truth->models[rc.robot], in.truth->board.X_FT);
  s.score = ScoreRobot(rc.nominal, rc.identified, true_model, s.observability,
                       config.scoring_configurations, config.scoring_seed);
  s.covered_region = ScoreCoveredRegion(rc, true_model, config);
  if (rc.refit) {
    // The calibration-set model too, so that the refit's gain is visible.
    s.calibration_set_model = ScoreRobot(rc.nominal, rc.holdout, true_model, s.observability,
                                         config.scoring_configurations, config.scoring_seed);
  }
  return s;
}

// The robots' part of a calibration stage: their scores, measurements.csv, stage times.
struct ScoredRobots {
  std::vector<RobotStageResult> robots;  ///< in the procedure's order
  std::string csv;                       ///< measurements.csv
  double planning = 0, planning_compute = 0, servoing = 0, identification = 0;  ///< sums [s]
};

// Scores each calibrated robot against truth, writing its servo images and
// identified_<robot>.yaml into staging; collects measurements.csv and the stage times.
ScoredRobots ScoreRobots(const OpticalAxisResult& result, const RobotScoringInputs& in) {
  ScoredRobots out;
  int csv_joints = 0;
  for (const RobotCalibration& rc : result.robots) {
    csv_joints = std::max(csv_joints, rc.nominal.num_joints());
  }
  std::ostringstream csv;
  csv << MeasurementsCsvHeader(csv_joints) << '\n';
  for (const RobotCalibration& rc : result.robots) {
    const std::string name = in.sc.robot_names[rc.robot];
    const std::string camera = in.sc.robot_names[rc.camera_robot];
    out.planning += rc.planning_s;
    out.planning_compute += rc.plan_compute_s;
    out.servoing += rc.servoing_s;
    out.identification += rc.identification_s;
    out.robots.push_back(ScoreRobotStage(rc, in));
    AppendRows(rc, name, camera, csv_joints, &csv);
    // The identified model, ready to load (tool link = board mount, as identified).
    WriteText(in.staging / ("identified_" + name + ".yaml"), ModelToYaml(rc.identified));
  }
  out.csv = csv.str();
  return out;
}

// The stages' times and the cell's frames and moves; `total` is the time since t_start, read
// now.
CalibrationTiming StageTiming(Clock::time_point t_start, const OpticalAxisResult& result,
                              const ScoredRobots& robots, double diagnosis_s, double scoring,
                              const TimedCell& timed) {
  CalibrationTiming t;
  t.total = SecondsSince(t_start);
  t.intrinsics = result.intrinsics_s;
  t.intrinsics_detection = result.intrinsics.detect_s;
  t.intrinsics_zhang = result.intrinsics.calibrate_s;
  t.planning = robots.planning;
  t.planning_compute = robots.planning_compute;
  t.servoing = robots.servoing;
  t.identification = robots.identification;
  t.diagnosis = diagnosis_s;
  t.scoring = scoring;
  t.frames = timed.frames;
  t.region_frames = timed.region_frames;
  t.region_pixels = timed.pixels;
  t.grab_image = timed.grab_s;
  t.moves = timed.moves;
  t.move_to = timed.move_s;
  if (const std::string gl = GlBackendDescription(); gl != "none") t.renderer = gl;
  return t;
}

// What the stage's report shows of the setting: the twin camera's true intrinsics, the plate
// Zhang's method saw (the intrinsics target when the cell was told one), planner and servo.
void RecordSetting(const TwinTruth* truth, const CalibrationConfig& config,
                   CalibrationStageResult* stage) {
  stage->truth_available = truth != nullptr;
  if (truth) {
    const Intrinsics& ti = truth->camera.intrinsics;
    const Distortion& td = truth->camera.distortion;
    stage->true_intrinsics = PinholeIntrinsics{ti.fx, ti.fy, ti.cx, ti.cy};
    stage->true_distortion = DistortionCoefficients{td.k1, td.k2, td.p1, td.p2, td.k3};
  } else {  // a cell without truth: NaN, written as null
    constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
    stage->true_intrinsics = PinholeIntrinsics{kNone, kNone, kNone, kNone};
    stage->true_distortion = DistortionCoefficients{kNone, kNone, kNone, kNone, kNone};
  }
  const CellKnowledge& k = config.knowledge;
  stage->plate = k.intrinsics_target ? *k.intrinsics_target : k.board;
  stage->dedicated_target = k.intrinsics_target.has_value();
  stage->planner = config.options.planner;
  stage->servo_tolerance_px = config.options.servo.tolerance_px;
}

}  // namespace

CalibrationStageResult RunCalibrationStage(BenchCell& cell, const Scenario& sc,
                                           CalibrationConfig config, const fs::path& staging,
                                           bool quiet,
                                           std::chrono::steady_clock::time_point t_start) {
  // Progress lines with the time since t_start.
  config.options.progress = [&](const std::string& line) {
    if (quiet) return;
    std::printf("[%7.1f s] %s\n", SecondsSince(t_start), line.c_str());
    std::fflush(stdout);
  };
  // The procedure, on a cell that adds up where the time goes.
  TimedCell timed(cell);
  CalibrationStageResult stage;
  stage.procedure = RunOpticalAxisCalibration(timed, config.knowledge, config.options);
  const OpticalAxisResult& result = stage.procedure;

  // Model discovery per calibrated robot, before any truth is read.
  const auto t_diagnosis = Clock::now();
  const std::map<int, RobotDiagnosisResult> diagnosis =
      DiagnoseRobots(sc, config, result, quiet, t_start);
  const double diagnosis_s = SecondsSince(t_diagnosis);

  // Scoring: estimates meet truth only here, after the procedure ended (a cell without truth,
  // a real one: the estimates alone).
  const auto t_score = Clock::now();
  const std::optional<TwinTruth> truth =
      cell.HasTruth() ? std::optional<TwinTruth>(cell.Truth()) : std::nullopt;
  RecordSetting(truth ? &*truth : nullptr, config, &stage);
  // Each robot's scores, servo images and identified model; then measurements.csv.
  const RobotScoringInputs inputs{sc,        config,  truth ? &*truth : nullptr,
                                  result.intrinsics.intrinsics, diagnosis, staging};
  ScoredRobots robots = ScoreRobots(result, inputs);
  WriteText(staging / "measurements.csv", robots.csv);
  const double scoring = SecondsSince(t_score);
  // Where the time went.
  stage.timing = StageTiming(t_start, result, robots, diagnosis_s, scoring, timed);
  stage.robots = std::move(robots.robots);
  return stage;
}

namespace {

// What the physical-truth measurement of one robot compares: the twin moves the robot, and
// each settled pose is measured there and predicted by both models at the same readings.
struct PhysicalTruthSetup {
  BenchCell& cell;
  const RobotCalibration& rc;
  const RobotModel& delivered;         ///< the calibration's model
  const RobotModel& discovered_model;  ///< the diagnosis' model (or the delivered one)
  int wanted;                          ///< poses to measure
};

// The feature point's positions at the poses that settled: true and as each model predicts.
struct PhysicalMeasurements {
  std::vector<Vector3> p_true, p_delivered, p_discovered;
};

// The twin moved to each configuration that settles, until `wanted` are measured.
// The draws are taken in order, in batches of as many as are still wanted, and each batch
// is visited nearest first from where the robot stands (by the largest joint difference,
// which sets how long a move's ramp lasts): the same seeded poses as in draw order, on a
// shorter way round them (about half the moves' simulated time on the paper scenario).
PhysicalMeasurements MeasurePhysicalTruth(const PhysicalTruthSetup& s,
                                          const std::vector<JointVector>& configurations) {
  BenchCell& cell = s.cell;
  const RobotCalibration& rc = s.rc;
  PhysicalMeasurements m;
  const size_t want = static_cast<size_t>(s.wanted);
  size_t next = 0;
  for (bool stop = false; !stop && m.p_true.size() < want && next < configurations.size();) {
    const size_t count = std::min(configurations.size() - next, want - m.p_true.size());
    std::vector<JointVector> batch(configurations.begin() + next,
                                   configurations.begin() + next + count);
    next += count;
    JointVector at = cell.ReadEncoders(rc.robot);
    while (!stop && !batch.empty()) {
      size_t nearest = 0;
      double shortest = std::numeric_limits<double>::infinity();
      for (size_t i = 0; i < batch.size(); ++i) {
        const double d = (batch[i] - at).cwiseAbs().maxCoeff();
        if (d < shortest) {
          shortest = d;
          nearest = i;
        }
      }
      const JointVector q = batch[nearest];
      batch.erase(batch.begin() + nearest);
      const JointVector before = cell.ReadEncoders(rc.robot);
      at = q;
      if (cell.MoveTo(rc.robot, q).status != MoveStatus::kSettled) {
        at = cell.ReadEncoders(rc.robot);
        continue;
      }
      MeasurementContext c;
      c.q = cell.ReadEncoders(rc.robot);
      c.approach = ApproachDirections(before, q);
      c.time_s = cell.ClockSeconds();
      if (std::isfinite(rc.temperature_reference_C)) {
        c.temperature_delta_K = cell.ReadTemperatureC(rc.robot) - rc.temperature_reference_C;
      }
      if (!MissingContext(s.discovered_model, c).empty()) {  // a term needs what is not read
        stop = true;
        break;
      }
      const TwinTruth t = cell.Truth();
      m.p_true.push_back(t.X_WB[rc.robot].inverse() * t.X_WT.translation());
      m.p_delivered.push_back(EndPose(s.delivered, c).translation());
      m.p_discovered.push_back(EndPose(s.discovered_model, c).translation());
    }
  }
  return m;
}

// The physical truth of measured poses: both models' raw and rigid gauges, with `rule`.
PhysicalTruthScore PhysicalScore(const PhysicalMeasurements& m, const std::string& rule) {
  PhysicalTruthScore p;
  p.poses = m.p_true.size();
  p.rule = rule;
  p.calibrated = CompareInGauges(m.p_delivered, m.p_true);
  p.discovered = CompareInGauges(m.p_discovered, m.p_true);
  return p;
}

// The whole joint space (the limits less 10 deg): 20 * wanted seeded random configurations.
std::vector<JointVector> WholeJointSpaceConfigurations(const Scenario& sc,
                                                       const RobotCalibration& rc, int wanted) {
  std::vector<JointVector> anywhere;
  std::mt19937_64 rng(sc.seeds.truth * 7919 + 31 + rc.robot);
  const double margin = DegToRad(10.0);
  for (int a = 0; a < 20 * wanted; ++a) {
    JointVector q = ZeroJoints(rc.nominal);
    for (int i = 0; i < rc.nominal.num_joints(); ++i) {
      const JointLimits& l = rc.nominal.links[i].limits;
      q(i) = std::uniform_real_distribution<double>(l.lower + margin, l.upper - margin)(rng);
    }
    anywhere.push_back(q);
  }
  return anywhere;
}

// One diagnosed robot that holds the board: the physical truth over the whole joint space and
// over the region its aligned poses covered, into its scores `s`.
void ScoreRobotPhysicalTruth(BenchCell& cell, const Scenario& sc, const CalibrationConfig& config,
                             const RobotCalibration& rc, const DiscoveryResult& diagnosis,
                             RobotStageResult* s) {
  const RobotModel delivered = MakeRobotModel(rc.identified);
  // Nothing added and nothing declared: the discovered model is the delivered one; with
  // declared terms it is the diagnosis' model (the geometry refitted with them).
  const RobotModel& discovered_model =
      diagnosis.effects_added.empty() && diagnosis.model.terms.empty() ? delivered
                                                                       : diagnosis.model;
  const int wanted = config.diagnosis.truth_poses;
  const PhysicalTruthSetup setup{cell, rc, delivered, discovered_model, wanted};
  const std::vector<JointVector> anywhere = WholeJointSpaceConfigurations(sc, rc, wanted);
  const PhysicalMeasurements whole = MeasurePhysicalTruth(setup, anywhere);
  if (whole.p_true.size() < 10) {
    s->physical_skipped = "fewer than 10 random poses settled";
    return;
  }
  s->physical = PhysicalScore(
      whole, "the board's feature point where the twin's physics puts it (every effect) "
             "at seeded random poses, against each model at the same readings");
  // The region the aligned poses covered (their joint box), where the data vouches for the
  // model; beside the whole joint space, which the model reaches only by extrapolation.
  std::vector<JointVector> aligned;
  for (const AlignedPose& p : rc.aligned) aligned.push_back(p.q_passive);
  if (!aligned.empty()) {
    const JointBox box = CoveredJointBox(aligned);
    const PhysicalMeasurements covered = MeasurePhysicalTruth(
        setup, RandomJointConfigurationsIn(box, 20 * wanted,
                                           sc.seeds.truth * 7919 + 37 + rc.robot));
    if (covered.p_true.size() >= 10) {
      s->physical_covered_region = PhysicalScore(
          covered, "as truth_position_error_mm_physical, at seeded random poses inside "
                   "the joint box of the robot's aligned poses");
    }
  }
}

// Physical truth (bench only, after the procedure and the diagnosis): the board's feature point
// where the twin's physics puts it (every effect, the mount's deflection included) at seeded
// random poses of each diagnosed robot that holds the board now, against the delivered model
// and the discovered one at the same readings; raw and rigid gauges as the tracker runs.
// The robot ends where the last pose left it.
void ScorePhysicalTruth(BenchCell& cell, const Scenario& sc, const CalibrationConfig& config,
                        CalibrationStageResult* stage) {
  for (size_t i = 0; i < stage->robots.size(); ++i) {
    const RobotCalibration& rc = stage->procedure.robots[i];
    RobotStageResult& s = stage->robots[i];
    if (!s.diagnosis.result) continue;
    if (!stage->truth_available) {
      s.physical_skipped = "the cell offers no truth";
      continue;
    }
    if (cell.Truth().board.robot != rc.robot) {
      s.physical_skipped = "the board is on the other robot at the end of the procedure";
      continue;
    }
    // The whole joint space and the covered region, measured on the twin.
    ScoreRobotPhysicalTruth(cell, sc, config, rc, *s.diagnosis.result, &s);
  }
}

// A refusal at run time (too few aligned poses, the board not in view, ...) names the step;
// the message also names the scenario file so the user knows which input to fix.
[[noreturn]] void RethrowNamingScenario(const InputError& e, const std::string& scenario) {
  if (e.where().rfind(scenario, 0) == 0) throw e;
  throw InputError(scenario, e.what());
}

// A validated optical-axis run: its inputs, checked, and the folders it writes.
struct OpticalAxisRun {
  const RunOptions& options;
  const Scenario& sc;
  const CalibrationConfig& config;
  const Acceptance& acceptance;
  Clock::time_point t_start;  ///< the run's start (progress lines, timing)
  const fs::path& out;        ///< the output folder
  const fs::path& staging;    ///< written first, published as `out` at the end
};

// Runs the calibration stage and the physical truth into `stage`, judges the acceptance
// criteria on the report, writes report.json (and report.html) and publishes the staging
// folder. On failure the staging folder is discarded and an InputError names the scenario file.
AcceptanceVerdict RunAndPublishReport(BenchCell& cell, const OpticalAxisRun& run,
                                      CalibrationStageResult* stage) {
  AcceptanceVerdict verdict;
  try {
    std::printf("twinbench run: scenario %s (%s)\n", run.sc.name.c_str(), run.sc.path.c_str());
    *stage = RunCalibrationStage(cell, run.sc, run.config, run.staging, run.options.quiet,
                                 run.t_start);
    ScorePhysicalTruth(cell, run.sc, run.config, stage);
    cell.Finish();  // the last call: a recording is complete, a replay used up
    // Criteria on figures against the truth cannot be judged without it: left out, and said so.
    const Acceptance judged = stage->truth_available
                                  ? run.acceptance
                                  : WithoutTruthCriteria(run.acceptance, run.options.quiet);
    const JudgedReport report = CalibrationReport(run.sc, *stage, judged, run.options.images);
    verdict = report.verdict;
    WriteText(run.staging / "report.json", report.json);
    if (run.options.images) WriteText(run.staging / "report.html", report.html);
    PublishDirectory(run.staging.string(), run.out.string());
  } catch (const InputError& e) {
    DiscardStaging(run.staging.string());
    RethrowNamingScenario(e, run.sc.path);
  } catch (...) {
    DiscardStaging(run.staging.string());
    throw;
  }
  return verdict;
}

// A figure as the summary prints it: what the report holds as null (NaN, infinite: not
// computed) prints as nan.
double Figure(double v) { return std::isfinite(v) ? v : std::numeric_limits<double>::quiet_NaN(); }
// A length in m as the summary prints it [mm].
double Mm(double m) { return Figure(1000.0 * m); }

// One robot's misaligned-error and truth-error lines of the run summary.
void PrintRobotErrors(const RobotCalibration& rc, const RobotStageResult& s) {
  const char* name = s.name.c_str();
  for (const bool cal : {true, false}) {
    const MisalignedSummary& m = cal ? rc.calibration_error : rc.validation_error;
    if (m.samples == 0 || !std::isfinite(1000.0 * m.before)) continue;  // null in the report
    std::printf("%-6s %-22s %10.4f %10.4f %8.1f%%\n", name,
                (std::string("misaligned ") + (cal ? "calibration" : "validation")).c_str(),
                Mm(m.before), Mm(m.after), Figure(DecreasePercent(m.before, m.after)));
  }
  const GaugeErrors& b = s.score.before;
  const GaugeErrors& a = s.score.after;
  const std::pair<const char*, PositionErrorStats GaugeErrors::*> gauges[] = {
      {"raw", &GaugeErrors::raw}, {"rigid", &GaugeErrors::rigid},
      {"similarity", &GaugeErrors::similarity}};
  if (!std::isfinite(b.raw.rms)) {  // a cell without truth
    std::printf("%-6s %-22s (the cell offers no truth)\n", name, "truth RMS");
  }
  for (const auto& [gauge, g] : gauges) {
    if (!std::isfinite((b.*g).rms)) break;
    std::printf("%-6s %-22s %10.4f %10.4f   (max %.4f -> %.4f)\n", name,
                (std::string("truth RMS ") + gauge).c_str(), Mm((b.*g).rms), Mm((a.*g).rms),
                Mm((b.*g).max), Mm((a.*g).max));
  }
  if (s.covered_region) {
    const RegionScore& c = s.covered_region->score;
    std::printf("%-6s covered region (%d poses' joint box): truth RMS rigid %.4f -> %.4f, "
                "similarity %.4f -> %.4f\n",
                name, static_cast<int>(s.covered_region->poses), Mm(c.before.rigid.rms),
                Mm(c.after.rigid.rms), Mm(c.before.similarity.rms), Mm(c.after.similarity.rms));
  }
  if (s.calibration_set_model) {
    const RobotScore& h = *s.calibration_set_model;
    std::printf("%-6s delivered model refit on all axes; the calibration-set model alone: "
                "truth RMS rigid %.4f, similarity %.4f\n",
                name, Mm(h.after.rigid.rms), Mm(h.after.similarity.rms));
  }
}

// One robot's diagnosis, physical-truth, scale and servo lines of the run summary.
void PrintRobotDiagnosis(const RobotCalibration& rc, const RobotStageResult& s) {
  const char* name = s.name.c_str();
  if (!s.diagnosis.result) {
    std::printf("%-6s diagnosis skipped (%s)\n", name, s.diagnosis.skipped.c_str());
  } else {
    std::printf("%-6s diagnosis: %s: %s\n", name, ToString(s.diagnosis.result->verdict),
                s.diagnosis.result->reason.c_str());
  }
  if (s.physical) {
    std::printf("%-6s physical truth (%d poses, rigid RMS): calibrated %.4f mm, discovered "
                "%.4f mm\n",
                name, static_cast<int>(s.physical->poses), Mm(s.physical->calibrated.rigid.rms),
                Mm(s.physical->discovered.rigid.rms));
  }
  if (s.physical_covered_region) {
    const PhysicalTruthScore& ph = *s.physical_covered_region;
    std::printf("%-6s physical truth, covered region (%d poses, rigid RMS): calibrated %.4f "
                "mm, discovered %.4f mm\n",
                name, static_cast<int>(ph.poses), Mm(ph.calibrated.rigid.rms),
                Mm(ph.discovered.rigid.rms));
  }
  const int aligned = static_cast<int>(rc.aligned.size());
  char scale_true[32] = "no truth";
  if (std::isfinite(s.score.scale_true)) {
    std::snprintf(scale_true, sizeof(scale_true), "%.6f", s.score.scale_true);
  }
  std::printf("%-6s scale estimated %.6f, true %s; servo %d aligned, %d failed, %.2f "
              "frames/pose\n",
              name, s.score.scale_estimated, scale_true, aligned,
              static_cast<int>(rc.failed.size()),
              aligned > 0 ? double(s.servo.frames) / aligned
                          : std::numeric_limits<double>::quiet_NaN());
}

// Prints the run summary: a table of each robot's figures (robots by name, as the report lists
// them), the timing and what was written into `out`.
void PrintRunSummary(const CalibrationStageResult& stage, const fs::path& out) {
  std::printf("\n%-6s %-22s %10s %10s %9s\n", "robot", "metric [mm]", "before", "after",
              "decrease");
  std::map<std::string, size_t> by_name;
  for (size_t i = 0; i < stage.robots.size(); ++i) by_name[stage.robots[i].name] = i;
  for (const auto& [name, i] : by_name) {
    PrintRobotErrors(stage.procedure.robots[i], stage.robots[i]);
    PrintRobotDiagnosis(stage.procedure.robots[i], stage.robots[i]);
  }
  const CalibrationTiming& t = stage.timing;
  std::printf("timing [s]: total %.1f = intrinsics %.1f + waiting for the plans %.1f + "
              "servoing %.1f + identification %.1f + diagnosis %.1f + scoring %.1f (planning %.1f "
              "in the background)\n",
              t.total, t.intrinsics, t.planning, t.servoing, t.identification, t.diagnosis,
              t.scoring, t.planning_compute);
  std::printf("cell: %d frames in %.1f s (GrabImage), %d moves in %.1f s (MoveTo)%s%s\n",
              t.frames, t.grab_image, t.moves, t.move_to,
              t.renderer.empty() ? "" : "; rendered with ", t.renderer.c_str());
  std::printf("wrote %s/{report.json, report.html, measurements.csv, servo_*.png}\n",
              out.string().c_str());
}

}  // namespace

void ApplyRunOptions(const RunOptions& o, CalibrationConfig* config) {
  if (!o.diagnosis) {
    config->diagnosis.enabled = false;
    config->diagnosis_skip_reason = "--no-diagnosis";
  }
  if (!o.plan_cache.empty()) {
    config->options.plan_store = std::make_shared<FilePlanStore>(o.plan_cache);
  }
  if (!o.images) config->options.kept_images = 0;
}

Scenario LoadRunScenario(const RunOptions& o, std::string* text) {
  if (o.scenario_text.empty()) {
    Scenario sc = LoadScenario(o.scenario);
    if (text) *text = ReadTextFile(o.scenario);
    ApplyTrial(o.trial, &sc);
    return sc;
  }
  // A replay's scenario: the recorded text, named as the recorded run named it.
  Scenario sc = ParseScenario(o.scenario_text, o.scenario, o.scenario_dir);
  PrintWarnings(sc.warnings);
  if (text) *text = o.scenario_text;
  ApplyTrial(o.trial, &sc);
  return sc;
}

CellOptions RunCellOptions(const RunOptions& o, const Scenario& sc, const std::string& text) {
  CellOptions cell = o.cell;
  if (cell.record_dir.empty()) return cell;
  RecordingManifest& m = cell.record_info;
  m.scenario_path = o.scenario;
  m.scenario_dir = fs::absolute(fs::path(sc.path).parent_path()).lexically_normal().string();
  m.scenario_text = text;
  m.trial = o.trial;
  m.diagnosis = o.diagnosis;
  m.images = o.images;
  m.plan_cache = o.plan_cache;
  m.cell = o.cell.address;
  return cell;
}

int RunCalibrationScenario(const RunOptions& o) {
  const auto t_start = Clock::now();
  std::string text;
  Scenario sc = LoadRunScenario(o, &text);
  // Other procedures run elsewhere: the laser tracker, the handclasp, the dual-arm workflow.
  if (IsPresent(sc.tracker_calibration)) return RunTrackerScenario(o);
  // base-frame calibration alone
  if (IsPresent(sc.handclasp) && !IsPresent(sc.calibration)) return RunHandclaspScenario(o);
  if (IsPresent(sc.handclasp) && IsPresent(sc.calibration)) return RunWorkflowScenario(o);
  // Everything is validated before anything is written: the sections, the output paths and
  // the cell itself (its initial pose must settle without collisions).
  CalibrationConfig config = ParseCalibrationConfig(sc);
  ApplyRunOptions(o, &config);
  const Acceptance acceptance = ParseAcceptance(sc);
  ValidateOutputFolder(o.out_dir, "--out");
  if (!o.junit.empty()) ValidateJunitFile(o.junit, o.out_dir);
  InstallMujocoErrorHandlers();
  // On a cell without truth (a real one) the report has the estimates alone.
  const std::unique_ptr<BenchCell> cell =
      OpenBenchCell(sc.twin, sc.path, RunCellOptions(o, sc, text));
  const fs::path out(o.out_dir);
  const fs::path staging = CreateStagingDirectory(o.out_dir);
  // The calibration, scored and judged, written and published as out_dir.
  CalibrationStageResult stage;
  const AcceptanceVerdict verdict = RunAndPublishReport(
      *cell, OpticalAxisRun{o, sc, config, acceptance, t_start, out, staging}, &stage);
  // Summary of the typed results.
  PrintRunSummary(stage, out);
  // JUnit file, verdict, exit code.
  if (!o.junit.empty()) WriteJunit(o.junit, sc.name, verdict, SecondsSince(t_start));
  PrintVerdict(verdict);
  return VerdictExitCode(verdict);
}

int CheckScenario(const std::string& scenario_path) {
  // The schema first (schemas/scenario.schema.json): a wrong key or value by its key path.
  ValidateScenarioSchema(scenario_path);
  const Scenario sc = LoadScenario(scenario_path);
  const bool calibration = IsPresent(sc.calibration), handclasp = IsPresent(sc.handclasp);
  if (calibration) ParseCalibrationConfig(sc);
  if (handclasp) {
    const HandclaspConfig h = ParseHandclaspConfig(sc);
    if (calibration && h.trials != 1) {
      throw InputError(sc.path + " scenario.handclasp.trials",
                       "the dual-arm workflow runs one trial; trials must be 1, got " +
                           std::to_string(h.trials));
    }
  }
  const bool tracker = IsPresent(sc.tracker_calibration);
  if (tracker) ValidateTrackerScenario(sc);
  const Acceptance acceptance = ParseAcceptance(sc);
  InstallMujocoErrorHandlers();
  const TwinCell cell(sc.twin, sc.path);  // the cell settles at its initial pose
  const char* what = calibration && handclasp ? "the dual-arm workflow"
                     : calibration            ? "the optical-axis calibration"
                     : handclasp              ? "the handclasp base-frame calibration"
                     : tracker                ? "the laser-tracker calibration"
                                              : "no procedure (no calibration:, handclasp: or "
                                                "tracker_calibration: section; `render` shows "
                                                "the cell)";
  std::printf("%s: valid; `twinbench run` would run %s with %zu acceptance criteria\n",
              sc.path.c_str(), what, acceptance.criteria.size());
  return 0;
}


namespace {

// The --board-mount option as X_FT ("x,y,z,roll,pitch,yaw" in mm and deg); empty: the board at
// the flange. Throws InputError for a malformed or implausible mount.
Transform ParseBoardMount(const std::string& board_mount) {
  Transform X_FT = Transform::Identity();  // documented nominal: the board at the flange
  if (!board_mount.empty()) {
    std::vector<double> v;
    for (const std::string& item : SplitCsv(board_mount)) {
      v.push_back(CsvNumber(item, "--board-mount"));
    }
    if (v.size() != 6) {
      throw InputError("--board-mount", "expected x,y,z,roll,pitch,yaw (mm, deg), got '" +
                                            board_mount + "'");
    }
    // Plausibility: a board bracket is shorter than a metre; angles are periodic.
    if (Vector3(v[0], v[1], v[2]).norm() > 1000.0) {
      throw InputError("--board-mount", "the board must sit within 1000 mm of the flange (a "
                                        "flange tool's bracket), got '" + board_mount + "'");
    }
    for (int k = 3; k < 6; ++k) {
      if (std::abs(v[k]) > 360.0) {
        throw InputError("--board-mount", "angles must be within +-360 deg, got '" +
                                              board_mount + "'");
      }
    }
    X_FT.translation() = Vector3(v[0], v[1], v[2]) / 1000.0;
    X_FT.linear() = RpyToRotation(Vector3(DegToRad(v[3]), DegToRad(v[4]), DegToRad(v[5])));
  }
  return X_FT;
}

// Recorded rows as identification input: the robot on its board model with the samples, and
// the axes the CSV's set column puts in the calibration and the validation set.
struct RecordedSamples {
  RobotCalibration rc;              ///< nominal (board model, named as the file's robot), samples
  std::set<int> cal_axes, val_axes;  ///< axes of the calibration / validation rows
};

// The measurements file's rows as samples of `model` carrying the board at X_FT.
RecordedSamples SamplesFromRows(const MeasurementsFile& file, const KinematicModel& model,
                                const Transform& X_FT) {
  RecordedSamples out;
  RobotCalibration& rc = out.rc;
  rc.nominal = BoardRobotModel(model, X_FT);
  for (const MeasurementRow& row : file.rows) {
    AxisSample s;
    s.axis = row.axis;
    s.q = row.q;
    s.depth = row.depth_m;
    s.offset = row.offset;
    if (row.set == "calibration") out.cal_axes.insert(row.axis);
    if (row.set == "validation") out.val_axes.insert(row.axis);
    rc.samples.push_back(s);
  }
  rc.nominal.name = file.robot;
  return out;
}

// Writes identification.json and identified_<robot>.yaml into a staging folder and publishes it
// as out_dir (the staging folder discarded on failure).
void WriteIdentificationFiles(const std::string& out_dir, const std::string& report_text,
                              const RobotCalibration& rc, const std::string& robot) {
  const fs::path out(out_dir);
  const fs::path staging = CreateStagingDirectory(out_dir);
  try {
    WriteText(staging / "identification.json", report_text);
    WriteText(staging / ("identified_" + robot + ".yaml"), ModelToYaml(rc.identified));
    PublishDirectory(staging.string(), out.string());
  } catch (...) {
    DiscardStaging(staging.string());
    throw;
  }
}

// Prints the identification's summary: samples, method, eq. 46 errors, what was written.
void PrintIdentificationSummary(const RobotCalibration& rc, const std::string& robot,
                                const fs::path& out) {
  std::printf("%s: %zu samples, method %s\n", robot.c_str(), rc.samples.size(), rc.method.c_str());
  std::printf("misaligned error (eq. 46): calibration %.4f -> %.4f mm", 1000 * rc.calibration_error.before,
              1000 * rc.calibration_error.after);
  if (rc.validation_error.samples > 0) {
    std::printf(", validation %.4f -> %.4f mm", 1000 * rc.validation_error.before,
                1000 * rc.validation_error.after);
  }
  std::printf("\nwrote %s/identification.json and identified_%s.yaml\n", out.string().c_str(),
              robot.c_str());
}

}  // namespace

int RunIdentify(const IdentifyOptions& o) {
  // Everything is validated before anything is written.
  ValidateOutputFolder(o.out_dir, "--out");
  if (!o.robot.empty()) RequireSafeName(o.robot, "--robot", "robot name");
  KinematicModel model = LoadRobotModelAndWarn(o.model, o.links);
  const Transform X_FT = ParseBoardMount(o.board_mount);
  const MeasurementsFile file = ReadMeasurementsCsv(o.measurements, model.num_joints(), o.robot);
  const std::string& robot = file.robot;
  // The rows as the board robot's samples, split into calibration and validation axes.
  RecordedSamples recorded = SamplesFromRows(file, model, X_FT);
  RobotCalibration& rc = recorded.rc;
  model.name = robot;
  // Identification with both methods.
  OpticalAxisOptions options;
  try {
    IdentifyRobot({recorded.cal_axes.begin(), recorded.cal_axes.end()},
                  {recorded.val_axes.begin(), recorded.val_axes.end()}, options, &rc);
  } catch (const InputError& e) {
    throw InputError(o.measurements, e.what());  // refused: name the data that was refused
  }
  // identification.json and the identified model, published as out_dir; then the summary.
  const fs::path out(o.out_dir);
  WriteIdentificationFiles(o.out_dir, IdentificationReportText(rc, robot), rc, robot);
  PrintIdentificationSummary(rc, robot, out);
  return 0;
}

}  // namespace twin
