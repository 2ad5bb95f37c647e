// Model discovery's view of its data (internal to calib/diagnosis; model_discovery.h is the
// public interface): a unit of data is a tracker point or an optical-axis sample. Data says
// what the search needs of one kind of measurement: identify a model on some units, score the
// others held out against that fit, and give the per-unit context and residual components for
// the evidence. TrackerData and OpticalData are the two kinds, with their noise floors
// (model_discovery.h, steps 1 and "Optical axes").
#pragma once

#include <cmath>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "calib/diagnosis/model_discovery.h"

namespace twin::discovery {

/// One identification on a subset of the data.
struct Fit {
  IdentificationResult result;
  Transform X_TB = Transform::Identity();  ///< tracker points: the tracker pose
  /// Optical axes: the identified line and depth offset of each training axis (by its index).
  std::vector<int> axes;
  std::vector<Line3> lines;
  std::vector<double> depth_offsets;
};

/// Held-out residuals of one cross-validation, per unit of data (a point, a sample): e[i] from
/// the model trained without i's fold.
struct CrossValidation {
  std::vector<Eigen::VectorXd> e;  ///< the unit's residual [m]
  std::vector<double> loss;        ///< what gains and the paired test compare
  std::vector<double> dist2;       ///< squared distance, of the reported RMS [m^2]
  std::vector<double> chi2;        ///< e^T Sigma^-1 e against the noise floor [-]
  double dof = 0;                  ///< of sum(chi2)
  double unknowns = 0;             ///< mean over folds of the fit's unknowns
  double train_rows = 0;           ///< mean over folds of the training residual rows
  /// Sized for n units, every entry empty or zero.
  void Resize(int n) {
    e.assign(n, Eigen::VectorXd());
    loss.assign(n, 0.0);
    dist2.assign(n, 0.0);
    chi2.assign(n, 0.0);
  }
  double Sse() const { return std::accumulate(loss.begin(), loss.end(), 0.0); }
  double Rms() const {
    return dist2.empty() ? 0.0
                         : std::sqrt(std::accumulate(dist2.begin(), dist2.end(), 0.0) /
                                     dist2.size());
  }
};

/// Named per-unit components of the residual ("x", "norm", "distance", ...).
using Components = std::vector<std::pair<std::string, std::vector<double>>>;

/// What the search needs of one kind of measurement.
class Data {
 public:
  virtual ~Data() = default;
  virtual int size() const = 0;
  virtual const std::string& source() const = 0;
  virtual const MeasurementContext& context(int i) const = 0;
  virtual std::string Where(int i) const = 0;   ///< "row 12", for messages
  virtual double Order(int i) const = 0;        ///< acquisition order
  virtual std::string Measured() const = 0;     ///< "these points", for notes
  /// Identifies `model` on the units `train` (all when empty); throws InputError where the
  /// identification fails (`what` names the fit in the message).
  virtual Fit FitOn(const RobotModel& model, const std::vector<int>& train,
                    const std::string& what) const = 0;
  /// Residual rows of the units `train` in a fit.
  virtual double Rows(const std::vector<int>& train) const = 0;
  /// Fills cv's entries of the units `test` (a fold) from `fit`, adds their dof.
  virtual void HeldOut(const Fit& fit, const std::vector<int>& test, CrossValidation* cv) const = 0;
  /// Named per-unit components of the residual for the evidence.
  virtual Components ResidualComponents(const CrossValidation& cv) const = 0;
  /// The units' residuals `e` (of HeldOut with `fit`) turned into the robot's base frame B, in
  /// place; false (e unchanged) where a residual is not a vector in a frame of the cell (an
  /// optical axis's distance from its line).
  virtual bool ResidualsInBase(const Fit& fit, std::vector<Eigen::VectorXd>* e) const {
    (void)fit;
    (void)e;
    return false;
  }
  /// Whether the residual test is the adjustment's global test (InSample) rather than
  /// held-out (model_discovery.h, "Optical axes").
  virtual bool GlobalTest() const { return false; }
  /// The in-sample residuals of `model` fitted on every unit with the stated weights; dof the
  /// redundancy. Only where GlobalTest().
  virtual CrossValidation InSample(const RobotModel& model, const std::string& what) const;
};

/// The identification of `model` on `set`; `all_data`: the fit on every unit, the only one
/// whose term_dependence the search reads (the disguise check). Throws InputError (naming
/// `source`) where it fails.
Fit Identified(const RobotModel& model, MeasurementSet* set, const DiscoveryOptions& o,
               const std::string& source, bool all_data);

/// The end point's position Jacobian in the joint angles at `c`, by central differences of
/// `model` [m/rad].
Eigen::Matrix<double, 3, Eigen::Dynamic> PositionJacobian(const RobotModel& model,
                                                          const MeasurementContext& c);

/// Laser-tracker points. Per point the covariance sigma_i^2 I + sigma_q^2 J J^T
/// (model_discovery.h, step 1), J from `start`.
class TrackerData : public Data {
 public:
  TrackerData(const RobotModel& start, const std::vector<TrackerPoint>& points,
              const DiscoveryOptions& o);
  int size() const override { return static_cast<int>(points_.size()); }
  const std::string& source() const override { return o_.set.source; }
  const MeasurementContext& context(int i) const override { return points_[i].context; }
  std::string Where(int i) const override { return "row " + std::to_string(points_[i].row); }
  double Order(int i) const override { return points_[i].row; }
  std::string Measured() const override { return "these points"; }
  Fit FitOn(const RobotModel& model, const std::vector<int>& train,
            const std::string& what) const override;
  double Rows(const std::vector<int>& train) const override { return 3.0 * train.size(); }
  void HeldOut(const Fit& fit, const std::vector<int>& test, CrossValidation* cv) const override;
  Components ResidualComponents(const CrossValidation& cv) const override;
  bool ResidualsInBase(const Fit& fit, std::vector<Eigen::VectorXd>* e) const override;

