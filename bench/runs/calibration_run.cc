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

#include <nlohmann/json.hpp>
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
#include "bench/report/diagnosis_report.h"
#include "bench/report/report_html.h"
#include "bench/report/scenario_json.h"
#include "bench/io/scenario.h"
#include "bench/io/yaml_util.h"
#include "calib/common/clock.h"
#include "calib/common/errors.h"
#include "calib/model/parameters.h"
#include "sim/world/mujoco_handles.h"
#include "sim/cell/twin_cell.h"

namespace twin {
namespace fs = std::filesystem;
using json = nlohmann::json;
namespace {

// JSON number, or null for NaN / infinity (JSON has neither).
json Num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
json Mm(double m) { return Num(1000.0 * m); }

double DecreasePercent(double before, double after) {
  return before > 0.0 ? 100.0 * (before - after) / before
                      : std::numeric_limits<double>::quiet_NaN();
}

json Misaligned(const MisalignedSummary& m) {
  // No samples (e.g. no validation axis aligned): every figure is there, null, so that an
  // acceptance criterion on it fails as "has no value" instead of naming an unknown figure.
  if (m.samples == 0) {
    return json{{"before", nullptr}, {"after", nullptr}, {"decrease_percent", nullptr},
                {"samples", 0}};
  }
  return json{{"before", Mm(m.before)},
              {"after", Mm(m.after)},
              {"decrease_percent", Num(DecreasePercent(m.before, m.after))},
              {"samples", m.samples}};
}

json Stats(const PositionErrorStats& s) { return json{{"rms", Mm(s.rms)}, {"max", Mm(s.max)}}; }

json Gauges(int configurations, const GaugeErrors& before, const GaugeErrors& after) {
  json j;
  j["configurations"] = configurations;
  j["raw"] = {{"before", Stats(before.raw)}, {"after", Stats(after.raw)}};
  j["rigid"] = {{"before", Stats(before.rigid)}, {"after", Stats(after.rigid)}};
  j["similarity"] = {{"before", Stats(before.similarity)}, {"after", Stats(after.similarity)}};
  return j;
}

json Gauges(const RobotScore& s) { return Gauges(s.configurations, s.before, s.after); }

json IntrinsicsJson(const PinholeIntrinsics& k, const DistortionCoefficients& d) {
  return json{{"fx", k.fx}, {"fy", k.fy}, {"cx", k.cx}, {"cy", k.cy}, {"k1", d.k1},
              {"k2", d.k2}, {"p1", d.p1}, {"p2", d.p2}, {"k3", d.k3}};
}

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

// The printed plate Zhang's method saw: the intrinsics target when the cell was told one.
json PlateJson(const CellKnowledge& k) {
  const BoardGeometry& p = k.intrinsics_target ? *k.intrinsics_target : k.board;
  return json{{"squares", {p.squares_x, p.squares_y}},
              {"square_mm", p.square_m * 1e3},
              {"dedicated_target", k.intrinsics_target.has_value()}};
}


// Model discovery's outcome per calibrated robot (robot index -> ...).
struct RobotDiagnoses {
  std::map<int, DiscoveryResult> results;  ///< robots whose diagnosis ran
  std::map<int, std::string> skipped;      ///< why a robot's diagnosis was skipped
  std::map<int, json> declared_terms;      ///< per robot: the declared effects' term labels
};

// Model discovery per calibrated robot: estimator side (its aligned poses, the nominal board
// model, the stated noise), before any truth is read. A robot whose poses do not allow it
// (fewer than 3 axes) is reported as skipped; the calibration stands.
RobotDiagnoses DiagnoseRobots(const Scenario& sc, const CalibrationConfig& config,
                              const OpticalAxisResult& result, bool quiet,
                              Clock::time_point t_start) {
  RobotDiagnoses out;
  for (const RobotCalibration& rc : result.robots) {
    const std::string name = sc.robot_names[rc.robot];
    if (!config.diagnosis.enabled) {
      out.skipped[rc.robot] = config.diagnosis_skip_reason;
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
    out.declared_terms[rc.robot] = json::array();
    for (const auto& t : start.terms) out.declared_terms[rc.robot].push_back(TermLabel(t->spec()));
    try {
      out.results[rc.robot] = DiscoverOpticalAxisModel(start, rc.samples, d);
    } catch (const InputError& e) {
      out.skipped[rc.robot] = e.what();
    }
  }
  return out;
}

// The report's `intrinsics` key: Zhang's estimate against the twin camera's truth, and the plate.
json IntrinsicsReportJson(const OpticalAxisResult& result, const TwinTruth& truth,
                          const CellKnowledge& knowledge) {
  const Intrinsics& ti = truth.camera.intrinsics;
  const Distortion& td = truth.camera.distortion;
  const PinholeIntrinsics& ei = result.intrinsics.intrinsics;
  return json{
      {"estimated", IntrinsicsJson(ei, result.intrinsics.distortion)},
      {"true", IntrinsicsJson(PinholeIntrinsics{ti.fx, ti.fy, ti.cx, ti.cy},
                          DistortionCoefficients{td.k1, td.k2, td.p1, td.p2, td.k3})},
      {"error_px",
       {{"fx", ei.fx - ti.fx}, {"fy", ei.fy - ti.fy}, {"cx", ei.cx - ti.cx}, {"cy", ei.cy - ti.cy}}},
      {"rms_reprojection_px", result.intrinsics.rms_px},
      {"views_used", result.intrinsics.views_used},
      {"views_skipped", result.intrinsics.skipped},
      {"plate", PlateJson(knowledge)}};
}

// A robot's `planning` key: the pose plan, its PSO runs and the candidates' rejections.
json PlanningJson(const RobotCalibration& rc, const PosePlannerOptions& planner) {
  json history = json::array();
  for (const auto& run : rc.plan.fitness_history) history.push_back(run);
  const RejectionCounts& rej = rc.plan.rejections;
  return json{{"axes", rc.plan.axes.size()},
              {"positions_per_axis", planner.positions_per_axis},
              {"best_fitness", Num(rc.plan.best_fitness)},
              {"best_run", rc.plan.best_run},
              {"select_run", planner.select_run ==
                                     PosePlannerOptions::RunSelection::kPredictedError
                                 ? "predicted_error"
                                 : "best_fitness"},
              {"run_fitness", rc.plan.run_fitness},
              {"run_predicted_error_mm", [&] {
                 json e = json::array();
                 for (double x : rc.plan.run_predicted_error) e.push_back(Num(1e3 * x));
                 return e;
               }()},
              {"run_predicted_similarity_error_mm", [&] {
                 json e = json::array();
                 for (double x : rc.plan.run_predicted_similarity_error) {
                   e.push_back(Num(1e3 * x));
                 }
                 return e;
               }()},
              {"evaluations", rc.plan.evaluations},
              {"fitness_history", history},
              {"rejections",
               {{"active_ik", rej.active_ik}, {"passive_ik", rej.passive_ik},
                {"c1_joint_limits", rej.c1_joint_limits},
                {"c2_singularity", rej.c2_singularity},
                {"c3_visibility", rej.c3_visibility},
                {"c4_min_distance", rej.c4_min_distance},
                {"c5_max_distance", rej.c5_max_distance}}},
              {"time_s", rc.plan_compute_s},
              {"wait_time_s", rc.planning_s},
              {"from_plan_store", rc.plan_from_store}};
}

// Writes a robot's servo images into staging (each kept pose before and after the servo,
// annotated, then each refused board pose magnified) and returns their files and captions.
json WriteServoImages(const RobotCalibration& rc, const std::string& name,
                      const PinholeIntrinsics& ei, const fs::path& staging) {
  json images = json::array();
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
      images.push_back({{"file", file}, {"caption", caption.str()}});
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
    images.push_back({{"file", file}, {"caption", caption.str()}});
  }
  return images;
}

// A robot's `servo` key: aligned and failed poses, frames, final errors; writes its images.
json ServoJson(const RobotCalibration& rc, const std::string& name, const PinholeIntrinsics& ei,
               double tolerance_px, const fs::path& staging) {
  int frames = 0, region_frames = 0, fallbacks = 0;
  double max_px = 0.0;
  for (const AlignedPose& p : rc.aligned) {
    frames += p.frames;
    region_frames += p.region_frames;
    fallbacks += p.full_frame_fallbacks;
    max_px = std::max({max_px, std::abs(p.pixel_error.x), std::abs(p.pixel_error.y)});
  }
  json failures = json::array();
  for (const FailedPose& f : rc.failed) {
    failures.push_back({{"axis", f.axis}, {"index", f.index}, {"status", f.status},
                        {"reason", f.reason}, {"frames", f.frames}});
  }
  const json images = WriteServoImages(rc, name, ei, staging);
  const int aligned = static_cast<int>(rc.aligned.size());
  return json{{"aligned_poses", aligned},
              {"failed_poses", rc.failed.size()},
              {"mean_frames_per_pose", aligned > 0 ? json(double(frames) / aligned) : json()},
              {"max_final_pixel_error_px", max_px},
              {"region_frames", region_frames},
              {"full_frame_fallbacks", fallbacks},
              {"tolerance_px", tolerance_px},
              {"failures", failures},
              {"images", images},
              {"time_s", rc.servoing_s}};
}

// A robot's `split` key: its calibration and validation axes and how they were chosen.
json SplitJson(const RobotCalibration& rc) {
  json split = {{"calibration_axes", rc.calibration_axes},
                {"validation_axes", rc.validation_axes},
                {"rule", rc.split_candidates.empty() ? "first" : "best_conditioned"},
                {"evaluated_at", rc.split_candidates.empty() ? json(nullptr) : json(rc.split_at)}};
  for (const auto& [axes, sigma] : rc.split_candidates) {
    split["candidates"].push_back({{"calibration_axes", axes},
                                   {"smallest_singular_value", sigma}});
  }
  return split;
}

// A robot's `misaligned_error_mm` key: eq. 46 per set and per axis, before and after.
json MisalignedErrorJson(const RobotCalibration& rc) {
  json per_axis = json::array();
  for (size_t k = 0; k < rc.per_axis.size(); ++k) {
    const int axis = static_cast<int>(k);
    const bool cal = std::find(rc.calibration_axes.begin(), rc.calibration_axes.end(),
                               axis) != rc.calibration_axes.end();
    if (rc.per_axis[k].samples == 0) continue;
    per_axis.push_back({{"axis", axis}, {"set", cal ? "calibration" : "validation"},
                        {"before", Mm(rc.per_axis[k].before)},
                        {"after", Mm(rc.per_axis[k].after)}});
  }
  return json{{"calibration", Misaligned(rc.calibration_error)},
              {"validation", Misaligned(rc.validation_error)},
              {"per_axis", per_axis}};
}

// The truth errors over the region the delivered model's poses covered (their joint-space box):
// what the calibration can vouch for, beside the whole joint space. Sets
// truth_position_error_mm_covered_region when there are such poses.
void ScoreCoveredRegion(const RobotCalibration& rc, const KinematicModel& true_model,
                        const CalibrationConfig& config, json* r) {
  std::vector<JointVector> used;
  for (const AlignedPose& p : rc.aligned) {
    const bool cal = std::find(rc.calibration_axes.begin(), rc.calibration_axes.end(),
                               p.axis) != rc.calibration_axes.end();
    if (rc.refit || cal) used.push_back(p.q_passive);
  }
  if (!used.empty()) {
    const JointBox box = CoveredJointBox(used);
    const RegionScore region =
        ScoreRegion(rc.nominal, rc.identified, true_model, box,
                    config.scoring_configurations, config.scoring_seed);
    json joints = json::array();
    for (int i = 0; i < box.lower.size(); ++i) {
      joints.push_back({{"joint", i + 1}, {"lower_deg", RadToDeg(box.lower(i))},
                        {"upper_deg", RadToDeg(box.upper(i))}});
    }
    json covered = Gauges(region.configurations, region.before, region.after);
    covered["poses"] = used.size();
    covered["joint_box_deg"] = joints;
    (*r)["truth_position_error_mm_covered_region"] = covered;
  }
}

// A robot's `identifiable_combinations` key: the observable combinations against truth, with
// the identification's covariance.
json IdentifiableCombinationsJson(const RobotCalibration& rc, const RobotScore& score,
                                  const ObservabilityReport& obs) {
  json combos = json::array();
  const IdentificationCovariance& cov = rc.covariance;
  for (size_t i = 0; i < score.combination_estimated.size(); ++i) {
    const bool has_sigma = cov.ok && static_cast<int>(i) < cov.sigma_z.size();
    combos.push_back({{"index", i}, {"estimated", 1000 * score.combination_estimated[i]},
                      {"true", 1000 * score.combination_true[i]},
                      {"sigma", has_sigma ? json(1000 * cov.sigma_z(i)) : json(nullptr)}});
  }
  json combinations = {{"count", obs.rank},
                       {"unit", "mm or mrad (scaled coordinates, 1 m)"},
                       {"rms_error", 1000 * score.combination_rms_error},
                       {"max_error", 1000 * score.combination_max_error},
                       {"items", combos}};
  combinations["covariance"] = {
      {"status", cov.ok ? "ok" : "not_estimated"},
      {"reason", cov.reason},
      {"residual_sigma_mm", 1000 * cov.residual_sigma},
      {"redundancy", cov.redundancy}};
  return combinations;
}

// A robot's `parameters` key: each parameter estimated against truth, in mm or deg.
json ParametersJson(const RobotScore& score, const IdentificationCovariance& cov) {
  json params = json::array();
  for (size_t k = 0; k < score.parameters.size(); ++k) {
    const ParameterComparison& p = score.parameters[k];
    const double f = p.length ? 1000.0 : RadToDeg(1.0);
    const bool has_sigma = cov.ok && static_cast<int>(k) < cov.sigma_parameters.size();
    params.push_back({{"name", p.name}, {"unit", p.length ? "mm" : "deg"},
                      {"estimated", f * p.estimated}, {"true", f * p.truth},
                      {"sigma", has_sigma ? json(f * cov.sigma_parameters(k)) : json(nullptr)}});
  }
  return params;
}

// A robot's `identification` key: both methods' outcomes, the refit and their difference.
json IdentificationJson(const RobotCalibration& rc) {
  const LinearizedIdentificationResult& lin = rc.linearized;
  const NonlinearIdentificationResult& nl = rc.nonlinear;
  json eps = json::array();
  for (double e : lin.eps_history) eps.push_back(1000 * e);
  return json{
      {"method", rc.method},
      {"time_s", rc.identification_s},
      {"linearized",
       {{"status", ToString(lin.status)}, {"reason", lin.reason}, {"iterations", lin.iterations},
        {"rank", lin.observability.rank}, {"eps_history_mm", eps},
        {"calibration_after_mm", Mm(lin.mean_misaligned_error_after)}}},
      {"nonlinear",
       {{"status", ToString(nl.status)}, {"iterations", nl.iterations},
        {"rank", nl.observability.rank}, {"passes", nl.passes},
        {"depth_used", nl.depth_used},
        {"singular_values", nl.observability.singular_values},
        {"depth_weight", nl.depth_weight},
        {"rms_distance_before_mm", Mm(nl.rms_distance_before)},
        {"rms_distance_after_mm", Mm(nl.rms_distance_after)},
        {"rms_depth_residual_mm", Mm(nl.rms_depth_residual)}}},
      {"delivered_model", rc.refit ? "all axes (refit after validation)" : "calibration axes"},
      {"refit_all_axes",
       rc.refit ? json{{"status", ToString(rc.refit_result.status)},
                       {"axes", rc.calibration_axes.size() + rc.validation_axes.size()},
                       {"rank", rc.refit_result.observability.rank},
                       {"passes", rc.refit_result.passes},
                       {"rms_distance_after_mm", Mm(rc.refit_result.rms_distance_after)},
                       {"rms_depth_residual_mm", Mm(rc.refit_result.rms_depth_residual)}}
                : json(nullptr)},
      {"linearized_vs_ceres_max_parameter_difference",
       lin.status == LinearizedIdentificationStatus::kSkipped ? json(nullptr) : json
       {{"mm", 1000 * [&] {
           double m = 0;
           for (int i = 0; i < lin.correction.size(); ++i)
             if (IsLengthParameter(i))
               m = std::max(m, std::abs(lin.correction(i) - nl.correction(i)));
           return m;
         }()},
        {"deg", RadToDeg([&] {
           double m = 0;
           for (int i = 0; i < lin.correction.size(); ++i)
             if (!IsLengthParameter(i))
               m = std::max(m, std::abs(lin.correction(i) - nl.correction(i)));
           return m;
         }())}}}};
}

// The value of `map` at `key`, or a default one where it has none (what operator[] reads).
template <typename Value>
Value ValueOrDefault(const std::map<int, Value>& map, int key) {
  const auto it = map.find(key);
  return it == map.end() ? Value() : it->second;
}

// Sets a robot's `diagnosis` key (and `declared_terms` where the diagnosis ran).
void AddDiagnosisJson(const RobotDiagnoses& diagnoses, int robot, json* r) {
  if (diagnoses.results.count(robot)) {
    (*r)["diagnosis"] = DiagnosisJson(diagnoses.results.at(robot));
    (*r)["declared_terms"] = ValueOrDefault(diagnoses.declared_terms, robot);
  } else {
    (*r)["diagnosis"] = {{"verdict", nullptr},
                         {"skipped", ValueOrDefault(diagnoses.skipped, robot)}};
  }
}

// What scoring a robot against truth needs besides its calibration.
struct RobotScoringInputs {
  const Scenario& sc;
  const CalibrationConfig& config;
  const TwinTruth& truth;           ///< read after the procedure ended
  const PinholeIntrinsics& ei;      ///< estimated intrinsics (the servo images' annotation)
  const RobotDiagnoses& diagnoses;  ///< model discovery per robot
  const fs::path& staging;          ///< where the servo images go
};

// One robot's report entry: planning, servo (its images written into staging), split, errors
// against truth, identification and diagnosis.
json RobotReportJson(const RobotCalibration& rc, const RobotScoringInputs& in) {
  const std::string name = in.sc.robot_names[rc.robot];
  const std::string camera = in.sc.robot_names[rc.camera_robot];
  const CalibrationConfig& config = in.config;
  const KinematicModel true_model =
      BoardRobotModel(in.truth.models[rc.robot], in.truth.board.X_FT);
  const ObservabilityReport& obs = rc.refit                    ? rc.refit_result.observability
                                   : rc.method == "linearized" ? rc.linearized.observability
                                                               : rc.nonlinear.observability;
  const RobotScore score = ScoreRobot(rc.nominal, rc.identified, true_model, obs,
                                      config.scoring_configurations, config.scoring_seed);
  json r;
  r["camera_robot"] = camera;
  r["planning"] = PlanningJson(rc, config.options.planner);
  r["servo"] = ServoJson(rc, name, in.ei, config.options.servo.tolerance_px, in.staging);
  if (std::isfinite(rc.temperature_reference_C)) {
    r["temperature_reference_C"] = rc.temperature_reference_C;
  }
  r["split"] = SplitJson(rc);
  r["misaligned_error_mm"] = MisalignedErrorJson(rc);
  r["truth_position_error_mm"] = Gauges(score);
  ScoreCoveredRegion(rc, true_model, config, &r);
  if (rc.refit) {
    // The calibration-set model too, so that the refit's gain is visible.
    const RobotScore held = ScoreRobot(rc.nominal, rc.holdout, true_model, obs,
                                       config.scoring_configurations, config.scoring_seed);
    r["truth_position_error_mm_calibration_set_model"] = Gauges(held);
  }
  r["scale"] = {{"estimated", score.scale_estimated}, {"true", score.scale_true},
                {"identified_length_ratio",
                 rc.refit ? rc.refit_result.scale : rc.nonlinear.scale}};
  r["unidentifiable"] = obs.unidentifiable;
  r["identifiable_combinations"] = IdentifiableCombinationsJson(rc, score, obs);
  r["parameters"] = ParametersJson(score, rc.covariance);
  r["identification"] = IdentificationJson(rc);
  AddDiagnosisJson(in.diagnoses, rc.robot, &r);
  return r;
}

// The robots' part of a calibration stage: report entries, measurements.csv, stage times.
struct RobotsReport {
  json robots = json::object();  ///< the report's `robots` key
  std::string csv;               ///< measurements.csv
  double planning = 0, planning_compute = 0, servoing = 0, identification = 0;  ///< sums [s]
};

// Scores each calibrated robot against truth into its report entry, writing its servo images
// and identified_<robot>.yaml into staging; collects measurements.csv and the stage times.
RobotsReport ReportRobots(const OpticalAxisResult& result, const RobotScoringInputs& in) {
  RobotsReport out;
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
    out.robots[name] = RobotReportJson(rc, in);
    AppendRows(rc, name, camera, csv_joints, &csv);
    // The identified model, ready to load (tool link = board mount, as identified).
    WriteText(in.staging / ("identified_" + name + ".yaml"), ModelToYaml(rc.identified));
  }
  out.csv = csv.str();
  return out;
}

// The report's `timing_s` key: the stages' times and the cell's frames and moves; `total` is
// the time since t_start, read now.
json TimingJson(Clock::time_point t_start, const OpticalAxisResult& result,
                const RobotsReport& robots, double diagnosis_s, double scoring,
                const TimedCell& timed) {
  return json{{"total", SecondsSince(t_start)}, {"intrinsics", result.intrinsics_s},
              {"intrinsics_detection", result.intrinsics.detect_s},
              {"intrinsics_zhang", result.intrinsics.calibrate_s},
              {"planning", robots.planning},      {"planning_compute", robots.planning_compute},
              {"servoing", robots.servoing},
              {"identification", robots.identification}, {"diagnosis", diagnosis_s},
              {"scoring", scoring},
              {"cell",
               {{"frames", timed.frames},
                {"region_frames", timed.region_frames},
                {"region_mean_pixels",
                 timed.region_frames > 0 ? json(timed.pixels / timed.region_frames)
                                         : json(nullptr)},
                {"grab_image", timed.grab_s},
                {"moves", timed.moves},
                {"move_to", timed.move_s}}}};
}

}  // namespace

