#include "calib/measurements/tracker_set.h"

#include <cmath>

#include <Eigen/SVD>

#include "calib/common/errors.h"
#include "calib/measurements/point_measurement_cost.h"
#include "calib/measurements/tracker_point_residual.h"

namespace twin {

bool FitRigid(const std::vector<Vector3>& a, const std::vector<Vector3>& b, Transform* X) {
  if (a.size() < 3 || a.size() != b.size()) return false;
  Vector3 ca = Vector3::Zero(), cb = Vector3::Zero();
  for (size_t i = 0; i < a.size(); ++i) ca += a[i], cb += b[i];
  ca /= a.size();
  cb /= b.size();
  Matrix3 H = Matrix3::Zero();
  for (size_t i = 0; i < a.size(); ++i) H += (a[i] - ca) * (b[i] - cb).transpose();
  Eigen::JacobiSVD<Matrix3> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  // Collinear points leave a rotation about their line undetermined (second singular value 0).
  if (!(svd.singularValues()(1) > 1e-12 * svd.singularValues()(0))) return false;
  Matrix3 D = Matrix3::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Matrix3 R = svd.matrixV() * D * svd.matrixU().transpose();
  *X = Transform::Identity();
  X->linear() = R;
  X->translation() = cb - R * ca;
  return true;
}

TrackerSet::TrackerSet(std::vector<TrackerPoint> points, const TrackerSetOptions& options)
    : points_(std::move(points)), options_(options) {
  if (points_.empty()) throw InputError(options.source, "no tracker points");
  if (!(options.default_sigma > 0.0 && std::isfinite(options.default_sigma))) {
    throw InputError(options.source, "default sigma must be a positive finite number [m]");
  }
  for (TrackerPoint& p : points_) {
    const std::string where = options.source + ":" + std::to_string(p.row);
    if (!p.p_T.allFinite()) throw InputError(where, "measured point is not finite");
    if (!p.context.q.allFinite()) throw InputError(where, "joint readings are not finite");
    if (p.sigma == 0.0) p.sigma = options.default_sigma;
    if (!(p.sigma > 0.0 && std::isfinite(p.sigma))) {
      throw InputError(where, "sigma must be a positive finite number [m]");
    }
  }
}

void TrackerSet::Validate(const RobotModel& model) const {
  for (const TrackerPoint& p : points_) {
    const std::string where = options_.source + ":" + std::to_string(p.row);
    if (p.context.q.size() != model.chain.num_joints()) {
      throw InputError(where, std::to_string(p.context.q.size()) + " joint angles for the " +
                                  std::to_string(model.chain.num_joints()) + "-joint robot " +
                                  model.name());
    }
    const std::string missing = MissingContext(model, p.context);
    if (!missing.empty()) throw InputError(where, missing);
  }
}

void TrackerSet::Initialize(const RobotModel& model) {
  std::vector<Vector3> predicted, measured;
  for (const TrackerPoint& p : points_) {
    predicted.push_back(EndPose(model, p.context).translation());
    measured.push_back(p.p_T);
  }
  Transform X;
  if (!FitRigid(predicted, measured, &X)) {
    if (!options_.X_TB_told) {
      throw InputError(options_.source, "the tracker's pose cannot be fitted from " +
                                            std::to_string(points_.size()) +
                                            " points (fewer than 3, or collinear) and none was "
                                            "told");
    }
    X = *options_.X_TB_told;
  }
  SetX_TB(X);
  weight_ = 1.0;
}

void TrackerSet::SetX_TB(const Transform& X_TB) {
  const Eigen::Quaterniond q(X_TB.linear());
  q_TB_ << q.x(), q.y(), q.z(), q.w();
  q_TB_.normalize();
  p_TB_ = X_TB.translation();
}

Transform TrackerSet::X_TB() const {
  Transform X = Transform::Identity();
  X.linear() = Eigen::Quaterniond(q_TB_(3), q_TB_(0), q_TB_(1), q_TB_(2)).normalized().toRotationMatrix();
  X.translation() = p_TB_;
  return X;
}

void TrackerSet::AddResiduals(const RobotModel& model, double* params, ceres::Problem* problem) {
  blocks_.clear();
  for (const TrackerPoint& p : points_) {
    auto* cost = new PointMeasurementCost<TrackerPointResidual, 3, 4, 3>(
        model, p.context, new TrackerPointResidual{p.p_T, p.sigma, weight_});
    blocks_.push_back(problem->AddResidualBlock(cost, nullptr, {params, q_TB_.data(), p_TB_.data()}));
  }
  problem->SetManifold(q_TB_.data(), new ceres::EigenQuaternionManifold());
}

std::vector<NuisanceBlock> TrackerSet::nuisance() {
  return {{q_TB_.data(), 4, 3, "tracker rotation"}, {p_TB_.data(), 3, 3, "tracker position"}};
}

std::vector<ResidualGroup> TrackerSet::groups() {
  return {{"tracker", blocks_, 0, -1, &weight_, std::max(0, 3 * size() - 6)}};
}

std::vector<Vector3> TrackerSet::Residuals(const RobotModel& model) const {
  const Transform X = X_TB();
  std::vector<Vector3> out;
  for (const TrackerPoint& p : points_) {
    out.push_back(X * EndPose(model, p.context).translation() - p.p_T);
  }
  return out;
}

std::vector<double> TrackerSet::ResidualNorms(const RobotModel& model) const {
  std::vector<double> out;
  for (const Vector3& r : Residuals(model)) out.push_back(r.norm());
  return out;
}

std::vector<int> PoseGroups(const std::vector<TrackerPoint>& points) {
  std::vector<int> group(points.size(), -1);
  int groups = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (group[i] >= 0) continue;
    group[i] = groups;
    for (std::size_t k = i + 1; k < points.size(); ++k) {
      if (group[k] < 0 && points[k].context.q.size() == points[i].context.q.size() &&
          (points[k].context.q - points[i].context.q).cwiseAbs().maxCoeff() <=
              kSamePoseTolerance) {
        group[k] = groups;
      }
    }
    ++groups;
  }
  return group;
}

}  // namespace twin