  /// The point's stated sigma, else the set's default [m].
  double Sigma(int i) const;
  const std::vector<TrackerPoint>& points() const { return points_; }
  const std::vector<Matrix3>& covariance() const { return covariance_; }
  /// The stated joint noise (DiscoveryOptions::joint_sigma_rad) [rad]; 0: none. The fit
  /// (FitOn) weighs each point by Sigma(i) alone; covariance() adds this noise.
  double joint_sigma_rad() const { return o_.joint_sigma_rad; }

 private:
  std::vector<TrackerPoint> points_;
  const DiscoveryOptions& o_;
  std::vector<Matrix3> covariance_;
};

/// Step 1 for tracker points: the stated (or default) sigmas with the joint noise, and the
/// spread of repeated poses.
NoiseFloor TrackerNoise(const TrackerData& data, const DiscoveryOptions& o);

/// Optical-axis samples (model_discovery.h, "Optical axes").
class OpticalData : public Data {
 public:
  OpticalData(const RobotModel& start, const std::vector<AxisSample>& samples,
              const DiscoveryOptions& o);
  int size() const override { return static_cast<int>(samples_.size()); }
  const std::string& source() const override { return o_.axis_source; }
  const MeasurementContext& context(int i) const override { return contexts_[i]; }
  std::string Where(int i) const override;
  double Order(int i) const override { return i; }
  std::string Measured() const override { return "the optical axes (the line constraint)"; }
  Fit FitOn(const RobotModel& model, const std::vector<int>& train,
            const std::string& what) const override;
  double Rows(const std::vector<int>& train) const override {
    return (depth_ ? 3.0 : 2.0) * train.size();
  }
  void HeldOut(const Fit& fit, const std::vector<int>& test, CrossValidation* cv) const override;
  bool GlobalTest() const override { return true; }
  CrossValidation InSample(const RobotModel& model, const std::string& what) const override;
  Components ResidualComponents(const CrossValidation& cv) const override;

  /// Whether every sample has a depth and the options use depths.
  bool depth() const { return depth_; }
  /// Distinct axis indices, ascending.
  const std::vector<int>& axes() const { return axes_; }
  /// Sample i's noise: its own (the board pose's covariance) where known, else the stated
  /// one [m].
  double SigmaOffset(int i) const;
  double SigmaDepth(int i) const;
  /// The stated joint noise at sample i through the model, averaged over directions [m^2].
  double JointVariancePerCoordinate(int i) const;
  const std::vector<AxisSample>& samples() const { return samples_; }

 private:
  // The residual of samples idx (points p on their axis) against `line` and depth offset t.
  void Score(const Line3& line, double t, const std::vector<int>& idx,
             const std::vector<Vector3>& p, CrossValidation* cv) const;

  RobotModel start_;
  std::vector<AxisSample> samples_;
  const DiscoveryOptions& o_;
  bool depth_ = false;
  std::vector<MeasurementContext> contexts_;
  std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>> jacobians_;
  std::vector<int> axes_;  // distinct axis indices, ascending
};

/// The noise floor of optical-axis samples: each sample's own sigmas where stated, else the
/// options', with the joint noise.
NoiseFloor OpticalNoise(const OpticalData& data, const DiscoveryOptions& o);

}  // namespace twin::discovery
