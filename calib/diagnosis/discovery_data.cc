#include "calib/diagnosis/discovery_data.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "calib/common/errors.h"

namespace twin::discovery {

CrossValidation Data::InSample(const RobotModel& model, const std::string& what) const {
  (void)model;
  TWIN_REQUIRE(GlobalTest(), source() + ", " + what + ": no in-sample test for this data");
  return {};
}

Fit Identified(const RobotModel& model, MeasurementSet* set, const DiscoveryOptions& o,
               const std::string& source, bool all_data) {
  Fit f;
  IdentificationOptions engine = o.engine;
  engine.term_dependence = engine.term_dependence && all_data;
  f.result = Identify(model, {set}, engine);
  if (f.result.status == IdentificationStatus::kFailed) {
    throw InputError(source, "the identification failed: " + f.result.reason);
  }
  return f;
}

Eigen::Matrix<double, 3, Eigen::Dynamic> PositionJacobian(const RobotModel& model,
                                                          const MeasurementContext& c) {
  const double h = 1e-6;
  Eigen::Matrix<double, 3, Eigen::Dynamic> J(3, c.q.size());
  for (int i = 0; i < c.q.size(); ++i) {
    MeasurementContext plus = c, minus = c;
    plus.q(i) += h;
    minus.q(i) -= h;
    J.col(i) =
        (EndPose(model, plus).translation() - EndPose(model, minus).translation()) / (2.0 * h);
  }
  return J;
}

// ---- tracker points ------------------------------------------------------------------------

TrackerData::TrackerData(const RobotModel& start, const std::vector<TrackerPoint>& points,
                         const DiscoveryOptions& o)
    : points_(points), o_(o) {
  for (int i = 0; i < size(); ++i) {
    const double s = Sigma(i);
    Matrix3 S = s * s * Matrix3::Identity();
    if (o_.joint_sigma_rad > 0.0) {
      const auto J = PositionJacobian(start, points_[i].context);
      S += o_.joint_sigma_rad * o_.joint_sigma_rad * J * J.transpose();
    }
    covariance_.push_back(S);
  }
}

double TrackerData::Sigma(int i) const {
  return points_[i].sigma > 0.0 ? points_[i].sigma : o_.set.default_sigma;
}

Fit TrackerData::FitOn(const RobotModel& model, const std::vector<int>& train,
                       const std::string& what) const {
  TrackerSetOptions so = o_.set;
  so.source = o_.set.source + " (" + what + ")";
  std::vector<TrackerPoint> subset;
  if (train.empty()) {
    subset = points_;
  } else {
    for (int i : train) subset.push_back(points_[i]);
  }
  TrackerSet set(subset, so);
  Fit f = Identified(model, &set, o_, so.source, train.empty());
  f.X_TB = set.X_TB();
  return f;
}

void TrackerData::HeldOut(const Fit& fit, const std::vector<int>& test,
                          CrossValidation* cv) const {
  for (int i : test) {
    const Vector3 e =
        fit.X_TB * EndPose(fit.result.model, points_[i].context).translation() - points_[i].p_T;
    cv->e[i] = e;
    cv->loss[i] = e.squaredNorm();
    cv->dist2[i] = e.squaredNorm();
    cv->chi2[i] = e.dot(covariance_[i].ldlt().solve(e));
    cv->dof += 3.0;
  }
}

bool TrackerData::ResidualsInBase(const Fit& fit, std::vector<Eigen::VectorXd>* e) const {
  // HeldOut's e = X_TB p_B - p_T is in the tracker frame T.
  const Matrix3 R_BT = fit.X_TB.linear().transpose();
  for (Eigen::VectorXd& v : *e) {
    if (v.size() == 3) v = R_BT * Vector3(v);
  }
  return true;
}

Components TrackerData::ResidualComponents(const CrossValidation& cv) const {
  Components out{{"x", {}}, {"y", {}}, {"z", {}}, {"norm", {}}};
  for (const Eigen::VectorXd& e : cv.e) {
    for (int a = 0; a < 3; ++a) out[a].second.push_back(e(a));
    out[3].second.push_back(e.norm());
  }
  return out;
}

NoiseFloor TrackerNoise(const TrackerData& data, const DiscoveryOptions& o) {
  const std::vector<TrackerPoint>& points = data.points();
  NoiseFloor nf;
  double sum = 0, tracker = 0;
  int stated = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    sum += data.covariance()[i].trace() / 3.0;
    tracker += data.Sigma(i) * data.Sigma(i);
    if (points[i].sigma > 0.0) ++stated;
  }
  nf.sigma_m = std::sqrt(sum / points.size());
  nf.tracker_sigma_m = std::sqrt(tracker / points.size());
  nf.joint_sigma_rad = o.joint_sigma_rad;
  nf.source = stated == static_cast<int>(points.size())
                  ? "the sigma stated for each point"
                  : (stated == 0 ? "the set's default sigma (no point states one)"
                                 : "the stated sigmas, the set's default where a point has none");
  if (o.joint_sigma_rad > 0.0) {
    nf.source += ", with the stated joint reading noise through the model";
  }
  // Repeats of one pose (PoseGroups): their spread is the tracker's repeatability.
  const std::vector<int> pose_of = PoseGroups(points);
  std::vector<std::vector<int>> groups;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (pose_of[i] >= static_cast<int>(groups.size())) groups.resize(pose_of[i] + 1);
    groups[pose_of[i]].push_back(static_cast<int>(i));
  }
  double ss = 0;
  int dof = 0;
  for (const std::vector<int>& group : groups) {
    if (group.size() < 2) continue;
    ++nf.repeated_groups;
    Vector3 m = Vector3::Zero();
    for (int g : group) m += points[g].p_T;
    m /= group.size();
    for (int g : group) ss += (points[g].p_T - m).squaredNorm();
    dof += 3 * (static_cast<int>(group.size()) - 1);
  }
  if (dof > 0) nf.repeat_sigma_m = std::sqrt(ss / dof);
  return nf;
}

