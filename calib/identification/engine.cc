#include "calib/identification/engine.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <set>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <ceres/ceres.h>

#include "calib/common/errors.h"

namespace twin {
namespace {

// phi = x + B delta: the model block moves in the identifiable directions B (n x r, SI) only.
class SubspaceManifold : public ceres::Manifold {
 public:
  explicit SubspaceManifold(const Eigen::MatrixXd& B)
      : B_(B), pinv_((B.transpose() * B).ldlt().solve(B.transpose())) {}
  int AmbientSize() const override { return static_cast<int>(B_.rows()); }
  int TangentSize() const override { return static_cast<int>(B_.cols()); }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override {
    Eigen::Map<Eigen::VectorXd>(x_plus_delta, B_.rows()) =
        Eigen::Map<const Eigen::VectorXd>(x, B_.rows()) +
        B_ * Eigen::Map<const Eigen::VectorXd>(delta, B_.cols());
    return true;
  }
  bool PlusJacobian(const double*, double* jacobian) const override {
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    Eigen::Map<RowMajor>(jacobian, B_.rows(), B_.cols()) = B_;
    return true;
  }
  bool Minus(const double* y, const double* x, double* y_minus_x) const override {
    Eigen::Map<Eigen::VectorXd>(y_minus_x, B_.cols()) =
        pinv_ * (Eigen::Map<const Eigen::VectorXd>(y, B_.rows()) -
                 Eigen::Map<const Eigen::VectorXd>(x, B_.rows()));
    return true;
  }
  bool MinusJacobian(const double*, double* jacobian) const override {
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    Eigen::Map<RowMajor>(jacobian, B_.cols(), B_.rows()) = pinv_;
    return true;
  }

 private:
  Eigen::MatrixXd B_;
  Eigen::MatrixXd pinv_;
};

// The problem of one identification: the model block first, then every set's nuisance.
struct Assembly {
  std::unique_ptr<ceres::Problem> problem;
  std::vector<double*> blocks;
  std::vector<int> tangent;
  int nuisance_tangent = 0;
};

Assembly Assemble(const RobotModel& model, double* params, const std::vector<MeasurementSet*>& sets,
                  const IdentificationOptions& o) {
  Assembly a;
  ceres::Problem::Options po;
  po.enable_fast_removal = false;
  a.problem = std::make_unique<ceres::Problem>(po);
  for (MeasurementSet* s : sets) s->AddResiduals(model, params, a.problem.get());
  a.blocks.push_back(params);
  a.tangent.push_back(model.num_parameters());
  for (MeasurementSet* s : sets) {
    for (const NuisanceBlock& b : s->nuisance()) {
      a.blocks.push_back(b.data);
      a.tangent.push_back(b.tangent_size);
      a.nuisance_tangent += b.tangent_size;
    }
  }
  (void)o;
  return a;
}

// Dense Jacobian of all residuals (rows) by the blocks' tangent columns, in block order.
Eigen::MatrixXd DenseJacobian(ceres::Problem* problem, const std::vector<double*>& blocks,
                              double* cost) {
  ceres::Problem::EvaluateOptions eo;
  eo.parameter_blocks = blocks;
  eo.apply_loss_function = false;
  ceres::CRSMatrix crs;
  problem->Evaluate(eo, cost, nullptr, nullptr, &crs);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r) {
    for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) J(r, crs.cols[k]) = crs.values[k];
  }
  return J;
}

// Indices of the parameters not held by options.fixed (names or block names).
std::vector<int> FreeParameters(const ParameterLayout& layout, const IdentificationOptions& o) {
  std::set<int> fixed;
  for (const std::string& f : o.fixed) {
    bool found = false;
    for (const ParameterBlock& b : layout.blocks()) {
      if (b.name == f) {
        for (int i = b.begin; i < b.begin + b.size; ++i) fixed.insert(i);
        found = true;
      }
    }
    if (!found) fixed.insert(layout.Find(f));  // throws for an unknown name
  }
  std::vector<int> free;
  for (int i = 0; i < layout.size(); ++i) {
    if (!fixed.count(i)) free.push_back(i);
  }
  return free;
}

