#include "bench/runs/synthetic_measurements.h"

#include <cmath>
#include <cstdio>
#include <random>
#include <sstream>

#include "bench/io/measurements_csv.h"
#include "bench/io/model_loader.h"
#include "bench/io/output_files.h"
#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "calib/kinematics/inverse_kinematics.h"
#include "calib/model/parameters.h"

namespace twin {

int RunSynthesizeMeasurements(const SynthesizeOptions& o) {
  ValidateOutputFile(o.out, "--out");  // a new file only: a CSV carries no mark of ours
  constexpr int kAxes = 5;
  if (o.rows < 3 * kAxes || o.rows > 1000000) {
    throw InputError("--rows", "expected 15 to 1000000 rows, got " + std::to_string(o.rows));
  }
  const KinematicModel nominal = LoadRobotModelAndWarn(o.model, o.links);
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  ParameterVector phi = GetParameters(nominal);
  for (int i = 0; i < phi.size(); ++i) phi(i) += (IsLengthParameter(i) ? 1e-3 : DegToRad(0.1)) * u(rng);
  const KinematicModel truth = WithParameters(nominal, phi);
  const Vector3 camera(0.35, -0.45, 0.75);
  const Vector3 centre(0.45, 0.0, 0.30);
  const Vector3 offsets[kAxes] = {{0, 0, 0}, {0.12, 0.10, 0}, {-0.12, 0.10, 0.05},
                                  {0.10, -0.08, -0.10}, {-0.10, -0.05, 0.10}};
  std::ostringstream csv;
  csv << MeasurementsCsvHeader(nominal.num_joints()) << '\n';
  IkOptions ik;
  ik.random_restarts = 20;
  JointVector seed_q = MidRange(truth);
  for (int k = 0; k < kAxes; ++k) {
    const int n = o.rows / kAxes + (k < o.rows % kAxes ? 1 : 0);
    const Vector3 mu = (centre + offsets[k] - camera).normalized();
    const double mid = (centre + offsets[k] - camera).norm();
    Matrix3 facing;  // z axis back along the axis, towards the camera
    facing.col(2) = -mu;
    facing.col(0) = mu.cross(Vector3::UnitZ()).normalized();
    facing.col(1) = facing.col(2).cross(facing.col(0));
    for (int i = 0; i < n; ++i) {
      const double depth = mid - 0.09 + 0.18 * i / std::max(1, n - 1);  // 180 mm along the axis
      Transform X = Transform::Identity();
      X.linear() = Eigen::AngleAxisd(DegToRad(20.0) * u(rng), facing.col(0)) * facing;
      X.translation() = camera + depth * mu;
      IkResult r = SolveIk(truth, X, seed_q, ik);
      if (r.status != IkStatus::kSuccess) {
        throw InputError(o.model, "axis " + std::to_string(k) + " point " + std::to_string(i) +
                                      " is out of this arm's reach: " + r.reason +
                                      " (the synthetic cell suits arms of about 1 m reach)");
      }
      seed_q = r.q;
      MeasurementRow row;
      row.robot = "r2";
      row.camera_robot = "r1";
      row.axis = k;
      row.index = i;
      row.set = k < 3 ? "calibration" : "validation";
      row.q = r.q;
      for (int j = 0; j < r.q.size(); ++j) row.q(j) += DegToRad(0.001) * noise(rng);
      row.du_px = row.dv_px = 0.0;
      row.depth_m = depth;
      row.frames = 1;
      row.moves = 0;
      csv << MeasurementsCsvRow(row, nominal.num_joints()) << '\n';
    }
  }
  WriteFileAtomically(o.out, csv.str());
  std::printf("wrote %d rows to %s\n", o.rows, o.out.c_str());
  return 0;
}

}  // namespace twin