// ---- optical axes --------------------------------------------------------------------------

OpticalData::OpticalData(const RobotModel& start, const std::vector<AxisSample>& samples,
                         const DiscoveryOptions& o)
    : start_(start), samples_(samples), o_(o) {
  depth_ = o_.axis_set.use_depth &&
           std::all_of(samples_.begin(), samples_.end(),
                       [](const AxisSample& s) { return std::isfinite(s.depth); });
  for (const AxisSample& s : samples_) {
    contexts_.push_back(s.context());
    if (o_.joint_sigma_rad > 0.0) jacobians_.push_back(PositionJacobian(start, contexts_.back()));
  }
  for (const AxisSample& s : samples_) {
    if (std::find(axes_.begin(), axes_.end(), s.axis) == axes_.end()) axes_.push_back(s.axis);
  }
  std::sort(axes_.begin(), axes_.end());
}

std::string OpticalData::Where(int i) const {
  return "sample " + std::to_string(i + 1) + " (axis " + std::to_string(samples_[i].axis + 1) +
         ")";
}

double OpticalData::SigmaOffset(int i) const {
  return samples_[i].sigma_offset > 0.0 ? samples_[i].sigma_offset
                                        : o_.axis_set.sigma_perpendicular;
}

double OpticalData::SigmaDepth(int i) const {
  return samples_[i].sigma_depth > 0.0 ? samples_[i].sigma_depth : o_.axis_set.sigma_depth;
}

double OpticalData::JointVariancePerCoordinate(int i) const {
  return o_.joint_sigma_rad > 0.0
             ? o_.joint_sigma_rad * o_.joint_sigma_rad * jacobians_[i].squaredNorm() / 3.0
             : 0.0;
}