// The model columns `columns` of J (n model columns, then nuisance) with the nuisance profiled
// out: projected onto the orthogonal complement of the nuisance columns' range (what the data
// sees once the nuisance is refitted).
Eigen::MatrixXd ProfiledModelColumns(const Eigen::MatrixXd& J, int n,
                                     const std::vector<int>& columns) {
  const int f = static_cast<int>(columns.size());
  Eigen::MatrixXd Jm(J.rows(), f);
  for (int c = 0; c < f; ++c) Jm.col(c) = J.col(columns[c]);
  const int u = static_cast<int>(J.cols()) - n;
  if (u > 0) {
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(J.rightCols(u));
    const int k = static_cast<int>(qr.rank());
    if (k > 0) {
      const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(J.rows(), k);
      Jm -= Q * (Q.transpose() * Jm);
    }
  }
  return Jm;
}

// Step 1 of the header on the Jacobian J (model columns first, n of them, then nuisance).
ObservabilityReport AnalyseJacobian(const Eigen::MatrixXd& J, int n, const std::vector<int>& free,
                                    const ParameterLayout& layout,
                                    const std::vector<Eigen::VectorXd>& invariants,
                                    double rank_tolerance) {
  const int f = static_cast<int>(free.size());
  const Eigen::MatrixXd Jm = ProfiledModelColumns(J, n, free);
  std::vector<std::string> names;
  Eigen::VectorXd scales(f);
  for (int c = 0; c < f; ++c) {
    names.push_back(layout[free[c]].name);
    scales(c) = layout[free[c]].scale;
  }
  std::vector<Eigen::VectorXd> inv;
  for (const Eigen::VectorXd& v : invariants) {
    Eigen::VectorXd w(f);
    for (int c = 0; c < f; ++c) w(c) = v(free[c]);
    if (w.norm() > 1e-12 * std::max(1.0, v.norm())) inv.push_back(w);
  }
  return AnalyseObservability(Jm, names, scales, rank_tolerance, inv);
}

// TermGeometryDependence of every term block, from the full Jacobian Jp (model columns at the
// solution, then nuisance).
std::vector<TermGeometryDependence> TermDependence(const Eigen::MatrixXd& Jp, int n,
                                                   const std::vector<int>& free,
                                                   const ParameterLayout& layout) {
  std::vector<int> all(n);
  for (int i = 0; i < n; ++i) all[i] = i;
  const Eigen::MatrixXd Jm = ProfiledModelColumns(Jp, n, all);
  std::vector<int> geometric;
  for (int i : free) {
    if (layout[i].term < 0) geometric.push_back(i);
  }
  Eigen::MatrixXd G(Jm.rows(), geometric.size());
  for (std::size_t c = 0; c < geometric.size(); ++c) G.col(c) = Jm.col(geometric[c]);
  const Eigen::MatrixXd QG = SpanBasis(G);
  std::vector<TermGeometryDependence> out;
  for (const ParameterBlock& b : layout.blocks()) {
    if (b.begin < layout.geometry_size()) continue;
    TermGeometryDependence d;
    d.block = b.name;
    const Eigen::MatrixXd QT = SpanBasis(Jm.middleCols(b.begin, b.size));
    if (QT.cols() > 0 && QG.cols() > 0) {
      Eigen::JacobiSVD<Eigen::MatrixXd> svd(QG.transpose() * QT, Eigen::ComputeThinV);
      const Eigen::VectorXd cosines = svd.singularValues();
      for (int k = 0; k < cosines.size(); ++k) {
        d.canonical_correlations.push_back(std::min(1.0, cosines(k)));
        const Eigen::VectorXd u = QT * svd.matrixV().col(k);  // the term's direction
        double best = -1;
        std::string name;
        for (std::size_t c = 0; c < geometric.size(); ++c) {
          const double norm = G.col(c).norm();
          if (!(norm > 0)) continue;
          const double cos = std::abs(G.col(c).dot(u)) / norm;
          if (cos > best) {
            best = cos;
            name = layout[geometric[c]].name;
          }
        }
        d.nearest_geometric.push_back(name);
      }
    } else {
      d.canonical_correlations.assign(QT.cols(), 0.0);
      d.nearest_geometric.assign(QT.cols(), "");
    }
    // Visibility beside every other free parameter (geometry and the other terms).
    const Eigen::MatrixXd JT = Jm.middleCols(b.begin, b.size);
    for (int i : free) {
      if (i < b.begin || i >= b.begin + b.size) d.others.push_back(i);
    }
    // The others' columns in the layout's scaled units (so that a relative singular-value cut
    // means the same for a length and an angle).
    const int k_others = static_cast<int>(d.others.size());
    Eigen::VectorXd scale(k_others);
    Eigen::MatrixXd K(Jm.rows(), k_others);
    for (int c = 0; c < k_others; ++c) {
      scale(c) = layout[d.others[c]].scale;
      K.col(c) = Jm.col(d.others[c]) * scale(c);
    }
    Eigen::MatrixXd seen = JT;
    d.compensation = Eigen::MatrixXd::Zero(k_others, b.size);
    if (k_others > 0) {
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(K, Eigen::ComputeThinU | Eigen::ComputeThinV);
      const Eigen::VectorXd sv = svd.singularValues();
      // Least squares on the others' span (a numerical cut only: a fit of everything moves
      // the others along weakly seen directions too), in scaled coordinates
      // W S^-1 U' J_T, then in SI; what is left of J_T is what the measurements see.
      int r = 0;
      while (r < sv.size() && sv(r) > 1e-12 * sv(0)) ++r;
      const Eigen::MatrixXd U = svd.matrixU().leftCols(r);
      d.compensation = scale.asDiagonal() * svd.matrixV().leftCols(r) *
                       sv.head(r).cwiseInverse().asDiagonal() * (U.transpose() * JT);
      seen -= U * (U.transpose() * JT);
    }
    d.visible_information = seen.transpose() * seen;
    d.raw_information_scale = (JT.transpose() * JT).diagonal().maxCoeff();
    out.push_back(std::move(d));
  }
  return out;
}

