// Laser-tracker points of one robot as a MeasurementSet (sensor model and residual in
// tracker_point_residual.h): the reflector on the robot's tool measured in the tracker's frame;
// the tracker's pose X_TB is the nuisance, started from the rigid best fit (Kabsch) of the
// model's predicted points onto the measured ones, or from a told pose when there are too few
// points for a fit.
#pragma once

#include <optional>
#include <vector>

#include "calib/measurements/measurement_set.h"

namespace twin {

/// One tracker measurement.
struct TrackerPoint {
  MeasurementContext context;        ///< the robot's joint readings etc. for this point
  Vector3 p_T = Vector3::Zero();     ///< measured reflector position in the tracker frame [m]
  double sigma = 0.0;                ///< its standard deviation per axis [m]; 0: the set's default
  int row = 0;                       ///< source row (file line) for messages
};

/// Options of a TrackerSet.
struct TrackerSetOptions {
  double default_sigma = 1e-5;             ///< sigma of points without their own [m]
  std::optional<Transform> X_TB_told;      ///< told tracker pose (rough), if any
  std::string source = "tracker points";   ///< file or origin, for messages
};

class TrackerSet : public MeasurementSet {
 public:
  /// Throws InputError for an empty set, non-finite values or bad sigmas (naming the row).
  TrackerSet(std::vector<TrackerPoint> points, const TrackerSetOptions& options = {});

  std::string kind() const override { return "tracker_point"; }
  int size() const override { return static_cast<int>(points_.size()); }
  void Validate(const RobotModel& model) const override;
  void Initialize(const RobotModel& model) override;
  void AddResiduals(const RobotModel& model, double* params, ceres::Problem* problem) override;
  std::vector<NuisanceBlock> nuisance() override;
  std::vector<ResidualGroup> groups() override;
  /// None beyond what the numerical analysis finds: a rigid motion of the base is the
  /// tracker pose's, and the tracker sees absolute distances (scale).
  std::vector<Eigen::VectorXd> Invariants(const RobotModel&, const ParameterLayout&) const override {
    return {};
  }
  /// Distance between measured and predicted point [m].
  std::vector<double> ResidualNorms(const RobotModel& model) const override;

  /// The current tracker pose (after a solve, the identified one).
  Transform X_TB() const;
  /// Sets the tracker pose (e.g. the one identified on training data, to score held-out points).
  void SetX_TB(const Transform& X_TB);
  /// Predicted-minus-measured vectors in the tracker frame [m], one per point.
  std::vector<Vector3> Residuals(const RobotModel& model) const;
  const std::vector<TrackerPoint>& points() const { return points_; }

 private:
  std::vector<TrackerPoint> points_;
  TrackerSetOptions options_;
  Eigen::Vector4d q_TB_ = Eigen::Vector4d(0, 0, 0, 1);  // x, y, z, w
  Vector3 p_TB_ = Vector3::Zero();
  double weight_ = 1.0;
  std::vector<ceres::ResidualBlockId> blocks_;
};

/// The rigid transform X minimizing sum |X a_i - b_i|^2 (Kabsch / Umeyama without scale);
/// false when the points are fewer than 3 or collinear.
bool FitRigid(const std::vector<Vector3>& a, const std::vector<Vector3>& b, Transform* X);

/// Rows whose joint readings all agree to this are one pose measured again: far below any
/// commanded move, at the level of a few encoder counts behind the gear [rad].
constexpr double kSamePoseTolerance = 1e-6;

/// Per point, the index of its pose (numbered in order of first appearance): points whose joint
/// readings agree to kSamePoseTolerance on every joint are repeats of one pose. Repeats are no
/// independent points: held-out splits keep them together, point counts count poses.
std::vector<int> PoseGroups(const std::vector<TrackerPoint>& points);

}  // namespace twin
