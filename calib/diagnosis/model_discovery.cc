#include "calib/diagnosis/model_discovery.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>
#include <random>
#include <sstream>
#include <thread>

#include "calib/common/cpus.h"
#include "calib/common/errors.h"
#include "calib/diagnosis/statistics.h"

namespace twin {
namespace {

std::string Mm(double m) {
  std::ostringstream os;
  os.precision(4);
  os << 1e3 * m << " mm";
  return os.str();
}

// One identification on a subset of the data.
struct Fit {
  IdentificationResult result;
  Transform X_TB = Transform::Identity();  // tracker points
  // Optical axes: the identified line and depth offset of each training axis (by its index).
  std::vector<int> axes;
  std::vector<Line3> lines;
  std::vector<double> depth_offsets;
};

// Held-out residuals of one cross-validation, per unit of data (a point, a sample): e[i] from
// the model trained without i's fold.
struct CrossValidation {
  std::vector<Eigen::VectorXd> e;  // the unit's residual [m]
  std::vector<double> loss;        // what gains and the paired test compare
  std::vector<double> dist2;       // squared distance, of the reported RMS [m^2]
  std::vector<double> chi2;        // e^T Sigma^-1 e against the noise floor [-]
  double dof = 0;                  // of sum(chi2)
  double unknowns = 0;             // mean over folds of the fit's unknowns
  double train_rows = 0;           // mean over folds of the training residual rows
  double Sse() const { return std::accumulate(loss.begin(), loss.end(), 0.0); }
  double Rms() const {
    return dist2.empty() ? 0.0
                         : std::sqrt(std::accumulate(dist2.begin(), dist2.end(), 0.0) /
                                     dist2.size());
  }
};

// What the search needs of one kind of measurement.
class Data {
 public:
  virtual ~Data() = default;
  virtual int size() const = 0;
  virtual const std::string& source() const = 0;
  virtual const MeasurementContext& context(int i) const = 0;
  virtual std::string Where(int i) const = 0;   // "row 12", for messages
  virtual double Order(int i) const = 0;        // acquisition order
  virtual std::string Measured() const = 0;     // "these points", for notes
  /// Identifies `model` on the units `train` (all when empty).
  virtual Fit FitOn(const RobotModel& model, const std::vector<int>& train,
                    const std::string& what) const = 0;
  /// Residual rows of the units `train` in a fit.
  virtual double Rows(const std::vector<int>& train) const = 0;
  /// Fills cv's entries of the units `test` (a fold) from `fit`, adds their dof.
  virtual void HeldOut(const Fit& fit, const std::vector<int>& test, CrossValidation* cv) const = 0;
  /// Named per-unit components of the residual for the evidence.
  virtual std::vector<std::pair<std::string, std::vector<double>>> Components(
      const CrossValidation& cv) const = 0;
  /// Whether the residual test is the adjustment's global test (InSample) rather than
  /// held-out (header, "Optical axes").
  virtual bool GlobalTest() const { return false; }
  /// The in-sample residuals of `model` fitted on every unit with the stated weights; dof the
  /// redundancy.
  virtual CrossValidation InSample(const RobotModel& model, const std::string& what) const {
    (void)model;
    throw InputError(source(), what + ": no in-sample test for this data");
  }
};

// `all_data`: the fit on every unit, the only one whose term_dependence the search reads (the
// disguise check); cross-validation folds skip it.
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

// ---- tracker points ------------------------------------------------------------------------

double SigmaOf(const TrackerPoint& p, const DiscoveryOptions& o) {
  return p.sigma > 0.0 ? p.sigma : o.set.default_sigma;
}

// Per point: sigma_i^2 I + sigma_q^2 J J^T (header), J by central differences of `model`.
Eigen::Matrix<double, 3, Eigen::Dynamic> PositionJacobian(const RobotModel& model,
                                                          const MeasurementContext& c) {
  const double h = 1e-6;
  Eigen::Matrix<double, 3, Eigen::Dynamic> J(3, c.q.size());
  for (int i = 0; i < c.q.size(); ++i) {
    MeasurementContext plus = c, minus = c;
    plus.q(i) += h;
    minus.q(i) -= h;
    J.col(i) = (EndPose(model, plus).translation() - EndPose(model, minus).translation()) / (2.0 * h);
  }
  return J;
}

class TrackerData : public Data {
 public:
  TrackerData(const RobotModel& start, const std::vector<TrackerPoint>& points,
              const DiscoveryOptions& o)
      : points_(points), o_(o) {
    for (const TrackerPoint& p : points_) {
      const double s = SigmaOf(p, o_);
      Matrix3 S = s * s * Matrix3::Identity();
      if (o_.joint_sigma_rad > 0.0) {
        const auto J = PositionJacobian(start, p.context);
        S += o_.joint_sigma_rad * o_.joint_sigma_rad * J * J.transpose();
      }
      covariance_.push_back(S);
    }
  }
  int size() const override { return static_cast<int>(points_.size()); }
  const std::string& source() const override { return o_.set.source; }
  const MeasurementContext& context(int i) const override { return points_[i].context; }
  std::string Where(int i) const override { return "row " + std::to_string(points_[i].row); }
  double Order(int i) const override { return points_[i].row; }
  std::string Measured() const override { return "these points"; }
  Fit FitOn(const RobotModel& model, const std::vector<int>& train,
            const std::string& what) const override {
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
  double Rows(const std::vector<int>& train) const override { return 3.0 * train.size(); }
  void HeldOut(const Fit& fit, const std::vector<int>& test, CrossValidation* cv) const override {
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
  std::vector<std::pair<std::string, std::vector<double>>> Components(
      const CrossValidation& cv) const override {
    std::vector<std::pair<std::string, std::vector<double>>> out{
        {"x", {}}, {"y", {}}, {"z", {}}, {"norm", {}}};
    for (const Eigen::VectorXd& e : cv.e) {
      for (int a = 0; a < 3; ++a) out[a].second.push_back(e(a));
      out[3].second.push_back(e.norm());
    }
    return out;
  }

  const std::vector<TrackerPoint>& points() const { return points_; }
  const std::vector<Matrix3>& covariance() const { return covariance_; }

 private:
  std::vector<TrackerPoint> points_;
  const DiscoveryOptions& o_;
  std::vector<Matrix3> covariance_;
};

// Workspace blocks: k-means (Lloyd) on the measured points, started from the point nearest
// the centroid and then each time the point farthest from the centres so far (deterministic).
std::vector<int> RegionFolds(const std::vector<TrackerPoint>& points, int k, std::string* rule) {
  const int n = static_cast<int>(points.size());
  Vector3 mean = Vector3::Zero();
  for (const TrackerPoint& p : points) mean += p.p_T;
  mean /= n;
  std::vector<Vector3> centres;
  int first = 0;
  for (int i = 1; i < n; ++i) {
    if ((points[i].p_T - mean).norm() < (points[first].p_T - mean).norm()) first = i;
  }
  centres.push_back(points[first].p_T);
  while (static_cast<int>(centres.size()) < k) {
    int far = 0;
    double best = -1;
    for (int i = 0; i < n; ++i) {
      double d = std::numeric_limits<double>::infinity();
      for (const Vector3& c : centres) d = std::min(d, (points[i].p_T - c).squaredNorm());
      if (d > best) {
        best = d;
        far = i;
      }
    }
    centres.push_back(points[far].p_T);
  }
  std::vector<int> fold(n, 0);
  for (int it = 0; it < 100; ++it) {
    bool changed = false;
    for (int i = 0; i < n; ++i) {
      int nearest = 0;
      for (int c = 1; c < k; ++c) {
        if ((points[i].p_T - centres[c]).squaredNorm() <
            (points[i].p_T - centres[nearest]).squaredNorm()) {
          nearest = c;
        }
      }
      changed = changed || nearest != fold[i];
      fold[i] = nearest;
    }
    std::vector<Vector3> sum(k, Vector3::Zero());
    std::vector<int> count(k, 0);
    for (int i = 0; i < n; ++i) {
      sum[fold[i]] += points[i].p_T;
      ++count[fold[i]];
    }
    for (int c = 0; c < k; ++c) {
      if (count[c] > 0) centres[c] = sum[c] / count[c];
    }
    if (!changed && it > 0) break;
  }
  std::vector<int> count(k, 0);
  for (int f : fold) ++count[f];
  std::ostringstream os;
  os << k << " workspace blocks by k-means on the measured points (sizes";
  for (int c = 0; c < k; ++c) os << (c ? ", " : " ") << count[c];
  os << "); each block predicted by the model trained on the others";
  *rule = os.str();
  return fold;
}

std::vector<int> RandomFolds(int n, int k, std::uint64_t seed) {
  std::vector<int> index(n);
  std::iota(index.begin(), index.end(), 0);
  std::mt19937_64 rng(seed);
  std::shuffle(index.begin(), index.end(), rng);
  std::vector<int> fold(n);
  for (int r = 0; r < n; ++r) fold[index[r]] = r % k;
  return fold;
}

NoiseFloor TrackerNoise(const TrackerData& data, const DiscoveryOptions& o) {
  const std::vector<TrackerPoint>& points = data.points();
  NoiseFloor nf;
  double sum = 0, tracker = 0;
  int stated = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    sum += data.covariance()[i].trace() / 3.0;
    tracker += SigmaOf(points[i], o) * SigmaOf(points[i], o);
    if (points[i].sigma > 0.0) ++stated;
  }
  nf.sigma_m = std::sqrt(sum / points.size());
  nf.tracker_sigma_m = std::sqrt(tracker / points.size());
  nf.joint_sigma_rad = o.joint_sigma_rad;
  nf.source = stated == static_cast<int>(points.size())
                  ? "the sigma stated for each point"
                  : (stated == 0 ? "the set's default sigma (no point states one)"
                                 : "the stated sigmas, the set's default where a point has none");
  if (o.joint_sigma_rad > 0.0) nf.source += ", with the stated joint reading noise through the model";
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

class OpticalData : public Data {
 public:
  OpticalData(const RobotModel& start, const std::vector<AxisSample>& samples,
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
  int size() const override { return static_cast<int>(samples_.size()); }
  const std::string& source() const override { return o_.axis_source; }
  const MeasurementContext& context(int i) const override { return contexts_[i]; }
  std::string Where(int i) const override {
    return "sample " + std::to_string(i + 1) + " (axis " + std::to_string(samples_[i].axis + 1) +
           ")";
  }
  double Order(int i) const override { return i; }
  std::string Measured() const override { return "the optical axes (the line constraint)"; }
  bool depth() const { return depth_; }
  const std::vector<int>& axes() const { return axes_; }
  /// Sample i's noise: its own (the board pose's covariance) where known, else the stated one.
  double SigmaOffset(int i) const {
    return samples_[i].sigma_offset > 0.0 ? samples_[i].sigma_offset
                                          : o_.axis_set.sigma_perpendicular;
  }
  double SigmaDepth(int i) const {
    return samples_[i].sigma_depth > 0.0 ? samples_[i].sigma_depth : o_.axis_set.sigma_depth;
  }
  /// The stated joint noise at sample i through the model, averaged over directions [m^2].
  double JointVariancePerCoordinate(int i) const {
    return o_.joint_sigma_rad > 0.0
               ? o_.joint_sigma_rad * o_.joint_sigma_rad * jacobians_[i].squaredNorm() / 3.0
               : 0.0;
  }
  const std::vector<AxisSample>& samples() const { return samples_; }

  Fit FitOn(const RobotModel& model, const std::vector<int>& train,
            const std::string& what) const override {
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
  double Rows(const std::vector<int>& train) const override {
    return (depth_ ? 3.0 : 2.0) * train.size();
  }
  void HeldOut(const Fit& fit, const std::vector<int>& test, CrossValidation* cv) const override {
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
  // The residual of samples idx (points p on their axis) against `line` and depth offset t.
  void Score(const Line3& line, double t, const std::vector<int>& idx,
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
  bool GlobalTest() const override { return true; }
  CrossValidation InSample(const RobotModel& model, const std::string& what) const override {
    DiscoveryOptions stated = o_;
    stated.engine.estimate_group_weights = false;  // the weights are the stated sigmas
    const OpticalData with_stated(start_, samples_, stated);
    const Fit all = with_stated.FitOn(model, {}, what);
    CrossValidation cv;
    const int n = size();
    cv.e.assign(n, Eigen::VectorXd());
    cv.loss.assign(n, 0.0);
    cv.dist2.assign(n, 0.0);
    cv.chi2.assign(n, 0.0);
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
  std::vector<std::pair<std::string, std::vector<double>>> Components(
      const CrossValidation& cv) const override {
    std::vector<std::pair<std::string, std::vector<double>>> out{{"distance", {}}};
    if (depth_) out.push_back({"depth", {}});
    for (const Eigen::VectorXd& e : cv.e) {
      out[0].second.push_back(e.head<2>().norm());
      if (depth_) out[1].second.push_back(e(2));
    }
    return out;
  }

 private:
  RobotModel start_;
  std::vector<AxisSample> samples_;
  const DiscoveryOptions& o_;
  bool depth_ = false;
  std::vector<MeasurementContext> contexts_;
  std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>> jacobians_;
  std::vector<int> axes_;  // distinct axis indices, ascending
};

// Region folds: whole axes, consecutive plan axes together (every sample of an axis in the
// same fold).
std::vector<int> AxisFolds(const OpticalData& data, int k, std::string* rule) {
  const std::vector<int>& axes = data.axes();
  const int q = static_cast<int>(axes.size());
  std::vector<int> fold;
  for (const AxisSample& s : data.samples()) {
    const int r = static_cast<int>(std::lower_bound(axes.begin(), axes.end(), s.axis) - axes.begin());
    fold.push_back(r * k / q);
  }
  std::ostringstream os;
  os << k << " folds of whole optical axes (" << q << " axes, consecutive plan axes together); "
     << "each held-out axis scored by the straightness of its predicted points (its own line "
        "and depth offset fitted to them)";
  *rule = os.str();
  return fold;
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
  if (o.joint_sigma_rad > 0.0) nf.source += ", with the stated joint reading noise through the model";
  return nf;
}

CrossValidation CrossValidate(const Data& data, const RobotModel& model,
                              const std::vector<int>& fold_of, int folds,
                              const std::string& what) {
  CrossValidation cv;
  const int n = data.size();
  cv.e.assign(n, Eigen::VectorXd());
  cv.loss.assign(n, 0.0);
  cv.dist2.assign(n, 0.0);
  cv.chi2.assign(n, 0.0);
  for (int k = 0; k < folds; ++k) {
    std::vector<int> train, test;
    for (int i = 0; i < n; ++i) (fold_of[i] == k ? test : train).push_back(i);
    if (test.empty()) continue;
    const Fit fit = data.FitOn(model, train, what + ", fold " + std::to_string(k + 1));
    data.HeldOut(fit, test, &cv);
    cv.unknowns += fit.result.unknowns / static_cast<double>(folds);
    cv.train_rows += data.Rows(train) / folds;
  }
  return cv;
}

ResidualTest TestResiduals(const CrossValidation& cv, const DiscoveryOptions& o,
                           const std::string& held_out) {
  ResidualTest t;
  t.held_out = held_out;
  t.points = static_cast<int>(cv.e.size());
  t.rms_m = cv.Rms();
  const double chi2 = std::accumulate(cv.chi2.begin(), cv.chi2.end(), 0.0);
  t.dof = cv.dof;
  t.inflation = cv.train_rows > 0 ? 1.0 + cv.unknowns / cv.train_rows : 1.0;
  t.statistic = chi2 / t.inflation;
  t.p_value = stats::ChiSquareUpperTail(t.statistic, t.dof);
  t.systematic = t.p_value < o.alpha;
  return t;
}

// The residual test of `model` (step 2): held out (random folds) or, where the data says so,
// the adjustment's global test.
ResidualTest RunResidualTest(const Data& data, const RobotModel& model,
                             const std::vector<int>& folds_of, int folds,
                             const DiscoveryOptions& o, const std::string& rule,
                             const std::string& what) {
  if (!data.GlobalTest()) return TestResiduals(CrossValidate(data, model, folds_of, folds, what), o, rule);
  return TestResiduals(data.InSample(model, what + ", every sample"), o, rule);
}

// The size test of a candidate (CandidateScore::size_p_value): Wald's chi-square of its size
// measures (ErrorTerm::SizeMeasures: by default its amplitude parameters; a warm-up's growth
// by the data's latest time stamp `session_s`) against zero, their covariance J C J^T from
// the term's covariance block C (first, its parameters) by the delta method, with its
// pseudo-inverse over the numerical rank (a combination the data cannot see has no variance
// there and counts for nothing). A term can raise the rank and still have a size the data
// cannot tell from zero: on the paper cell's optical axes (a 4 min session; the undeclared
// mount deflection, trial 19) a warm-up started at 10 min, its growth nearly a scale of the
// joint links (canonical correlation 0.99997), fitted a growth of 0.1 sigma (Wald p = 0.92)
// yet won 38 % of the held-out sum of squares; added, it moved the physical-truth error from
// 0.09 to 0.56 mm. The warm-up's final growth alone is the wrong measure the other way: for a
// time constant long against the session it trades off against the time constant, and on
// synthetic data a warm-up that explained 75 % of the held-out loss had p = 0.1 on it.
void SizeTest(const IdentificationResult& fit, int first, const ErrorTerm& term, double session_s,
              CandidateScore* c) {
  const int n = static_cast<int>(term.parameters().size());
  if (n <= 0 || fit.covariance.rows() < first + n) return;
  Eigen::VectorXd p(n);
  for (int k = 0; k < n; ++k) p(k) = fit.parameters[first + k].estimated;
  Eigen::MatrixXd J;
  const Eigen::VectorXd size = term.SizeMeasures(p.data(), session_s, &J);
  const stats::WaldTest w =
      stats::WaldTestZero(size, J * fit.covariance.block(first, first, n, n) * J.transpose());
  c->size_statistic = w.statistic;
  c->size_dof = w.dof;
  c->size_p_value = w.p_value;
}

// The RMS of every residual norm of an identification's sets at its solution [m].
double ResidualRms(const IdentificationResult& r) {
  double sum = 0;
  int count = 0;
  for (const SetSummary& s : r.sets) {
    sum += s.rms_after * s.rms_after * s.measurements;
    count += s.measurements;
  }
  return count > 0 ? std::sqrt(sum / count) : 0.0;
}

// Whether the term of `spec` has parameters that act only once others are non-zero
// (ErrorTerm::has_dormant_parameters: a warm-up's time constant).
bool HasDormantParameters(const TermSpec& spec, const RobotModel& start) {
  try {
    return MakeErrorTerm(spec, start.chain, start.name())->has_dormant_parameters();
  } catch (const InputError&) {
    return false;
  }
}

// The one-sided sign-flip p (stats::SignFlipTestGreater) of `better`'s region-fold held-out
// loss being below `c`'s: their loss differences summed per fold (`region`: each unit's fold).
double FoldSignFlipP(const CandidateScore& c, const CandidateScore& better,
                     const std::vector<int>& region, int folds) {
  std::vector<double> d(folds, 0.0);
  for (std::size_t i = 0; i < region.size(); ++i) {
    d[region[i]] += c.heldout_loss[i] - better.heldout_loss[i];
  }
  return stats::SignFlipTestGreater(d);
}

// TermDriver in words, for the notes.
const char* DriverText(TermDriver d) {
  switch (d) {
    case TermDriver::kMeasured: return "a measured quantity";
    case TermDriver::kClockLevelling: return "the clock, levelling off";
    case TermDriver::kClockUnbounded: return "the clock, without bound";
  }
  return "?";
}

// Sets `model` to `base` with the term of `spec`; false (c says why) where the term cannot be
// made or the data lacks the context it needs.
bool BuildCandidateModel(const Data& data, const RobotModel& base, const TermSpec& spec,
                         RobotModel* model, CandidateScore* c) {
  try {
    *model = WithTerm(base, MakeErrorTerm(spec, base.chain, base.name(), "candidate " + c->label));
  } catch (const InputError& e) {
    c->applicable = false;
    c->note = e.what();
    return false;
  }
  for (int i = 0; i < data.size(); ++i) {
    const std::string missing = MissingContext(*model, data.context(i));
    if (!missing.empty()) {
      c->applicable = false;
      c->note = "not applicable: " + missing + " (" + data.Where(i) + ")";
      return false;
    }
  }
  return true;
}

// A candidate's model and its fit on every unit of data.
struct CandidateFit {
  RobotModel model;  // the base with the term (restarted: from its first fit's term values)
  Fit all;           // the fit on every unit
  int added = 0;     // the term's parameters
  int first = 0;     // index of its first parameter in the model
  int rank = 0;      // of the all-data fit
};

// Fits the candidate's `model` on all the data; where dormant parameters were left partly
// unidentified, restarts from that first solution and keeps the restart if it is better.
CandidateFit FitCandidate(const Data& data, RobotModel model, int base_rank,
                          CandidateScore* c) {
  CandidateFit f;
  f.added = static_cast<int>(model.terms.back()->parameters().size());
  const int added = f.added;
  c->driver = model.terms.back()->driver();
  f.all = data.FitOn(model, {}, "candidate " + c->label + ", all data");
  f.first = model.num_parameters() - added;
  f.rank = f.all.result.observability.rank;
  if (model.terms.back()->has_dormant_parameters() && f.rank > base_rank &&
      f.rank < base_rank + added) {
    // Some parameters only have a gradient once the term acts (a time constant while the
    // amplitude is zero): start again from the first solution's term values, and keep that
    // start (for the cross-validation too) if more of the term is then identifiable and the
    // fit is no worse. (A restart can run off to another minimum: a warm-up whose time
    // constant fell to seconds, a step that the geometry's scale absorbs, fitted the session
    // as the geometry alone did, and its candidate lost the gain its first solution had.)
    RobotModel restart = model;
    restart.term_values.tail(added) = f.all.result.model.term_values.tail(added);
    Fit again = data.FitOn(restart, {}, "candidate " + c->label + ", all data, restarted");
    if (again.result.observability.rank > f.rank &&
        ResidualRms(again.result) <= (1.0 + 1e-6) * ResidualRms(f.all.result)) {
      model = std::move(restart);
      f.all = std::move(again);
      f.rank = f.all.result.observability.rank;
      c->restarted = true;
    }
  }
  f.model = std::move(model);
  return f;
}

// Records the term's parameters as fitted on all the data and its size test (SizeTest) at
// the data's latest time stamp.
void RecordParametersAndSize(const Data& data, const CandidateFit& f, CandidateScore* c) {
  for (int k = 0; k < f.added; ++k) {
    const IdentifiedParameter& ip = f.all.result.parameters[f.first + k];
    c->parameters.push_back({ip.name, ip.unit, ip.estimated, ip.sigma});
  }
  double session_s = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < data.size(); ++i) {
    const MeasurementContext& x = data.context(i);
    if (x.has_time() && (std::isnan(session_s) || x.time_s > session_s)) session_s = x.time_s;
  }
  SizeTest(f.all.result, f.first, *f.model.terms.back(), session_s, c);
}

// Whether the term raises the rank above `base_rank`; notes why not, or that it does partly.
bool RaisesRank(const Data& data, const CandidateFit& f, int base_rank, CandidateScore* c) {
  if (f.rank <= base_rank) {
    c->identifiable = false;
    c->note = "unidentifiable from " + data.Measured() + ": the rank does not rise with its " +
              std::to_string(f.added) + " parameter(s) (the measurements cannot tell it from "
              "the geometry, or it has nothing to act on)";
    return false;
  }
  if (f.rank < base_rank + f.added) {
    // Partly identifiable (e.g. a mount deflection along the flange axis is the tool length's):
    // the engine identifies only the combinations the data sees, the rest stay at zero.
    c->note = "partly identifiable: the rank rises by " + std::to_string(f.rank - base_rank) +
              " of its " + std::to_string(f.added) + " parameters";
  }
  return true;
}

// Disguise of the geometry: the canonical correlations of the term's columns with the
// geometric ones (TermGeometryDependence); the directions that did not raise the rank lie in
// the geometry by definition and are left out, the largest of the rest is the measure.
void MeasureGeometryDisguise(const CandidateFit& f, int base_rank, CandidateScore* c) {
  const std::string block = ParameterLayout(f.model).blocks().back().name;
  for (const TermGeometryDependence& d : f.all.result.term_dependence) {
    if (d.block != block) continue;
    const int rise = f.rank - base_rank;
    const int skip = std::max(0, static_cast<int>(d.canonical_correlations.size()) - rise);
    if (skip < static_cast<int>(d.canonical_correlations.size())) {
      c->max_geometry_correlation = d.canonical_correlations[skip];
      c->correlated_with = d.nearest_geometric[skip];
    }
  }
}

// The candidate's region cross-validation against the base's `base_cv`: held-out RMS, gain
// and Wilcoxon's one-sided p on the per-unit loss differences.
void TestHeldOut(const Data& data, const RobotModel& model, const std::vector<int>& region,
                 int folds, const CrossValidation& base_cv, CandidateScore* c) {
  const CrossValidation cv = CrossValidate(data, model, region, folds, "candidate " + c->label);
  c->heldout_rms_m = cv.Rms();
  const double base_sse = base_cv.Sse();
  c->gain_percent = base_sse > 0 ? 100.0 * (1.0 - cv.Sse() / base_sse) : 0.0;
  std::vector<double> d(cv.loss.size());
  for (std::size_t i = 0; i < d.size(); ++i) d[i] = base_cv.loss[i] - cv.loss[i];
  c->p_value = stats::WilcoxonSignedRankGreater(d).p_value;
  c->heldout_loss = cv.loss;
  c->tested = true;
}

// Scores one candidate against the step's base (its region cross-validation `base_cv`).
CandidateScore ScoreCandidate(const Data& data, const RobotModel& base, int base_rank,
                              const TermSpec& spec, const std::vector<int>& region, int folds,
                              const CrossValidation& base_cv, bool cross_validate = true) {
  CandidateScore c;
  c.spec = spec;
  c.label = TermLabel(spec);
  // The base with the term, where it applies to the data.
  RobotModel model;
  if (!BuildCandidateModel(data, base, spec, &model, &c)) return c;
  // Its fit on all the data, restarted where dormant parameters need it.
  const CandidateFit fit = FitCandidate(data, std::move(model), base_rank, &c);
  // Its parameters and whether its size is told from zero.
  RecordParametersAndSize(data, fit, &c);
  // Identifiable at all (the rank rises)?
  if (!RaisesRank(data, fit, base_rank, &c)) return c;
  // How nearly it is the geometry in disguise.
  MeasureGeometryDisguise(fit, base_rank, &c);
  if (!cross_validate) {
    c.note = (c.note.empty() ? "" : c.note + "; ") +
             "fitted on all the data, not tested: the residual is consistent with the noise";
    return c;
  }
  // Held out in the region folds against the base.
  TestHeldOut(data, fit.model, region, folds, base_cv, &c);
  return c;
}

// Every candidate of `specs` scored beside `current` (ScoreCandidate), `jobs` at a time; a
// candidate whose identification refuses the data (InputError) is reported unidentifiable with
// the reason; any other exception is a bug and is rethrown once the workers have ended.
std::vector<CandidateScore> ScoreAll(const Data& data, const RobotModel& current, int base_rank,
                                     const std::vector<TermSpec>& specs,
                                     const std::vector<int>& region, int folds,
                                     const CrossValidation& base_cv, bool cross_validate,
                                     int jobs,
                                     const std::function<void(const std::string&)>& say,
                                     const std::string& what) {
  std::vector<CandidateScore> out(specs.size());
  std::atomic<int> next{0}, done{0};
  std::mutex mutex;
  // The first bug (anything but a refusal of the data) of any worker, rethrown after the join:
  // a bug is never turned into a candidate's note.
  std::exception_ptr bug;
  const auto worker = [&]() {
    for (int k = next++; k < static_cast<int>(specs.size()); k = next++) {
      try {
        out[k] = ScoreCandidate(data, current, base_rank, specs[k], region, folds, base_cv,
                                cross_validate);
      } catch (const InputError& e) {
        out[k].spec = specs[k];
        out[k].label = TermLabel(specs[k]);
        out[k].identifiable = false;
        out[k].note = std::string("its identification failed: ") + e.what();
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!bug) bug = std::current_exception();
        next = static_cast<int>(specs.size());  // no further candidates
        return;
      }
      const int d = ++done;
      std::lock_guard<std::mutex> lock(mutex);
      say("diagnosis: " + what + ", candidate " + std::to_string(d) + " of " +
          std::to_string(specs.size()) + " (" + out[k].label + ")");
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < std::min<int>(jobs, static_cast<int>(specs.size())); ++t) {
    pool.emplace_back(worker);
  }
  for (std::thread& t : pool) t.join();
  if (bug) std::rethrow_exception(bug);
  return out;
}

// Quantities the residual is correlated with and mapped against, per unit of data.
struct Quantity {
  std::string name, unit;
  std::vector<double> values;
};

std::vector<Quantity> Quantities(const RobotModel& model, const Data& data) {
  std::vector<Quantity> out;
  const int n = model.chain.num_joints();
  const int units = data.size();
  for (int j = 0; j < n; ++j) {
    Quantity q{"q" + std::to_string(j + 1), "rad", {}};
    for (int i = 0; i < units; ++i) q.values.push_back(data.context(i).q(j));
    out.push_back(q);
  }
  std::vector<Eigen::VectorXd> tau;
  for (int i = 0; i < units; ++i) tau.push_back(GravityTorques(model, data.context(i).q));
  for (int j = 0; j < n; ++j) {
    Quantity q{"tau" + std::to_string(j + 1), "N m", {}};
    for (const Eigen::VectorXd& t : tau) q.values.push_back(t(j));
    out.push_back(q);
  }
  Quantity order{"order", "row", {}};
  for (int i = 0; i < units; ++i) order.values.push_back(data.Order(i));
  out.push_back(order);
  bool time = true, temperature = true;
  for (int i = 0; i < units; ++i) {
    time = time && data.context(i).has_time();
    temperature = temperature && data.context(i).has_temperature();
  }
  if (time) {
    Quantity q{"time", "s", {}};
    for (int i = 0; i < units; ++i) q.values.push_back(data.context(i).time_s);
    out.push_back(q);
  }
  if (temperature) {
    Quantity q{"temperature", "K", {}};
    for (int i = 0; i < units; ++i) q.values.push_back(data.context(i).temperature_delta_K);
    out.push_back(q);
  }
  return out;
}

void Evidence(const RobotModel& model, const Data& data, const CrossValidation& cv,
              DiscoveryResult* r) {
  const std::vector<Quantity> quantities = Quantities(model, data);
  const auto components = data.Components(cv);
  for (const Quantity& q : quantities) {
    for (const auto& [name, values] : components) {
      r->evidence.push_back({q.name, name, stats::Correlation(q.values, values)});
    }
    // Map: residual RMS in 8 equal bins of the quantity's range.
    ResidualMap m;
    m.quantity = q.name;
    m.unit = q.unit;
    const auto [lo_it, hi_it] = std::minmax_element(q.values.begin(), q.values.end());
    const double lo = *lo_it, hi = *hi_it;
    const int bins = hi > lo ? 8 : 1;
    std::vector<double> ss(bins, 0.0);
    m.count.assign(bins, 0);
    for (std::size_t i = 0; i < q.values.size(); ++i) {
      int b = hi > lo ? static_cast<int>((q.values[i] - lo) / (hi - lo) * bins) : 0;
      b = std::clamp(b, 0, bins - 1);
      ss[b] += cv.dist2[i];
      ++m.count[b];
    }
    for (int b = 0; b < bins; ++b) {
      m.bin_centre.push_back(lo + (b + 0.5) * (hi - lo) / bins);
      m.rms_m.push_back(m.count[b] > 0 ? std::sqrt(ss[b] / m.count[b]) : 0.0);
    }
    r->maps.push_back(m);
  }
  std::stable_sort(r->evidence.begin(), r->evidence.end(),
                   [](const ResidualCorrelation& a, const ResidualCorrelation& b) {
                     return std::abs(a.r) > std::abs(b.r);
                   });
  if (r->evidence.size() > 8) r->evidence.resize(8);
}

// What every stage of the search reads: Discover's arguments and what it derives from them.
struct Search {
  const Data& data;
  const RobotModel& start;
  const std::vector<int>& random;  // each unit's fold of the residual test
  int random_folds;
  const std::vector<int>& region;  // each unit's region fold
  int folds;                       // of the region folds
  const std::string& random_rule;
  const DiscoveryOptions& o;
  std::vector<TermSpec> all_specs;  // the candidates
  int jobs;                         // parallel candidate evaluations
  std::function<void(const std::string&)> say;  // progress lines
};

// The model every fit starts from: `start`, with its declared terms' dormant parameters taken
// from a first all-data fit where that identifies more and fits no worse.
RobotModel WakeDormantTerms(const Data& data, const RobotModel& start,
                            const std::function<void(const std::string&)>& say) {
  RobotModel current = start;
  if (HasDormantTermsAtZero(start)) {
    // A declared term whose dormant parameters sleep at zero (a warm-up's time constant):
    // every fit starts where a first fit on all the data put it, if that identifies more and
    // fits no worse (as ScoreCandidate restarts such a candidate).
    const Fit first = data.FitOn(start, {}, "declared terms, all data");
    RobotModel woken = WithDormantTermsFrom(start, first.result.model);
    const Fit again = data.FitOn(woken, {}, "declared terms, all data, restarted");
    if (again.result.observability.rank > first.result.observability.rank &&
        ResidualRms(again.result) <= (1.0 + 1e-6) * ResidualRms(first.result)) {
      current = std::move(woken);
      say("diagnosis: the declared terms' dormant parameters start from a first fit");
    }
  }
  return current;
}

// Step 2 on the starting model (r->test_before); returns its region cross-validation, the
// base of the first step.
CrossValidation TestStartingModel(const Search& search, const RobotModel& current,
                                  DiscoveryResult* out) {
  DiscoveryResult& r = *out;
  search.say("diagnosis: residual test of the starting model (" +
             std::to_string(search.random_folds) + " folds)");
  r.test_before = RunResidualTest(search.data, current, search.random, search.random_folds,
                                  search.o, search.random_rule, "residual test");
  CrossValidation current_region =
      CrossValidate(search.data, current, search.region, search.folds, "region folds");
  r.heldout_rms_start_m = current_region.Rms();
  return current_region;
}

// The verdict "consistent_with_noise", and with screen_when_noise every candidate fitted on
// all the data beside the model (DiscoveryResult::screened).
void ConcludeConsistentWithNoise(const Search& search, const RobotModel& current,
                                 const CrossValidation& current_region, DiscoveryResult* out) {
  DiscoveryResult& r = *out;
  const DiscoveryOptions& o = search.o;
  r.verdict = "consistent_with_noise";
  std::ostringstream os;
  os << "the residuals of the residual test (RMS " << Mm(r.test_before.rms_m)
     << ") are consistent with the noise floor (sigma " << Mm(r.noise.sigma_m)
     << " per coordinate): p = "
     << r.test_before.p_value << " >= alpha = " << o.alpha << "; no effect searched";
  r.reason = os.str();
  r.test_after = r.test_before;
  r.heldout_rms_discovered_m = r.heldout_rms_start_m;
  if (o.screen_when_noise) {
    const int base_rank = search.data.FitOn(current, {}, "screen base").result.observability.rank;
    r.screened = ScoreAll(search.data, current, base_rank, search.all_specs, search.region,
                          search.folds, current_region, false, search.jobs, search.say,
                          "screen");
    int seen = 0, unseen = 0;
    for (const CandidateScore& c : r.screened) {
      seen += c.applicable && c.identifiable;
      unseen += c.applicable && !c.identifiable;
    }
    r.reason += "; of " + std::to_string(r.screened.size()) +
                " candidates fitted beside the model the data could see " + std::to_string(seen) +
                ", " + std::to_string(unseen) + " are unidentifiable from them (screened[])";
  }
}

// Step `step`'s candidates, each scored beside `current` (ScoreAll) against its region
// cross-validation `current_region`.
DiscoveryStep ScoreStep(const Search& search, const RobotModel& current,
                        const CrossValidation& current_region, int step) {
  const int base_rank = search.data.FitOn(current, {}, "step base").result.observability.rank;
  DiscoveryStep s;
  s.index = step;
  s.heldout_rms_before_m = current_region.Rms();
  s.candidates = ScoreAll(search.data, current, base_rank, search.all_specs, search.region,
                          search.folds, current_region, true, search.jobs, search.say,
                          "step " + std::to_string(step));
  return s;
}

// The step's tested candidates (indices) and the one of largest gain among them whose size
// the data tell from zero (-1 none).
struct Selection {
  std::vector<int> tested;
  int best = -1;
};

// Holm over the tested candidates (CandidateScore::p_adjusted) and the largest gain among
// those that pass the size test; the others' notes say why they are not eligible.
Selection SelectLargestGain(const DiscoveryOptions& o, DiscoveryStep* step) {
  DiscoveryStep& s = *step;
  Selection sel;
  std::vector<int>& tested = sel.tested;
  // Holm over the tested candidates; the largest gain is accepted only if it passes.
  std::vector<double> p;
  for (int k = 0; k < static_cast<int>(s.candidates.size()); ++k) {
    if (s.candidates[k].tested) {
      tested.push_back(k);
      p.push_back(s.candidates[k].p_value);
    }
  }
  // Every tested candidate is in the family; one whose size the data cannot tell from
  // zero (SizeTest) is not eligible.
  const std::vector<double> adjusted = stats::HolmAdjust(p);
  int& best = sel.best;
  for (std::size_t t = 0; t < tested.size(); ++t) {
    CandidateScore& c = s.candidates[tested[t]];
    c.p_adjusted = adjusted[t];
    if (c.size_p_value >= o.alpha) {
      std::ostringstream why;
      why << "its size is not told from zero: Wald chi-square " << c.size_statistic
          << " on " << c.size_dof << " dof, p = " << c.size_p_value << " >= " << o.alpha;
      c.note = c.note.empty() ? why.str() : c.note + "; " + why.str();
      continue;
    }
    if (best < 0 || c.gain_percent > s.candidates[best].gain_percent) best = tested[t];
  }
  return sel;
}

// Why an eligible candidate would not be accepted on its own; empty: it would be.
std::string Refusal(const CandidateScore& c, const DiscoveryOptions& o,
                    const std::vector<int>& tested) {
  std::ostringstream why;
  if (c.p_adjusted >= o.alpha) {
    why << "not significant: Holm-adjusted p = " << c.p_adjusted << " >= " << o.alpha
        << " over " << tested.size() << " candidates";
  } else if (c.gain_percent < o.min_gain_percent) {
    why << c.gain_percent << " % < the " << o.min_gain_percent << " % worth a term";
  } else if (c.max_geometry_correlation >= o.correlation_limit) {
    why << "a disguise of the geometry: |rho| = " << c.max_geometry_correlation
        << " with " << c.correlated_with;
  }
  return why.str();
}

// The driver preference (header, step 3): the region folds are parts of one session, so
// they cannot test how a clock-driven term carries over to later times. Where the leader
// is clock-driven and an acceptable candidate with an earlier driver (TermDriver) is not
// told apart from it (the leader's held-out loss below the other's, summed per region
// fold, by the sign-flip test: p >= alpha), that candidate is taken instead: of several,
// the earliest driver, then the largest gain. The folds are the independent units here,
// not the points: a fold's points share the error of the model fitted without them, and
// between two near-equal models that shared error is the whole difference. Per point,
// Wilcoxon called a 0.14-point gain difference (a time-linear growth against the same
// growth read by a 0.03 K sensor, synthetic tracker data) significant at p = 0.0007.
// Returns the choice, `best` where nothing is preferred.
int PreferEarlierDriver(const Search& search, const std::vector<int>& tested, int best,
                        DiscoveryStep* step) {
  DiscoveryStep& s = *step;
  const DiscoveryOptions& o = search.o;
  const std::vector<int>& region = search.region;
  const int folds = search.folds;
  if (!(best >= 0 && s.candidates[best].driver != TermDriver::kMeasured &&
        Refusal(s.candidates[best], o, tested).empty())) {
    return best;
  }
  const CandidateScore& lead = s.candidates[best];
  int preferred = -1;
  for (int k : tested) {
    CandidateScore& c = s.candidates[k];
    if (c.driver >= lead.driver || c.size_p_value >= o.alpha || !Refusal(c, o, tested).empty()) {
      continue;
    }
    if (c.heldout_loss.size() != lead.heldout_loss.size() ||
        region.size() != lead.heldout_loss.size()) {
      continue;
    }
    c.versus_leader_p_value = FoldSignFlipP(c, lead, region, folds);
    if (c.versus_leader_p_value < o.alpha) {
      std::ostringstream why;
      why << "not preferred for its driver (" << DriverText(c.driver) << "): "
          << lead.label << " (" << DriverText(lead.driver)
          << ") is better in the region folds (sign-flip p = " << c.versus_leader_p_value
          << " < " << o.alpha << ")";
      c.note = c.note.empty() ? why.str() : c.note + "; " + why.str();
      continue;
    }
    const CandidateScore* q = preferred >= 0 ? &s.candidates[preferred] : nullptr;
    if (!q || c.driver < q->driver ||
        (c.driver == q->driver && c.gain_percent > q->gain_percent)) {
      preferred = k;
    }
  }
  if (preferred >= 0) {
    CandidateScore& leader = s.candidates[best];
    CandidateScore& c = s.candidates[preferred];
    c.preferred_over = leader.label;
    std::ostringstream why;
    why << "largest held-out gain (" << leader.gain_percent << " %), but driven by "
        << DriverText(leader.driver) << " and not told apart from " << c.label << " ("
        << c.gain_percent << " %, sign-flip p over the region folds = "
        << c.versus_leader_p_value << " >= " << o.alpha << "), driven by "
        << DriverText(c.driver);
    leader.note = leader.note.empty() ? why.str() : leader.note + "; " + why.str();
    best = preferred;
  }
  return best;
}

// A shape held at its start (header, step 3): a term whose shape (a warm-up's time
// constant) the data left at the value its search started from is that start's
// assumption; where the same term with its shape estimated from another start would be
// accepted and the region folds cannot tell the two apart, the estimated one is taken.
// Returns the choice, `best` where nothing changed; `shape_choice` says why it changed.
int PreferEstimatedShape(const Search& search, const std::vector<int>& tested, int best,
                         DiscoveryStep* step, std::string* shape_choice) {
  DiscoveryStep& s = *step;
  const DiscoveryOptions& o = search.o;
  const std::vector<int>& region = search.region;
  const int folds = search.folds;
  if (!(best >= 0 && !s.candidates[best].restarted &&
        Refusal(s.candidates[best], o, tested).empty() &&
        s.candidates[best].heldout_loss.size() == region.size() &&
        HasDormantParameters(s.candidates[best].spec, search.start))) {
    return best;
  }
  const CandidateScore& held = s.candidates[best];
  int estimated = -1;
  double estimated_p = 1.0;
  for (int k : tested) {
    const CandidateScore& c = s.candidates[k];
    if (k == best || c.spec.type != held.spec.type || !c.restarted ||
        c.size_p_value >= o.alpha || !Refusal(c, o, tested).empty() ||
        c.heldout_loss.size() != region.size()) {
      continue;
    }
    const double p_fold = FoldSignFlipP(c, held, region, folds);
    if (p_fold < o.alpha) continue;
    if (estimated < 0 || c.gain_percent > s.candidates[estimated].gain_percent) {
      estimated = k;
      estimated_p = p_fold;
    }
  }
  if (estimated >= 0) {
    CandidateScore& was = s.candidates[best];
    CandidateScore& c = s.candidates[estimated];
    std::ostringstream why;
    why << "its shape stayed at the start of its search (the data did not identify it "
           "there), and "
        << c.label << " estimates it with a held-out loss the region folds do not tell "
        << "apart (sign-flip p = " << estimated_p << " >= " << o.alpha << ")";
    was.note = was.note.empty() ? why.str() : was.note + "; " + why.str();
    std::ostringstream accepted_why;
    accepted_why << "accepted in place of " << was.label
                 << ", whose shape stayed at the start of its search: this one estimates "
                    "it, and the region folds do not tell the two apart (sign-flip p = "
                 << estimated_p << ")";
    *shape_choice = accepted_why.str();
    c.preferred_over = was.label;
    best = estimated;
  }
  return best;
}

// Accepts the chosen candidate `best` (CandidateScore::accepted) unless it is refused, and
// notes why either way; nothing where best < 0.
void DecideOnChoice(const DiscoveryOptions& o, const std::vector<int>& tested, int best,
                    const std::string& shape_choice, DiscoveryStep* step) {
  DiscoveryStep& s = *step;
  if (best < 0) return;
  CandidateScore& c = s.candidates[best];
  const std::string refused = Refusal(c, o, tested);
  std::ostringstream why;
  if (!refused.empty()) {
    why << "largest held-out gain, but " << refused;
  } else if (!shape_choice.empty()) {
    c.accepted = true;
    why << shape_choice << "; held-out gain " << c.gain_percent
        << " %, Holm-adjusted p = " << c.p_adjusted << " over " << tested.size()
        << " candidates";
  } else if (!c.preferred_over.empty()) {
    c.accepted = true;
    why << "accepted in place of " << c.preferred_over << " (driven by "
        << DriverText(c.driver) << ", fold p = "
        << c.versus_leader_p_value << "): held-out gain " << c.gain_percent
        << " %, Holm-adjusted p = " << c.p_adjusted << " over " << tested.size()
        << " candidates";
  } else {
    c.accepted = true;
    why << "accepted: largest held-out gain (" << c.gain_percent
        << " %), Holm-adjusted p = " << c.p_adjusted << " over " << tested.size()
        << " candidates";
  }
  c.note = c.note.empty() ? why.str() : c.note + "; " + why.str();
}

// The step's choice among its scored candidates (header, step 3): the index of the chosen
// one, -1 none; it is accepted only where its CandidateScore::accepted says so.
int ChooseCandidate(const Search& search, DiscoveryStep* step) {
  // Holm-adjusted p-values, and the largest gain among those with a size.
  const Selection sel = SelectLargestGain(search.o, step);
  step->heldout_rms_after_m = step->heldout_rms_before_m;
  // A clock-driven leader gives way to an earlier driver the folds cannot tell from it.
  int best = PreferEarlierDriver(search, sel.tested, sel.best, step);
  // A shape left at its start gives way to the same term with its shape estimated.
  std::string shape_choice;  // why this rule changed the choice
  best = PreferEstimatedShape(search, sel.tested, best, step, &shape_choice);
  // Accepted or refused, with the reason.
  DecideOnChoice(search.o, sel.tested, best, shape_choice, step);
  return best;
}

// Adds the accepted candidate `best` of step `s` to `current`, records the step and tests the
// extended model (r->test_after); returns whether its residual is still systematic.
bool AcceptTerm(const Search& search, DiscoveryStep s, int best, RobotModel* current,
                CrossValidation* current_region, DiscoveryResult* out) {
  DiscoveryResult& r = *out;
  const RobotModel& start = search.start;
  const CandidateScore& accepted = s.candidates[best];
  s.accepted = best;
  *current = WithTerm(*current, MakeErrorTerm(accepted.spec, start.chain, start.name()));
  if (accepted.restarted) {
    // Its fits start where its first fit ended (ScoreCandidate), for the same reason.
    const int added = static_cast<int>(accepted.parameters.size());
    for (int k = 0; k < added; ++k) {
      current->term_values(current->term_values.size() - added + k) =
          accepted.parameters[k].estimated;
    }
  }
  *current_region =
      CrossValidate(search.data, *current, search.region, search.folds, "region folds");
  s.heldout_rms_after_m = current_region->Rms();
  r.effects_added.push_back(accepted);
  search.say("diagnosis: step " + std::to_string(s.index) + " added " + accepted.label +
             ", held-out RMS " + Mm(s.heldout_rms_before_m) + " -> " +
             Mm(s.heldout_rms_after_m));
  r.steps.push_back(std::move(s));
  // Once the residual is consistent with the noise there is nothing left to explain: a
  // further term could only fit noise.
  r.test_after = RunResidualTest(search.data, *current, search.random, search.random_folds,
                                 search.o, search.random_rule, "residual test");
  return r.test_after.systematic;
}

// Forward selection (header, step 3): one term per step added to `current`, until none is
// accepted, the residual is consistent with the noise, or max_effects are in.
void SelectTerms(const Search& search, RobotModel* current, CrossValidation* current_region,
                 DiscoveryResult* r) {
  for (int step = 1; step <= search.o.max_effects; ++step) {
    // Every candidate scored beside the current model.
    DiscoveryStep s = ScoreStep(search, *current, *current_region, step);
    // The choice among them, accepted or not.
    const int best = ChooseCandidate(search, &s);
    if (best < 0 || !s.candidates[best].accepted) {
      r->steps.push_back(std::move(s));
      break;
    }
    // The extended model; stop once its residual is noise.
    if (!AcceptTerm(search, std::move(s), best, current, current_region, r)) break;
  }
}

// The verdict after a search (header, step 4): "effects_added" or "unexplained", with its
// reason; `current_region` is the discovered model's region cross-validation.
void StateSearchVerdict(const CrossValidation& current_region, DiscoveryResult* out) {
  DiscoveryResult& r = *out;
  r.heldout_rms_discovered_m = current_region.Rms();
  if (r.effects_added.empty()) {
    r.test_after = r.test_before;
    r.verdict = "unexplained";
    std::ostringstream os;
    os << "the residuals of the residual test (RMS " << Mm(r.test_before.rms_m)
       << ") are systematic (p = " << r.test_before.p_value << " against sigma "
       << Mm(r.noise.sigma_m) << " per coordinate) and no candidate effect passes";
    r.reason = os.str();
  } else {
    r.verdict = "effects_added";
    std::ostringstream os;
    os << r.effects_added.size() << " effect(s) added; region-disjoint held-out RMS "
       << Mm(r.heldout_rms_start_m) << " -> " << Mm(r.heldout_rms_discovered_m)
       << "; the residual is then " << (r.test_after.systematic ? "still systematic" :
                                                                  "consistent with noise")
       << " (p = " << r.test_after.p_value << ")";
    r.reason = os.str();
  }
}

// Steps 2-4 of the header on any kind of data; `r` holds the noise floor and the fold rules.
void Discover(const Data& data, const RobotModel& start, const std::vector<int>& random,
              int random_folds, const std::vector<int>& region, int folds,
              const std::string& random_rule,
              const DiscoveryOptions& o, DiscoveryResult* out) {
  DiscoveryResult& r = *out;
  const auto say = [&](const std::string& line) {
    if (o.progress) o.progress(line);
  };
  // The starting model, its declared terms' dormant parameters woken where that helps.
  RobotModel current = WakeDormantTerms(data, start, say);
  // The candidates, the parallelism and the rest of what every stage reads.
  const Search search{data, start, random, random_folds, region, folds, random_rule, o,
                      o.candidates.empty() ? CandidateTermSpecs(start.chain) : o.candidates,
                      o.jobs > 0 ? o.jobs : UsableCpuCount(), say};
  // Step 2: the residual test of the starting model, and its region cross-validation.
  CrossValidation current_region = TestStartingModel(search, current, &r);
  if (!r.test_before.systematic) {
    // Step 4 without a search: consistent with the noise, the candidates screened.
    ConcludeConsistentWithNoise(search, current, current_region, &r);
  } else {
    // Step 3: forward selection of terms.
    SelectTerms(search, &current, &current_region, &r);
    // Step 4: the verdict on what the search added.
    StateSearchVerdict(current_region, &r);
  }
  // The discovered model on all the data, and the residual's evidence.
  const Fit final_fit = data.FitOn(current, {}, "discovered model, all data");
  r.model = final_fit.result.model;
  r.X_TB = final_fit.X_TB;
  Evidence(start, data, current_region, &r);
}

}  // namespace

void ValidateDiscoveryOptions(const DiscoveryOptions& o) {
  const auto fail = [](const std::string& field, const std::string& why) {
    throw InputError("diagnosis." + field, why);
  };
  if (!(o.alpha > 0.0 && o.alpha < 0.5)) fail("alpha", "must be in (0, 0.5)");
  if (!(o.min_gain_percent >= 0.0 && o.min_gain_percent < 100.0)) {
    fail("min_gain_percent", "must be in [0, 100)");
  }
  if (o.max_effects < 0 || o.max_effects > 10) fail("max_effects", "must be from 0 to 10");
  if (o.folds < 2 || o.folds > 20) fail("folds", "must be from 2 to 20");
  if (!(o.correlation_limit > 0.0 && o.correlation_limit <= 1.0)) {
    fail("correlation_limit", "must be in (0, 1]");
  }
  if (o.jobs < 0) fail("jobs", "must be >= 0");
  if (!(o.joint_sigma_rad >= 0.0 && o.joint_sigma_rad <= 0.01)) {
    fail("joint_sigma", "must be from 0 to 0.01 rad (0.57 deg)");
  }
  ValidateIdentificationOptions(o.engine);
}

DiscoveryResult DiscoverTrackerModel(const RobotModel& start,
                                     const std::vector<TrackerPoint>& points,
                                     const DiscoveryOptions& o) {
  ValidateDiscoveryOptions(o);
  const int n = static_cast<int>(points.size());
  const int per_fold_train = n - (n + o.folds - 1) / o.folds;
  if (3 * per_fold_train <= start.num_parameters() + 6) {
    throw InputError(o.set.source, "model discovery: " + std::to_string(n) + " points leave " +
                                       std::to_string(per_fold_train) +
                                       " to train on in a fold of " + std::to_string(o.folds) +
                                       ", too few for the model's " +
                                       std::to_string(start.num_parameters()) +
                                       " parameters and the tracker pose");
  }
  const TrackerData data(start, points, o);
  DiscoveryResult r;
  r.data = "tracker_points";
  r.noise = TrackerNoise(data, o);
  const std::vector<int> random = RandomFolds(n, o.folds, o.seed);
  const std::vector<int> region = RegionFolds(points, o.folds, &r.region_rule);
  const std::string random_rule = std::to_string(o.folds) + "-fold cross-validation, points "
                                  "assigned to folds at random (seed " + std::to_string(o.seed) +
                                  ")";
  Discover(data, start, random, o.folds, region, o.folds, random_rule, o, &r);
  return r;
}

DiscoveryResult DiscoverOpticalAxisModel(const RobotModel& start,
                                         const std::vector<AxisSample>& samples,
                                         const DiscoveryOptions& o) {
  ValidateDiscoveryOptions(o);
  // An axis of fewer than 3 samples (the servo lost the others) has no straightness to score
  // held out: it is left out, and the result says so.
  std::map<int, int> per_axis;
  for (const AxisSample& s : samples) {
    if (s.axis < 0) {
      throw InputError(o.axis_source, "model discovery: a sample has axis index " +
                                          std::to_string(s.axis) + "; expected 0 or more");
    }
    ++per_axis[s.axis];
  }
  std::vector<AxisSample> kept;
  std::string left_out;
  for (const AxisSample& s : samples) {
    if (per_axis[s.axis] >= 3) kept.push_back(s);
  }
  for (const auto& [axis, m] : per_axis) {
    if (m >= 3) continue;
    left_out += (left_out.empty() ? "" : ", ") + std::string("axis ") + std::to_string(axis + 1) +
                " (" + std::to_string(m) + (m == 1 ? " sample)" : " samples)");
  }
  const OpticalData data(start, kept, o);
  const int q = static_cast<int>(data.axes().size());
  if (q < 3) {
    throw InputError(o.axis_source, "model discovery: " + std::to_string(q) +
                                        " optical axes; held-out scoring by whole axes needs 3 "
                                        "or more (2 to train on in every fold)");
  }
  const int folds = std::min(o.folds, q);  // of the region folds
  DiscoveryResult r;
  r.data = "optical_axes";
  if (!left_out.empty()) {
    r.data_note = "left out, fewer than 3 samples: " + left_out;
  }
  r.noise = OpticalNoise(data, o);
  const std::string global_rule =
      "in sample: the adjustment's global test, every sample fitted with the stated sigmas, "
      "chi-square over the redundancy (rows less the unknowns, lines included); held-out "
      "samples of few short axes have leverages up to near 1 and a heavy-tailed chi-square";
  const std::vector<int> region = AxisFolds(data, folds, &r.region_rule);
  Discover(data, start, region, folds, region, folds, global_rule, o, &r);
  return r;
}

}  // namespace twin