void Validate(const RobotModel& model, const std::vector<MeasurementSet*>& sets) {
  TWIN_REQUIRE(!sets.empty(), "Identify needs at least one measurement set, got none");
  for (const MeasurementSet* s : sets) {
    TWIN_REQUIRE(s != nullptr, "Identify got a null measurement set");
    s->Validate(model);
  }
}

std::vector<Eigen::VectorXd> AllInvariants(const RobotModel& model, const ParameterLayout& layout,
                                           const std::vector<MeasurementSet*>& sets) {
  std::vector<Eigen::VectorXd> out;
  for (const MeasurementSet* s : sets) {
    for (Eigen::VectorXd& v : s->Invariants(model, layout)) out.push_back(std::move(v));
  }
  return out;
}

// Removes the directions `held` (vectors over the flat model parameters, SI) from the model
// columns of J: in the layout's scaled coordinates, A <- A (I - W W^T) with W an orthonormal
// basis of them, so that they lie in the null space the analysis finds, before its rank is
// taken. (Added to the known invariants instead, directions that the numerical null space
// already holds up to a small rotation would leave remnants that Gram-Schmidt normalises into
// arbitrary directions, and those took a warm-up's time constant out of the identifiable ones.)
void HoldDirections(const std::vector<Eigen::VectorXd>& held, const ParameterLayout& layout,
                    Eigen::MatrixXd* J) {
  if (held.empty()) return;
  const int n = layout.size();
  Eigen::VectorXd scale(n);
  for (int i = 0; i < n; ++i) scale(i) = layout[i].scale;
  Eigen::MatrixXd W(n, held.size());
  for (std::size_t k = 0; k < held.size(); ++k) W.col(k) = held[k].cwiseQuotient(scale);
  const Eigen::MatrixXd Q = SpanBasis(W);
  const Eigen::MatrixXd A = J->leftCols(n) * scale.asDiagonal();
  J->leftCols(n) = (A - (A * Q) * Q.transpose()) * scale.cwiseInverse().asDiagonal();
}