Fit OpticalData::FitOn(const RobotModel& model, const std::vector<int>& train,
                       const std::string& what) const {
  std::vector<int> units = train;
  if (units.empty()) {
    units.resize(samples_.size());
    std::iota(units.begin(), units.end(), 0);
  }
  // The set wants axes 0..q-1: renumber the training axes in order.
  std::vector<int> present;
  for (int i : units) present.push_back(samples_[i].axis);
  std::sort(present.begin(), present.end());
  present.erase(std::unique(present.begin(), present.end()), present.end());
  std::vector<AxisSample> subset;
  for (int i : units) {
    AxisSample s = samples_[i];
    s.axis = static_cast<int>(std::lower_bound(present.begin(), present.end(), s.axis) -
                              present.begin());
    subset.push_back(s);
  }
  OpticalAxisSetOptions so = o_.axis_set;
  so.use_depth = depth_;
  so.use_sample_sigmas = true;  // each sample's own noise where known (SigmaOffset)
  OpticalAxisSet set(subset, so);
  Fit f = Identified(model, &set, o_, o_.axis_source + " (" + what + ")", train.empty());
  f.axes = present;
  f.lines = set.lines();
  f.depth_offsets = set.depth_offsets();
  return f;
}

void OpticalData::HeldOut(const Fit& fit, const std::vector<int>& test,
                          CrossValidation* cv) const {
  // Group the fold's samples by axis; each axis is scored by its own line.
  std::vector<int> axes;
  for (int i : test) {
    if (std::find(axes.begin(), axes.end(), samples_[i].axis) == axes.end()) {
      axes.push_back(samples_[i].axis);
    }
  }
  for (int axis : axes) {
    std::vector<int> idx;
    std::vector<Vector3> p;
    for (int i : test) {
      if (samples_[i].axis != axis) continue;
      idx.push_back(i);
      p.push_back(EndPose(fit.result.model, contexts_[i]).translation() - samples_[i].offset);
    }
    const auto trained = std::find(fit.axes.begin(), fit.axes.end(), axis);
    Line3 line;
    double t = 0;
    const int dim = depth_ ? 3 : 2;
    if (trained != fit.axes.end()) {
      // The axis trained its line: the held-out samples are scored against it (3 rows each).
      line = fit.lines[trained - fit.axes.begin()];
      t = depth_ ? fit.depth_offsets[trained - fit.axes.begin()] : 0.0;
      cv->dof += dim * static_cast<double>(idx.size());
    } else {
      // A whole held-out axis: its own line and depth offset from its predicted points.
      line = FitLine(p);
      if (depth_) {
        double c = 0;
        for (std::size_t k = 0; k < idx.size(); ++k) {
          c += line.direction.dot(p[k] - line.point) * samples_[idx[k]].depth;
        }
        if (c < 0) line.direction = -line.direction;  // along growing depth
        for (std::size_t k = 0; k < idx.size(); ++k) {
          t += (line.direction.dot(p[k] - line.point) - samples_[idx[k]].depth) / idx.size();
        }
      }
      const double m = static_cast<double>(idx.size());
      cv->dof += depth_ ? 3.0 * m - 5.0 : 2.0 * m - 4.0;
    }
    Score(line, t, idx, p, cv);
  }
}