OpticalAxisResult RunCalibrationStage(TwinCell& cell, const Scenario& sc, CalibrationConfig config,
                                    const fs::path& staging, bool quiet,
                                    std::chrono::steady_clock::time_point t_start, json* report,
                                    std::map<int, DiscoveryResult>* diagnoses) {
  // Progress lines with the time since t_start.
  config.options.progress = [&](const std::string& line) {
    if (quiet) return;
    std::printf("[%7.1f s] %s\n", SecondsSince(t_start), line.c_str());
    std::fflush(stdout);
  };
  // The procedure, on a cell that adds up where the time goes.
  TimedCell timed(cell);
  const OpticalAxisResult result = RunOpticalAxisCalibration(timed, config.knowledge,
                                                             config.options);

  // Model discovery per calibrated robot, before any truth is read.
  const auto t_diagnosis = Clock::now();
  RobotDiagnoses diagnosis = DiagnoseRobots(sc, config, result, quiet, t_start);
  const double diagnosis_s = SecondsSince(t_diagnosis);

  // Scoring: estimates meet truth only here, after the procedure ended.
  const auto t_score = Clock::now();
  const TwinTruth truth = cell.Truth();
  (*report)["scenario"] = ScenarioJson(sc);
  (*report)["intrinsics"] = IntrinsicsReportJson(result, truth, config.knowledge);
  // Each robot's entry, servo images and identified model; then measurements.csv.
  const RobotScoringInputs inputs{sc,        config,  truth, result.intrinsics.intrinsics,
                                  diagnosis, staging};
  const RobotsReport robots = ReportRobots(result, inputs);
  (*report)["robots"] = robots.robots;
  WriteText(staging / "measurements.csv", robots.csv);
  const double scoring = SecondsSince(t_score);
  // Where the time went.
  (*report)["timing_s"] = TimingJson(t_start, result, robots, diagnosis_s, scoring, timed);
  if (diagnoses) *diagnoses = std::move(diagnosis.results);
  return result;
}