// The free geometric combinations the data cannot see while every term is off (its values at
// zero), as vectors over the flat parameters [SI]; empty when the terms already are. A term that
// acts can make such a combination look identifiable through its own values alone: a thermal
// scale of the joint links at 1e-4 tells a joint link's length from the tool's at 1e-4 of their
// columns, far above the rank cut, yet what it "measures" is the term's model, not the arm (on
// a tracker session the restart of a warm-up candidate raised the rank by 3 such directions,
// and the time constant's own direction, under the cut, was held while the rank rise passed for
// it). They are held as they are at the terms' zero. `params` is the assembly's model block;
// it is restored.
std::vector<Eigen::VectorXd> GeometryNullSpaceWithTermsOff(
    const Assembly& a, Eigen::VectorXd& params, const ParameterLayout& layout,
    const std::vector<int>& free, const std::vector<Eigen::VectorXd>& invariants,
    double rank_tolerance) {
  const int n = layout.size();
  const int g = layout.geometry_size();
  if (n == g || params.tail(n - g).isZero(0.0)) return {};
  std::vector<int> geometric;
  for (int i : free) {
    if (layout[i].term < 0) geometric.push_back(i);
  }
  if (geometric.empty()) return {};
  const Eigen::VectorXd values = params.tail(n - g);
  params.tail(n - g).setZero();
  double cost = 0;
  const Eigen::MatrixXd J = DenseJacobian(a.problem.get(), a.blocks, &cost);
  params.tail(n - g) = values;
  const ObservabilityReport off =
      AnalyseJacobian(J, n, geometric, layout, invariants, rank_tolerance);
  std::vector<Eigen::VectorXd> out;
  for (int k = 0; k < off.null_basis.cols(); ++k) {
    Eigen::VectorXd v = Eigen::VectorXd::Zero(n);
    for (std::size_t c = 0; c < geometric.size(); ++c) {
      v(geometric[c]) = off.column_scale(c) * off.null_basis(c, k);
    }
    out.push_back(std::move(v));
  }
  return out;
}

}  // namespace

void ValidateIdentificationOptions(const IdentificationOptions& o) {
  // No user sets these (the scenario and CLI reach none of them): a bad value is our bug.
  auto fail = [](const char* field, double v, const char* expected) {
    FailPrecondition("valid IdentificationOptions",
                     std::string("IdentificationOptions.") + field + " " + expected + ", got " +
                         std::to_string(v),
                     __FILE__, __LINE__);
  };
  if (o.max_iterations < 1) fail("max_iterations", o.max_iterations, "must be >= 1");
  if (!(o.function_tolerance > 0.0 && o.function_tolerance < 1.0)) {
    fail("function_tolerance", o.function_tolerance, "must be in (0, 1)");
  }
  if (!(std::isfinite(o.gradient_tolerance) && o.gradient_tolerance > 0.0)) {
    fail("gradient_tolerance", o.gradient_tolerance, "must be a positive finite number");
  }
  if (!(std::isfinite(o.parameter_tolerance) && o.parameter_tolerance > 0.0)) {
    fail("parameter_tolerance", o.parameter_tolerance, "must be a positive finite number");
  }
  if (!(o.rank_tolerance > 0.0 && o.rank_tolerance < 1.0)) {
    fail("rank_tolerance", o.rank_tolerance, "must be in (0, 1)");
  }
  if (o.num_threads < 1) fail("num_threads", o.num_threads, "must be >= 1");
  if (!(o.correlation_threshold >= 0.0 && o.correlation_threshold <= 1.0)) {
    fail("correlation_threshold", o.correlation_threshold, "must be in [0, 1]");
  }
  if (o.max_correlations < 0) fail("max_correlations", o.max_correlations, "must be >= 0");
}

const char* ToString(IdentificationStatus status) {
  switch (status) {
    case IdentificationStatus::kConverged: return "converged";
    case IdentificationStatus::kMaxIterations: return "max_iterations";
    case IdentificationStatus::kFailed: return "failed";
  }
  return "unknown";
}

ObservabilityReport AnalyseIdentifiability(const RobotModel& model,
                                           const std::vector<MeasurementSet*>& sets,
                                           const IdentificationOptions& options) {
  ValidateIdentificationOptions(options);
  Validate(model, sets);
  const ParameterLayout layout(model);
  for (MeasurementSet* s : sets) s->Initialize(model);
  Eigen::VectorXd params = GetParameters(model);
  Assembly a = Assemble(model, params.data(), sets, options);
  const std::vector<int> free = FreeParameters(layout, options);
  const std::vector<Eigen::VectorXd> invariants = AllInvariants(model, layout, sets);
  const std::vector<Eigen::VectorXd> held =
      GeometryNullSpaceWithTermsOff(a, params, layout, free, invariants, options.rank_tolerance);
  double cost = 0;
  Eigen::MatrixXd J = DenseJacobian(a.problem.get(), a.blocks, &cost);
  HoldDirections(held, layout, &J);
  return AnalyseJacobian(J, model.num_parameters(), free, layout, invariants,
                         options.rank_tolerance);
}

