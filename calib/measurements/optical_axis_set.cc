#include "calib/measurements/optical_axis_set.h"

#include <cmath>

#include "calib/common/errors.h"
#include "calib/measurements/optical_axis_residual.h"
#include "calib/measurements/point_measurement_cost.h"
#include "calib/model/parameters.h"

namespace twin {
namespace {

bool AllHaveDepth(const std::vector<AxisSample>& samples) {
  for (const AxisSample& s : samples) {
    if (!std::isfinite(s.depth)) return false;
  }
  return !samples.empty();
}

Eigen::Matrix<double, 3, 2> PlaneBasis(const Vector3& mu) {
  const Vector3 any = std::abs(mu.x()) < 0.9 ? Vector3::UnitX() : Vector3::UnitY();
  Eigen::Matrix<double, 3, 2> N;
  N.col(0) = mu.cross(any).normalized();
  N.col(1) = mu.cross(N.col(0));
  return N;
}

Vector3 PointOf(const RobotModel& model, const AxisSample& s) {
  return EndPose(model, s.context()).translation() - s.offset;
}

}  // namespace

OpticalAxisSet::OpticalAxisSet(std::vector<AxisSample> samples,
                               const OpticalAxisSetOptions& options)
    : samples_(std::move(samples)), options_(options) {
  num_axes_ = ValidateAxisSamples(samples_);
  // The options come from the identification's own (no user sets them): a bad one is our bug.
  TWIN_REQUIRE(options.huber_scale >= 0.0 && std::isfinite(options.huber_scale),
               "huber_scale must be a finite number >= 0 [m], got " +
                   std::to_string(options.huber_scale));
  TWIN_REQUIRE(options.sigma_perpendicular > 0.0 && options.sigma_depth > 0.0 &&
                   std::isfinite(options.sigma_perpendicular) &&
                   std::isfinite(options.sigma_depth),
               "sigma_perpendicular and sigma_depth must be positive finite numbers [m], got " +
                   std::to_string(options.sigma_perpendicular) + " and " +
                   std::to_string(options.sigma_depth));
  depth_ = options.use_depth && AllHaveDepth(samples_);
}

void OpticalAxisSet::Validate(const RobotModel& model) const {
  for (size_t i = 0; i < samples_.size(); ++i) {
    const AxisSample& s = samples_[i];
    if (s.q.size() != model.chain.num_joints()) {
      throw InputError("samples[" + std::to_string(i) + "].q",
                       std::to_string(s.q.size()) + " joint angles for the " +
                           std::to_string(model.chain.num_joints()) + "-joint robot " +
                           model.name());
    }
    const std::string missing = MissingContext(model, s.context());
    if (!missing.empty()) throw InputError("samples[" + std::to_string(i) + "]", missing);
  }
}

void OpticalAxisSet::Initialize(const RobotModel& model) {
  std::vector<std::vector<Vector3>> points(num_axes_);
  for (const AxisSample& s : samples_) points[s.axis].push_back(PointOf(model, s));
  initial_.clear();
  for (const auto& p : points) initial_.push_back(FitLine(p));
  if (depth_) {
    // Orient each direction so that the measured depth grows along it.
    for (int k = 0; k < num_axes_; ++k) {
      double ma = 0, mz = 0, cov = 0;
      int n = 0;
      for (size_t i = 0; i < samples_.size(); ++i) {
        if (samples_[i].axis != k) continue;
        ma += (PointOf(model, samples_[i]) - initial_[k].point).dot(initial_[k].direction);
        mz += samples_[i].depth;
        ++n;
      }
      ma /= n;
      mz /= n;
      for (const AxisSample& s : samples_) {
        if (s.axis != k) continue;
        const double a = (PointOf(model, s) - initial_[k].point).dot(initial_[k].direction);
        cov += (a - ma) * (s.depth - mz);
      }
      if (cov < 0) initial_[k].direction = -initial_[k].direction;
    }
  }
  c0_.assign(num_axes_, Vector3::Zero());
  N_.assign(num_axes_, Eigen::Matrix<double, 3, 2>::Zero());
  s_.assign(num_axes_, Eigen::Vector2d::Zero());
  mu_.assign(num_axes_, Vector3::UnitZ());
  t_.assign(num_axes_, 0.0);
  std::vector<int> count(num_axes_, 0);
  for (int k = 0; k < num_axes_; ++k) {
    c0_[k] = initial_[k].point;
    mu_[k] = initial_[k].direction.normalized();
    N_[k] = PlaneBasis(mu_[k]);
  }
  if (depth_) {
    for (const AxisSample& s : samples_) {
      t_[s.axis] += (PointOf(model, s) - c0_[s.axis]).dot(mu_[s.axis]) - s.depth;
      ++count[s.axis];
    }
    for (int k = 0; k < num_axes_; ++k) t_[k] /= count[k];
  }
  w_perp_ = 1.0 / options_.sigma_perpendicular;
  w_depth_ = 1.0 / options_.sigma_depth;
}

void OpticalAxisSet::AddResiduals(const RobotModel& model, double* params,
                                  ceres::Problem* problem) {
  blocks_.clear();
  for (const AxisSample& smp : samples_) {
    const int k = smp.axis;
    const bool own = options_.use_sample_sigmas;
    const double scale = own && smp.sigma_offset > 0.0
                             ? options_.sigma_perpendicular / smp.sigma_offset : 1.0;
    const double depth_scale =
        own && smp.sigma_depth > 0.0 ? options_.sigma_depth / smp.sigma_depth : 1.0;
    const OpticalAxisLine line{smp.offset, c0_[k], N_[k], w_perp_, scale};
    // A Huber loss on the whole block (the perpendicular rows dominate it).
    ceres::LossFunction* loss =
        options_.huber_scale > 0.0
            ? new ceres::HuberLoss(options_.huber_scale / options_.sigma_perpendicular)
            : nullptr;
    if (depth_) {
      auto* cost = new PointMeasurementCost<OpticalAxisLineDepth, 4, 2, 3, 1>(
          model, smp.context(), new OpticalAxisLineDepth{line, smp.depth, w_depth_, depth_scale});
      blocks_.push_back(problem->AddResidualBlock(
          cost, loss, {params, s_[k].data(), mu_[k].data(), &t_[k]}));
    } else {
      auto* cost = new PointMeasurementCost<OpticalAxisLine, 3, 2, 3>(
          model, smp.context(), new OpticalAxisLine(line));
      blocks_.push_back(
          problem->AddResidualBlock(cost, loss, {params, s_[k].data(), mu_[k].data()}));
    }
  }
  for (int k = 0; k < num_axes_; ++k) {
    problem->SetManifold(mu_[k].data(), new ceres::SphereManifold<3>());
  }
}

std::vector<NuisanceBlock> OpticalAxisSet::nuisance() {
  std::vector<NuisanceBlock> out;
  for (int k = 0; k < num_axes_; ++k) {
    const std::string axis = "axis " + std::to_string(k);
    out.push_back({s_[k].data(), 2, 2, axis + " point"});
    out.push_back({mu_[k].data(), 3, 2, axis + " direction"});
    if (depth_) out.push_back({&t_[k], 1, 1, axis + " camera offset"});
  }
  return out;
}

std::vector<ResidualGroup> OpticalAxisSet::groups() {
  const int n = size();
  // A perpendicular residual has 2 independent rows (it lies in the plane normal to the line);
  // each line takes 4 of them. A depth has 1 row; each axis offset takes 1.
  std::vector<ResidualGroup> out = {
      {"perpendicular", blocks_, 0, 3, &w_perp_, std::max(0, 2 * n - 4 * num_axes_)}};
  if (depth_) out.push_back({"depth", blocks_, 3, 1, &w_depth_, std::max(0, n - num_axes_)});
  return out;
}

std::vector<Eigen::VectorXd> OpticalAxisSet::Invariants(const RobotModel& model,
                                                        const ParameterLayout& layout) const {
  const int n = layout.size();
  const Eigen::VectorXd phi = GetParameters(model.chain);
  Eigen::VectorXd rotation = Eigen::VectorXd::Zero(n), translation = Eigen::VectorXd::Zero(n);
  rotation(ParameterIndex(1, DhParameter::kTheta)) = 1.0;
  translation(ParameterIndex(1, DhParameter::kD)) = 1.0;
  std::vector<Eigen::VectorXd> out = {rotation, translation};
  if (!depth_) {
    Eigen::VectorXd scale = Eigen::VectorXd::Zero(n);
    for (int i = 0; i < layout.geometry_size(); ++i) {
      if (IsLengthParameter(i)) scale(i) = phi(i);
    }
    out.push_back(scale);
  }
  return out;
}

std::vector<Line3> OpticalAxisSet::lines() const {
  std::vector<Line3> out(num_axes_);
  for (int k = 0; k < num_axes_; ++k) {
    out[k].direction = mu_[k].normalized();
    out[k].point = c0_[k] + N_[k] * s_[k];
  }
  return out;
}

std::vector<double> OpticalAxisSet::ResidualNorms(const RobotModel& model) const {
  const std::vector<Line3> l = lines();
  std::vector<double> out;
  for (const AxisSample& s : samples_) {
    const Vector3 d = PointOf(model, s) - l[s.axis].point;
    const Vector3& mu = l[s.axis].direction;
    out.push_back((d - mu * d.dot(mu)).norm());
  }
  return out;
}

double OpticalAxisSet::DepthRms(const RobotModel& model) const {
  if (!depth_) return 0.0;
  const std::vector<Line3> l = lines();
  double sum = 0.0;
  for (const AxisSample& s : samples_) {
    const double r =
        (PointOf(model, s) - l[s.axis].point).dot(l[s.axis].direction) - t_[s.axis] - s.depth;
    sum += r * r;
  }
  return std::sqrt(sum / samples_.size());
}

}  // namespace twin