namespace {

// What the physical-truth measurement of one robot compares: the twin moves the robot, and
// each settled pose is measured there and predicted by both models at the same readings.
struct PhysicalTruthSetup {
  TwinCell& cell;
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
  TwinCell& cell = s.cell;
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

// Both models' raw and rigid gauges against the measured truth, with the poses and `rule`.
json PhysicalGaugesJson(const PhysicalMeasurements& m, const std::string& rule) {
  const GaugeErrors calibrated = CompareInGauges(m.p_delivered, m.p_true);
  const GaugeErrors discovered = CompareInGauges(m.p_discovered, m.p_true);
  return json{
      {"poses", m.p_true.size()},
      {"rule", rule},
      {"calibrated_model", {{"raw", Stats(calibrated.raw)}, {"rigid", Stats(calibrated.rigid)}}},
      {"discovered_model", {{"raw", Stats(discovered.raw)}, {"rigid", Stats(discovered.rigid)}}}};
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
// over the region its aligned poses covered, into its report entry `r`.
void ScoreRobotPhysicalTruth(TwinCell& cell, const Scenario& sc, const CalibrationConfig& config,
                             const RobotCalibration& rc, const DiscoveryResult& diagnosis,
                             json* robot_report) {
  json& r = *robot_report;
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
    r["truth_position_error_mm_physical"] = {
        {"skipped", "fewer than 10 random poses settled"}};
    return;
  }
  r["truth_position_error_mm_physical"] = PhysicalGaugesJson(
      whole, "the board's feature point where the twin's physics puts it (every effect) "
             "at seeded random poses, against each model at the same readings");
  r["truth_position_error_mm_discovered_model"] =
      r["truth_position_error_mm_physical"]["discovered_model"];
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
      r["truth_position_error_mm_physical_covered_region"] = PhysicalGaugesJson(
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
void ScorePhysicalTruth(TwinCell& cell, const Scenario& sc, const CalibrationConfig& config,
                        const OpticalAxisResult& result,
                        const std::map<int, DiscoveryResult>& diagnoses, json* report) {
  for (const RobotCalibration& rc : result.robots) {
    const auto d = diagnoses.find(rc.robot);
    if (d == diagnoses.end()) continue;
    json& r = (*report)["robots"][sc.robot_names[rc.robot]];
    if (cell.Truth().board.robot != rc.robot) {
      r["truth_position_error_mm_physical"] = {
          {"skipped", "the board is on the other robot at the end of the procedure"}};
      continue;
    }
    // The whole joint space and the covered region, measured on the twin.
    ScoreRobotPhysicalTruth(cell, sc, config, rc, d->second, &r);
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

// Runs the calibration stage and the physical truth, judges the acceptance criteria into
// `report`, writes report.json (and report.html) and publishes the staging folder. On failure
// the staging folder is discarded and an InputError names the scenario file.
AcceptanceVerdict RunAndPublishReport(TwinCell& cell, const OpticalAxisRun& run, json* report) {
  AcceptanceVerdict verdict;
  try {
    std::printf("twinbench run: scenario %s (%s)\n", run.sc.name.c_str(), run.sc.path.c_str());
    std::map<int, DiscoveryResult> diagnoses;
    const OpticalAxisResult result = RunCalibrationStage(
        cell, run.sc, run.config, run.staging, run.options.quiet, run.t_start, report, &diagnoses);
    ScorePhysicalTruth(cell, run.sc, run.config, result, diagnoses, report);
    verdict = EvaluateAcceptance(run.acceptance, report);
    WriteText(run.staging / "report.json", report->dump(2) + "\n");
    if (run.options.images) WriteText(run.staging / "report.html", RenderReportHtml(*report));
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

// Prints one robot's lines of the run summary from its report entry (read with json's
// non-const operator[], as before the split).
void PrintRobotSummary(const std::string& name, json* robot_report) {
  json& r = *robot_report;
  // A figure the report holds as null, not computed, prints as nan.
  const auto D = [](const json& v) {
    return v.is_number() ? v.get<double>() : std::numeric_limits<double>::quiet_NaN();
  };
  for (const char* set : {"calibration", "validation"}) {
    const json& m = r["misaligned_error_mm"][set];
    if (m["before"].is_null()) continue;
    std::printf("%-6s %-22s %10.4f %10.4f %8.1f%%\n", name.c_str(),
                (std::string("misaligned ") + set).c_str(), D(m["before"]),
                D(m["after"]), D(m["decrease_percent"]));
  }
  for (const char* gauge : {"raw", "rigid", "similarity"}) {
    const json& g = r["truth_position_error_mm"][gauge];
    std::printf("%-6s %-22s %10.4f %10.4f   (max %.4f -> %.4f)\n", name.c_str(),
                (std::string("truth RMS ") + gauge).c_str(), D(g["before"]["rms"]),
                D(g["after"]["rms"]), D(g["before"]["max"]),
                D(g["after"]["max"]));
  }
  if (r.contains("truth_position_error_mm_covered_region")) {
    const json& c = r["truth_position_error_mm_covered_region"];
    std::printf("%-6s covered region (%d poses' joint box): truth RMS rigid %.4f -> %.4f, "
                "similarity %.4f -> %.4f\n",
                name.c_str(), c["poses"].get<int>(), D(c["rigid"]["before"]["rms"]),
                D(c["rigid"]["after"]["rms"]), D(c["similarity"]["before"]["rms"]),
                D(c["similarity"]["after"]["rms"]));
  }
  if (r.contains("truth_position_error_mm_calibration_set_model")) {
    const json& h = r["truth_position_error_mm_calibration_set_model"];
    std::printf("%-6s delivered model refit on all axes; the calibration-set model alone: "
                "truth RMS rigid %.4f, similarity %.4f\n",
                name.c_str(), D(h["rigid"]["after"]["rms"]),
                D(h["similarity"]["after"]["rms"]));
  }
  const json& dg = r["diagnosis"];
  if (dg["verdict"].is_null()) {
    std::printf("%-6s diagnosis skipped (%s)\n", name.c_str(),
                dg.value("skipped", std::string()).c_str());
  } else {
    std::printf("%-6s diagnosis: %s: %s\n", name.c_str(),
                dg["verdict"].get<std::string>().c_str(),
                dg["reason"].get<std::string>().c_str());
  }
  if (r.contains("truth_position_error_mm_physical") &&
      r["truth_position_error_mm_physical"].contains("poses")) {
    const json& ph = r["truth_position_error_mm_physical"];
    std::printf("%-6s physical truth (%d poses, rigid RMS): calibrated %.4f mm, discovered "
                "%.4f mm\n",
                name.c_str(), ph["poses"].get<int>(),
                D(ph["calibrated_model"]["rigid"]["rms"]),
                D(ph["discovered_model"]["rigid"]["rms"]));
  }
  if (r.contains("truth_position_error_mm_physical_covered_region")) {
    const json& ph = r["truth_position_error_mm_physical_covered_region"];
    std::printf("%-6s physical truth, covered region (%d poses, rigid RMS): calibrated %.4f "
                "mm, discovered %.4f mm\n",
                name.c_str(), ph["poses"].get<int>(),
                D(ph["calibrated_model"]["rigid"]["rms"]),
                D(ph["discovered_model"]["rigid"]["rms"]));
  }
  std::printf("%-6s scale estimated %.6f, true %.6f; servo %d aligned, %d failed, %.2f "
              "frames/pose\n",
              name.c_str(), D(r["scale"]["estimated"]),
              D(r["scale"]["true"]), r["servo"]["aligned_poses"].get<int>(),
              r["servo"]["failed_poses"].get<int>(),
              D(r["servo"]["mean_frames_per_pose"]));
}

// Prints the run summary read from the report: a table of each robot's figures, the timing and
// what was written into `out`.
void PrintRunSummary(json* report_json, const fs::path& out) {
  json& report = *report_json;
  std::printf("\n%-6s %-22s %10s %10s %9s\n", "robot", "metric [mm]", "before", "after",
              "decrease");
  for (const auto& [name, r] : report["robots"].items()) PrintRobotSummary(name, &r);
  const json& t = report["timing_s"];
  std::printf("timing [s]: total %.1f = intrinsics %.1f + waiting for the plans %.1f + "
              "servoing %.1f + identification %.1f + scoring %.1f (planning %.1f in the "
              "background)\n",
              t["total"].get<double>(), t["intrinsics"].get<double>(),
              t["planning"].get<double>(), t["servoing"].get<double>(),
              t["identification"].get<double>(), t["scoring"].get<double>(),
              t["planning_compute"].get<double>());
  const json& cell_t = report["timing_s"]["cell"];
  std::printf("cell: %d frames in %.1f s (GrabImage), %d moves in %.1f s (MoveTo)\n",
              cell_t["frames"].get<int>(), cell_t["grab_image"].get<double>(),
              cell_t["moves"].get<int>(), cell_t["move_to"].get<double>());
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

int RunCalibrationScenario(const RunOptions& o) {
  const auto t_start = Clock::now();
  Scenario sc = LoadScenario(o.scenario);
  ApplyTrial(o.trial, &sc);
  // Other procedures run elsewhere: the laser tracker, the handclasp, the dual-arm workflow.
  if (IsPresent(sc.tracker_calibration)) return RunTrackerScenario(o);
  if (IsPresent(sc.handclasp) && !IsPresent(sc.calibration)) {
    // base-frame calibration alone
    return RunHandclaspScenario(o.scenario, o.out_dir, std::cerr, o.trial, o.junit);
  }
  if (IsPresent(sc.handclasp) && IsPresent(sc.calibration)) return RunWorkflowScenario(o);
  // Everything is validated before anything is written: the sections, the output paths and
  // the cell itself (its initial pose must settle without collisions).
  CalibrationConfig config = ParseCalibrationConfig(sc);
  ApplyRunOptions(o, &config);
  const Acceptance acceptance = ParseAcceptance(sc);
  ValidateOutputFolder(o.out_dir, "--out");
  if (!o.junit.empty()) ValidateJunitFile(o.junit, o.out_dir);
  InstallMujocoErrorHandlers();
  TwinCell cell(sc.twin, sc.path);
  const fs::path out(o.out_dir);
  const fs::path staging = CreateStagingDirectory(o.out_dir);
  // The calibration, scored and judged, written and published as out_dir.
  json report;
  const AcceptanceVerdict verdict = RunAndPublishReport(
      cell, OpticalAxisRun{o, sc, config, acceptance, t_start, out, staging}, &report);
  // Summary read from the report.
  PrintRunSummary(&report, out);
  // JUnit file, verdict, exit code.
  if (!o.junit.empty()) WriteJunit(o.junit, sc.name, verdict, SecondsSince(t_start));
  PrintVerdict(verdict);
  return VerdictExitCode(verdict);
}

int CheckScenario(const std::string& scenario_path) {
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

// identification.json: the method, eq. 46 errors, unidentifiable parameters, scale and the
// corrections to the nominal model (mm or deg).
json IdentificationSummaryJson(const RobotCalibration& rc, const std::string& robot) {
  json j;
  j["robot"] = robot;
  j["method"] = rc.method;
  j["samples"] = rc.samples.size();
  j["misaligned_error_mm"] = {{"calibration", Misaligned(rc.calibration_error)},
                              {"validation", Misaligned(rc.validation_error)}};
  const NonlinearIdentificationResult& nl = rc.nonlinear;
  j["unidentifiable"] = (rc.method == "linearized" ? rc.linearized : rc.linearized).observability
                            .unidentifiable;
  if (rc.method != "linearized") j["unidentifiable"] = nl.observability.unidentifiable;
  j["scale"] = {{"identified_length_ratio", nl.scale}, {"depth_used", nl.depth_used}};
  json corr = json::object();
  const ParameterVector d = GetParameters(rc.identified) - GetParameters(rc.nominal);
  for (int i = 0; i < d.size(); ++i) {
    corr[ParameterName(robot, i)] = IsLengthParameter(i) ? 1000 * d(i) : RadToDeg(d(i));
  }
  j["correction_mm_or_deg"] = corr;
  return j;
}

// Writes identification.json and identified_<robot>.yaml into a staging folder and publishes it
// as out_dir (the staging folder discarded on failure).
void WriteIdentificationFiles(const std::string& out_dir, const json& j,
                              const RobotCalibration& rc, const std::string& robot) {
  const fs::path out(out_dir);
  const fs::path staging = CreateStagingDirectory(out_dir);
  try {
    WriteText(staging / "identification.json", j.dump(2) + "\n");
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
  const json j = IdentificationSummaryJson(rc, robot);
  const fs::path out(o.out_dir);
  WriteIdentificationFiles(o.out_dir, j, rc, robot);
  PrintIdentificationSummary(rc, robot, out);
  return 0;
}

}  // namespace twin
