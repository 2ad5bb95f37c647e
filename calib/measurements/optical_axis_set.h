// The optical-axis measurements of one robot as a MeasurementSet (Zhu et al. 2019, section
// III.B, eq. 13-15, plus the depth scale measurement; residuals in optical_axis_residual.h):
// one nuisance line per axis, initialised by the total-least-squares fit of the nominal
// positions, and with depths one along-line offset per axis.
#pragma once

#include <vector>

#include "calib/measurements/measurement_set.h"
#include "calib/measurements/optical_axis_model.h"

namespace twin {

/// Options of an OpticalAxisSet.
struct OpticalAxisSetOptions {
  /// Use the samples' depths when every sample has one (the scale measurement).
  bool use_depth = true;
  /// Starting sigma of the perpendicular distance [m]: ~0.02 mm of servo residual.
  double sigma_perpendicular = 2e-5;
  /// Starting sigma of a depth [m]: ~0.1 mm from a small board's pose (DESIGN.md corner
  /// accuracy). Only the ratio of the two matters for the solution; both may be re-estimated.
  double sigma_depth = 1e-4;
  /// Huber threshold on a sample's perpendicular distance [m]; 0: plain least squares. Applied
  /// in whitened units with the starting sigma_perpendicular.
  double huber_scale = 0.0;
  /// Weight each sample by its own sigmas (AxisSample::sigma_offset, sigma_depth) where known,
  /// relative to the two above (which then scale the groups); false: every sample alike.
  bool use_sample_sigmas = false;
};

class OpticalAxisSet : public MeasurementSet {
 public:
  /// Throws InputError for bad samples (ValidateAxisSamples), PreconditionError for bad options.
  OpticalAxisSet(std::vector<AxisSample> samples, const OpticalAxisSetOptions& options = {});

  std::string kind() const override { return "optical_axis"; }
  int size() const override { return static_cast<int>(samples_.size()); }
  void Validate(const RobotModel& model) const override;
  void Initialize(const RobotModel& model) override;
  void AddResiduals(const RobotModel& model, double* params, ceres::Problem* problem) override;
  std::vector<NuisanceBlock> nuisance() override;
  std::vector<ResidualGroup> groups() override;
  /// Rotation about and translation along the z axis of L0 (link1.theta, link1.d) always;
  /// without depths also the uniform scale of every length (lines stay lines).
  std::vector<Eigen::VectorXd> Invariants(const RobotModel& model,
                                          const ParameterLayout& layout) const override;
  /// Perpendicular distance of each sample from its line [m].
  std::vector<double> ResidualNorms(const RobotModel& model) const override;

  /// Whether the depth residuals are in (use_depth and every sample has a depth).
  bool depth_used() const { return depth_; }
  int num_axes() const { return num_axes_; }
  /// The current lines (unit directions; after a solve, the identified ones).
  std::vector<Line3> lines() const;
  /// The initial lines (the fit of the nominal positions, oriented along growing depth).
  const std::vector<Line3>& initial_lines() const { return initial_; }
  /// RMS of (along-line position - t_k - depth) over the samples at the current values [m].
  double DepthRms(const RobotModel& model) const;
  /// The along-line offsets t_k of the depth residuals (current values; 0 without depths) [m].
  const std::vector<double>& depth_offsets() const { return t_; }
  /// Current weights (1 / sigma) of the perpendicular and depth residuals [1/m].
  double perpendicular_weight() const { return w_perp_; }
  double depth_weight() const { return w_depth_; }
  const std::vector<AxisSample>& samples() const { return samples_; }

 private:
  std::vector<AxisSample> samples_;
  OpticalAxisSetOptions options_;
  int num_axes_ = 0;
  bool depth_ = false;
  std::vector<Line3> initial_;
  std::vector<Vector3> c0_;
  std::vector<Eigen::Matrix<double, 3, 2>> N_;
  std::vector<Eigen::Vector2d> s_;
  std::vector<Vector3> mu_;
  std::vector<double> t_;
  double w_perp_ = 0.0, w_depth_ = 0.0;
  std::vector<ceres::ResidualBlockId> blocks_;
};

}  // namespace twin