void OpticalData::Score(const Line3& line, double t, const std::vector<int>& idx,
                        const std::vector<Vector3>& p, CrossValidation* cv) const {
  const Vector3 mu = line.direction.normalized();
  Eigen::Matrix3d P;  // rows n1, n2, mu
  const Vector3 n1 = mu.unitOrthogonal();
  P.row(0) = n1.transpose();
  P.row(1) = mu.cross(n1).transpose();
  P.row(2) = mu.transpose();
  const int dim = depth_ ? 3 : 2;
  for (std::size_t k = 0; k < idx.size(); ++k) {
    const int i = idx[k];
    const double sp = SigmaOffset(i), sd = SigmaDepth(i);
    const Vector3 local = P * (p[k] - line.point);
    Eigen::VectorXd e(dim);
    e(0) = local(0);
    e(1) = local(1);
    if (depth_) e(2) = local(2) - t - samples_[i].depth;
    Eigen::MatrixXd S = Eigen::MatrixXd::Zero(dim, dim);
    S(0, 0) = S(1, 1) = sp * sp;
    if (depth_) S(2, 2) = sd * sd;
    if (o_.joint_sigma_rad > 0.0) {
      const Eigen::MatrixXd PJ = (P * jacobians_[i]).topRows(dim);
      S += o_.joint_sigma_rad * o_.joint_sigma_rad * PJ * PJ.transpose();
    }
    cv->e[i] = e;
    cv->dist2[i] = e.head<2>().squaredNorm();
    cv->loss[i] =
        e.head<2>().squaredNorm() / (sp * sp) + (depth_ ? e(2) * e(2) / (sd * sd) : 0.0);
    cv->chi2[i] = e.dot(S.ldlt().solve(e));
  }
}

CrossValidation OpticalData::InSample(const RobotModel& model, const std::string& what) const {
  DiscoveryOptions stated = o_;
  stated.engine.estimate_group_weights = false;  // the weights are the stated sigmas
  const OpticalData with_stated(start_, samples_, stated);
  const Fit all = with_stated.FitOn(model, {}, what);
  CrossValidation cv;
  const int n = size();
  cv.Resize(n);
  for (std::size_t k = 0; k < all.axes.size(); ++k) {
    std::vector<int> idx;
    std::vector<Vector3> p;
    for (int i = 0; i < n; ++i) {
      if (samples_[i].axis != all.axes[k]) continue;
      idx.push_back(i);
      p.push_back(EndPose(all.result.model, contexts_[i]).translation() - samples_[i].offset);
    }
    Score(all.lines[k], depth_ ? all.depth_offsets[k] : 0.0, idx, p, &cv);
  }
  cv.dof = all.result.redundancy;
  return cv;
}

Components OpticalData::ResidualComponents(const CrossValidation& cv) const {
  Components out{{"distance", {}}};
  if (depth_) out.push_back({"depth", {}});
  for (const Eigen::VectorXd& e : cv.e) {
    out[0].second.push_back(e.head<2>().norm());
    if (depth_) out[1].second.push_back(e(2));
  }
  return out;
}

NoiseFloor OpticalNoise(const OpticalData& data, const DiscoveryOptions& o) {
  NoiseFloor nf;
  nf.joint_sigma_rad = o.joint_sigma_rad;
  // RMS over the samples: of the offset's sigma per coordinate (joint noise included, averaged
  // over directions) for sigma_m, of the offset's and the depth's alone for the others.
  double sum = 0, offset = 0, depth = 0;
  int own = 0;
  for (int i = 0; i < data.size(); ++i) {
    offset += data.SigmaOffset(i) * data.SigmaOffset(i);
    depth += data.SigmaDepth(i) * data.SigmaDepth(i);
    sum += data.SigmaOffset(i) * data.SigmaOffset(i) + data.JointVariancePerCoordinate(i);
    if (data.samples()[i].sigma_offset > 0.0 && data.samples()[i].sigma_depth > 0.0) ++own;
  }
  const int n = std::max(1, data.size());
  nf.sigma_m = std::sqrt(sum / n);
  nf.tracker_sigma_m = std::sqrt(offset / n);
  nf.depth_sigma_m = data.depth() ? std::sqrt(depth / n) : -1.0;
  nf.source = own == data.size()
                  ? "each sample's own: the board pose's covariance (the corner noise the "
                    "intrinsics step measured, through the camera model)"
                  : (own == 0 ? "the stated sigmas of the offset (sigma_perpendicular) and of "
                                "the depth (sigma_depth)"
                              : "each sample's own where known, the stated sigmas elsewhere");
  if (o.joint_sigma_rad > 0.0) {
    nf.source += ", with the stated joint reading noise through the model";
  }
  return nf;
}

}  // namespace twin::discovery
