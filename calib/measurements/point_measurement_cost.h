// The Ceres cost of a measurement of the robot's end point: the end point p_BE and its
// Jacobian with respect to the model's flat parameters come from EndPointJacobian (analytic or
// autodiff), the measurement's own residual r(p, nuisance...) from its templated functor by
// ceres::AutoDiffCostFunction over [p (3), nuisance blocks], and the chain rule joins them:
// dr/dphi = dr/dp dp/dphi. Parameter blocks: the model's flat parameters, then the nuisance.
#pragma once

#include <array>
#include <memory>

#include <Eigen/Core>
#include <ceres/ceres.h>

#include "calib/model/end_point_jacobian.h"
#include "calib/model/robot_model.h"

namespace twin {

template <class Measurement, int kRows, int... kNuisance>
class PointMeasurementCost final : public ceres::CostFunction {
 public:
  /// Takes ownership of `measurement`; `model` must outlive the cost.
  PointMeasurementCost(const RobotModel& model, MeasurementContext context,
                       Measurement* measurement)
      : model_(model), context_(std::move(context)), inner_(measurement) {
    set_num_residuals(kRows);
    mutable_parameter_block_sizes()->push_back(model.num_parameters());
    (mutable_parameter_block_sizes()->push_back(kNuisance), ...);
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    constexpr int kBlocks = 1 + sizeof...(kNuisance);
    Vector3 p;
    PointJacobian Jp;
    const bool model_jacobian = jacobians != nullptr && jacobians[0] != nullptr;
    if (model_jacobian) {
      EndPointJacobian(model_, parameters[0], context_, &p, &Jp);
    } else {
      p = RobotEndPoseT<double>(model_, parameters[0], context_).p;
    }
    std::array<const double*, kBlocks> inner_params;
    inner_params[0] = p.data();
    for (int k = 1; k < kBlocks; ++k) inner_params[k] = parameters[k];
    if (jacobians == nullptr) return inner_.Evaluate(inner_params.data(), residuals, nullptr);
    std::array<double, kRows * 3> dr_dp;
    std::array<double*, kBlocks> inner_jacobians;
    inner_jacobians[0] = model_jacobian ? dr_dp.data() : nullptr;
    for (int k = 1; k < kBlocks; ++k) inner_jacobians[k] = jacobians[k];
    if (!inner_.Evaluate(inner_params.data(), residuals, inner_jacobians.data())) return false;
    if (model_jacobian) {
      using RowMajor = Eigen::Matrix<double, kRows, Eigen::Dynamic, Eigen::RowMajor>;
      Eigen::Map<RowMajor>(jacobians[0], kRows, Jp.cols()) =
          Eigen::Map<const Eigen::Matrix<double, kRows, 3, Eigen::RowMajor>>(dr_dp.data()) * Jp;
    }
    return true;
  }

 private:
  const RobotModel& model_;
  MeasurementContext context_;
  ceres::AutoDiffCostFunction<Measurement, kRows, 3, kNuisance...> inner_;
};

}  // namespace twin
