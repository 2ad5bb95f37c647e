#include "calib/model/end_point_jacobian.h"

#include <array>
#include <cmath>
#include <vector>

namespace twin {

bool AnalyticEndPointJacobian(const RobotModel& model) {
  for (const auto& t : model.terms) {
    if (t->sags_under_gravity() || t->offsets_tool() || t->deflects_axes()) return false;
  }
  return true;
}

bool DeflectedEndPointJacobian(const RobotModel& model) {
  bool deflects = false;
  for (const auto& t : model.terms) {
    if (t->sags_under_gravity() || t->offsets_tool()) return false;
    deflects = deflects || t->deflects_axes();
  }
  return deflects;
}

namespace {

// Autodiff columns begin_col.. of J (kJetStride at a time; J sized by the caller); p the end
// point.
void AutodiffColumns(const RobotModel& model, const double* params, const MeasurementContext& c,
                     int begin_col, Vector3* p, PointJacobian* J) {
  const int n = model.num_parameters();
  std::vector<Jet> x(n);
  for (int i = 0; i < n; ++i) x[i] = Jet(params[i]);
  for (int begin = begin_col; begin < n; begin += kJetStride) {
    const int end = std::min(n, begin + kJetStride);
    for (int i = begin; i < end; ++i) x[i].v[i - begin] = 1.0;
    const RigidT<Jet> X = RobotEndPoseT<Jet>(model, x.data(), c);
    for (int r = 0; r < 3; ++r) {
      for (int i = begin; i < end; ++i) (*J)(r, i) = X.p(r).v[i - begin];
      (*p)(r) = X.p(r).a;
    }
    for (int i = begin; i < end; ++i) x[i].v[i - begin] = 0.0;
  }
  if (begin_col >= n) *p = RobotEndPoseT<double>(model, params, c).p;
}

// The deflected-chain way (header): term columns by autodiff, geometric ones on the deflected
// chain, each link's between its frame after the deflection before it and its frame after it.
void DeflectedJacobian(const RobotModel& model, const double* params, const MeasurementContext& c,
                       Vector3* p, PointJacobian* J) {
  const KinematicModel& chain = model.chain;
  const int nj = chain.num_joints();
  const int g = chain.num_parameters();
  J->resize(3, model.num_parameters());
  AutodiffColumns(model, params, c, g, p, J);
  double q[kMaxJoints];
  double s = 1.0;
  LinkAnglesT<double>(model, params, c, q, &s);
  std::array<RigidT<double>, kMaxJoints + 1> A;
  for (int i = 0; i < nj; ++i) A[i] = LinkTransformT(params + kParamsPerLink * i, q[i], s);
  A[nj] = LinkTransformT(params + kParamsPerLink * nj, 0.0, 1.0);  // stage 2
  std::array<RigidT<double>, kMaxJoints + 2> X;
  X[0] = RigidT<double>::FromTransform(chain.X_BL0);
  for (int i = 0; i <= nj; ++i) X[i + 1] = X[i] * A[i];
  double w[3 * kMaxJoints];
  AxisDeflectionsT<double>(model, params, c, X.data(), w);
  RigidT<double> F = X[0];
  ParameterJacobian G;
  for (int i = 0; i <= nj; ++i) {
    std::array<RigidT<double>, 2> link;
    link[0] = F;
    if (i < nj && !IsZeroRotation(w + 3 * i)) link[0].R = F.R * SmallRotationT<double>(w + 3 * i);
    link[1] = link[0] * A[i];
    const double scale = i < nj ? s : 1.0;  // the tool link does not grow (stage 2)
    IdentificationColumns(1, link.data(), params + kParamsPerLink * i, *p, scale, &G);
    J->middleCols(kParamsPerLink * i, kParamsPerLink) = G.topRows<3>();
    F = link[1];
  }
}

}  // namespace

void EndPointJacobianAutodiff(const RobotModel& model, const double* params,
                              const MeasurementContext& c, Vector3* p, PointJacobian* J) {
  J->resize(3, model.num_parameters());
  AutodiffColumns(model, params, c, 0, p, J);
}

void EndPointJacobian(const RobotModel& model, const double* params, const MeasurementContext& c,
                      Vector3* p, PointJacobian* J) {
  if (DeflectedEndPointJacobian(model)) {
    DeflectedJacobian(model, params, c, p, J);
    return;
  }
  if (!AnalyticEndPointJacobian(model)) {
    EndPointJacobianAutodiff(model, params, c, p, J);
    return;
  }
  const KinematicModel& chain = model.chain;
  const int nj = chain.num_joints();
  const int g = chain.num_parameters();
  const int n = model.num_parameters();
  J->resize(3, n);
  // Link angles and length scale with the terms' derivatives (stages 1-2 need no FK).
  std::vector<Jet> x(n);
  for (int i = 0; i < n; ++i) x[i] = Jet(params[i]);
  std::array<double, kMaxJoints> q;
  double s = 1.0;
  const int terms = n - g;
  std::vector<std::array<double, kMaxJoints>> dq(terms);
  std::vector<double> ds(terms, 0.0);
  if (terms == 0) {
    for (int i = 0; i < nj; ++i) q[i] = c.q(i);
  }
  for (int begin = g; begin < n; begin += kJetStride) {
    const int end = std::min(n, begin + kJetStride);
    for (int i = begin; i < end; ++i) x[i].v[i - begin] = 1.0;
    Jet qj[kMaxJoints];
    Jet sj;
    LinkAnglesT<Jet>(model, x.data(), c, qj, &sj);
    for (int i = 0; i < nj; ++i) {
      q[i] = qj[i].a;
      for (int k = begin; k < end; ++k) dq[k - g][i] = qj[i].v[k - begin];
    }
    s = sj.a;
    for (int k = begin; k < end; ++k) ds[k - g] = sj.v[k - begin];
    for (int i = begin; i < end; ++i) x[i].v[i - begin] = 0.0;
  }
  // Frames at those angles and that scale.
  std::array<RigidT<double>, kMaxJoints + 2> X;
  ChainFramesT<double>(chain, params, q.data(), s, X.data());
  // The tool link does not grow with the arm (robot_model.h, stage 2).
  X[nj + 1] = X[nj] * LinkTransformT(params + kParamsPerLink * nj, 0.0, 1.0);
  const RigidT<double>& X_BLt = X[chain.num_links()];
  *p = X_BLt * chain.X_LtE.translation();
  // Geometric columns (eq. 5-9; IdentificationJacobian's screws, the joint links' lengths
  // times s, the tool link's at scale 1).
  ParameterJacobian G;
  IdentificationColumns(chain.num_links(), X.data(), params, *p, s, &G);
  G.col(kParamsPerLink * nj + 1) /= s;  // the tool link's d and a
  G.col(kParamsPerLink * nj + 2) /= s;
  J->leftCols(g) = G.topRows<3>();
  // Term columns through the joint angles and the length scale: every translation from the
  // base frame L0 to the flange L_N scales with s.
  if (terms > 0) {
    const Vector3 dp_ds = (X[nj].p - chain.X_BL0.translation()) / s;
    for (int k = 0; k < terms; ++k) {
      Vector3 col = ds[k] * dp_ds;
      for (int i = 0; i < nj; ++i) {
        if (dq[k][i] != 0.0) col += dq[k][i] * X[i].R.col(2).cross(*p - X[i].p);
      }
      J->col(g + k) = col;
    }
  }
}

}  // namespace twin