IdentificationResult Identify(const RobotModel& start, const std::vector<MeasurementSet*>& sets,
                              const IdentificationOptions& options) {
  ValidateIdentificationOptions(options);
  Validate(start, sets);
  const ParameterLayout layout(start);
  const int n = layout.size();
  IdentificationResult res;
  res.model = start;
  res.correction = Eigen::VectorXd::Zero(n);
  res.covariance = Eigen::MatrixXd::Zero(n, n);
  res.free_parameters = FreeParameters(layout, options);

  for (MeasurementSet* s : sets) s->Initialize(start);
  for (const MeasurementSet* s : sets) {
    const std::vector<double> r = s->ResidualNorms(start);
    double sum = 0;
    for (double v : r) sum += v * v;
    res.sets.push_back({s->kind(), s->size(), std::sqrt(sum / std::max<size_t>(1, r.size())), 0});
  }
  const Eigen::VectorXd phi0 = GetParameters(start);
  Eigen::VectorXd params = phi0;
  Assembly a = Assemble(start, params.data(), sets, options);

  // 1. Observability at the start, the geometry's null space taken with the terms off (header).
  const std::vector<Eigen::VectorXd> invariants = AllInvariants(start, layout, sets);
  const std::vector<Eigen::VectorXd> held = GeometryNullSpaceWithTermsOff(
      a, params, layout, res.free_parameters, invariants, options.rank_tolerance);
  Eigen::MatrixXd J0 = DenseJacobian(a.problem.get(), a.blocks, &res.cost_before);
  res.residual_rows = static_cast<int>(J0.rows());
  HoldDirections(held, layout, &J0);
  res.observability = AnalyseJacobian(J0, n, res.free_parameters, layout, invariants,
                                      options.rank_tolerance);
  const int rank = res.observability.rank;
  const int f = static_cast<int>(res.free_parameters.size());
  res.identifiable_directions = Eigen::MatrixXd::Zero(n, rank);
  for (int c = 0; c < f; ++c) {
    res.identifiable_directions.row(res.free_parameters[c]) =
        res.observability.column_scale(c) * res.observability.identifiable_basis.row(c);
  }
  res.z = Eigen::VectorXd::Zero(rank);
  res.unknowns = rank + a.nuisance_tangent;
  auto fill_parameters = [&]() {
    std::set<int> free(res.free_parameters.begin(), res.free_parameters.end());
    res.parameters.clear();
    for (int i = 0; i < n; ++i) {
      const ParameterInfo& p = layout[i];
      res.parameters.push_back({p.name, p.unit, p.block, phi0(i), params(i),
                                std::sqrt(std::max(0.0, res.covariance(i, i))), !free.count(i)});
    }
  };
  if (rank == 0) {
    res.status = IdentificationStatus::kFailed;
    res.reason = "no identifiable parameter combination (rank 0)";
    fill_parameters();
    return res;
  }

  // 2. The model block moves in the identifiable subspace only.
  a.problem->SetManifold(params.data(), new SubspaceManifold(res.identifiable_directions));

  // 3. Solve; re-estimate the group weights and solve again.
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = options.max_iterations;
  so.function_tolerance = options.function_tolerance;
  so.gradient_tolerance = options.gradient_tolerance;
  so.parameter_tolerance = options.parameter_tolerance;
  so.num_threads = options.num_threads;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, a.problem.get(), &summary);
  res.iterations = static_cast<int>(summary.iterations.size()) - 1;
  std::vector<ResidualGroup> groups;
  for (MeasurementSet* s : sets) {
    for (ResidualGroup& g : s->groups()) groups.push_back(std::move(g));
  }
  if (options.estimate_group_weights && groups.size() > 1 && summary.IsSolutionUsable()) {
    bool changed = false;
    for (ResidualGroup& g : groups) {
      if (g.redundancy <= 0 || g.blocks.empty()) continue;
      double ssr = 0;
      for (ceres::ResidualBlockId id : g.blocks) {
        const int rows = a.problem->GetCostFunctionForResidualBlock(id)->num_residuals();
        std::vector<double> r(rows);
        double cost = 0;
        a.problem->EvaluateResidualBlock(id, false, &cost, r.data(), nullptr);
        const int end = g.num_rows < 0 ? rows : std::min(rows, g.first_row + g.num_rows);
        for (int i = g.first_row; i < end; ++i) ssr += r[i] * r[i];
      }
      const double factor = std::sqrt(ssr / g.redundancy);  // weighted sigma of the group
      if (factor > 0 && std::isfinite(factor)) {
        *g.weight = std::clamp(*g.weight / factor, 1e-12, 1e12);
        changed = true;
      }
    }
    if (changed) {
      ceres::Solve(so, a.problem.get(), &summary);
      res.iterations += static_cast<int>(summary.iterations.size()) - 1;
    }
  }
  for (const ResidualGroup& g : groups) res.groups.push_back({g.name, 1.0 / *g.weight, g.redundancy});
  res.brief_report = summary.BriefReport();
  res.reason = summary.message;
  switch (summary.termination_type) {
    case ceres::CONVERGENCE: res.status = IdentificationStatus::kConverged; break;
    case ceres::NO_CONVERGENCE: res.status = IdentificationStatus::kMaxIterations; break;
    default: res.status = IdentificationStatus::kFailed; break;
  }
  if (res.status == IdentificationStatus::kFailed) {
    params = phi0;
    fill_parameters();
    return res;
  }
  res.model = WithParameters(start, params);
  res.correction = params - phi0;
  {
    const Eigen::MatrixXd& B = res.identifiable_directions;
    res.z = (B.transpose() * B).ldlt().solve(B.transpose() * res.correction);
  }

  // 4. Uncertainty from the Jacobian at the solution (tangent columns: z, then nuisance).
  const Eigen::MatrixXd J = DenseJacobian(a.problem.get(), a.blocks, &res.cost_after);
  const int k = static_cast<int>(J.cols());
  // Degrees of freedom: the groups' independent rows less the nuisance each determines (their
  // redundancies), less the identifiable coordinates. Rows of a residual are not all
  // independent (an optical-axis perpendicular has 3 rows in a plane), so J's row count would
  // overstate them; without groups, the rows.
  int dof = 0;
  for (const GroupSummary& g : res.groups) dof += g.redundancy;
  dof = res.groups.empty() ? static_cast<int>(J.rows()) - k : dof - rank;
  res.redundancy = dof;
  res.sigma0 = dof > 0 ? std::sqrt(2.0 * res.cost_after / dof) : 0.0;
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(J);
  const Eigen::MatrixXd R =
      qr.matrixQR().topRows(std::min<Eigen::Index>(k, J.rows())).triangularView<Eigen::Upper>();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(R, Eigen::ComputeFullV);
  const Eigen::VectorXd sv = svd.singularValues();
  Eigen::VectorXd inv2 = Eigen::VectorXd::Zero(sv.size());
  for (int i = 0; i < sv.size(); ++i) {
    if (sv(i) > 1e-12 * sv(0)) inv2(i) = 1.0 / (sv(i) * sv(i));
  }
  const Eigen::MatrixXd cov_all =
      res.sigma0 * res.sigma0 * svd.matrixV() * inv2.asDiagonal() * svd.matrixV().transpose();
  const Eigen::MatrixXd& B = res.identifiable_directions;
  res.covariance_z = cov_all.topLeftCorner(rank, rank);
  res.covariance = B * res.covariance_z * B.transpose();
  fill_parameters();
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      const double si = res.parameters[i].sigma, sj = res.parameters[j].sigma;
      if (!(si > 0 && sj > 0)) continue;
      const double rho = res.covariance(i, j) / (si * sj);
      if (std::abs(rho) >= options.correlation_threshold) {
        res.correlations.push_back({layout[i].name, layout[j].name, rho});
      }
    }
  }
  std::sort(res.correlations.begin(), res.correlations.end(),
            [](const ParameterCorrelation& a, const ParameterCorrelation& b) {
              return std::abs(a.rho) > std::abs(b.rho);
            });
  if (static_cast<int>(res.correlations.size()) > options.max_correlations) {
    res.correlations.resize(options.max_correlations);
  }
  // 5. How far each term can be told from the geometry, on the full columns at the solution.
  if (options.term_dependence && layout.size() > layout.geometry_size()) {
    a.problem->SetManifold(params.data(), nullptr);
    double cost = 0;
    const Eigen::MatrixXd Jp = DenseJacobian(a.problem.get(), a.blocks, &cost);
    res.term_dependence = TermDependence(Jp, n, res.free_parameters, layout);
  }
  for (size_t s = 0; s < sets.size(); ++s) {
    const std::vector<double> r = sets[s]->ResidualNorms(res.model);
    double sum = 0;
    for (double v : r) sum += v * v;
    res.sets[s].rms_after = std::sqrt(sum / std::max<size_t>(1, r.size()));
  }
  return res;
}

}  // namespace twin
