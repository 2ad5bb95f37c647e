// A stand-in for model discovery's Data (calib/diagnosis/discovery_data.h) in the tests of the
// parts that only call it: no model, no identification.
#pragma once

#include <algorithm>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "calib/diagnosis/discovery_data.h"

namespace twin::discovery::stub {

// Data of n units without a model: a fit remembers its training units (in Fit::axes) and has
// 2 unknowns; a held-out unit's residual is 1 where the fit trained on it (a leak), else 0,
// its loss 1 + i, its squared distance 4 and its chi-square 1, one dof a unit.
class StubData : public Data {
 public:
  /// Where set, FitOn is this (the model and the fit's name).
  std::function<Fit(const RobotModel&, const std::string&)> fit;

  explicit StubData(int n, bool global = false, MeasurementContext context = {})
      : n_(n), global_(global), context_(std::move(context)) {}
  int size() const override { return n_; }
  const std::string& source() const override { return source_; }
  const MeasurementContext& context(int) const override { return context_; }
  std::string Where(int i) const override { return "unit " + std::to_string(i); }
  double Order(int i) const override { return i; }
  std::string Measured() const override { return "stub data"; }
  Fit FitOn(const RobotModel& model, const std::vector<int>& train,
            const std::string& what) const override {
    if (fit) return fit(model, what);
    Fit f;
    f.axes = train;
    f.result.unknowns = 2;
    return f;
  }
  double Rows(const std::vector<int>& train) const override { return train.size(); }
  void HeldOut(const Fit& fit, const std::vector<int>& test, CrossValidation* cv) const override {
    for (int i : test) {
      const bool leak = std::find(fit.axes.begin(), fit.axes.end(), i) != fit.axes.end();
      cv->e[i] = Eigen::VectorXd::Constant(1, leak ? 1.0 : 0.0);
      cv->loss[i] = 1.0 + i;
      cv->dist2[i] = 4.0;
      cv->chi2[i] = 1.0;
      cv->dof += 1.0;
    }
  }
  Components ResidualComponents(const CrossValidation&) const override { return {}; }
  bool GlobalTest() const override { return global_; }
  CrossValidation InSample(const RobotModel&, const std::string&) const override {
    CrossValidation cv;
    cv.Resize(n_);
    cv.dof = 0;  // no redundancy
    return cv;
  }

 private:
  int n_;
  bool global_;
  std::string source_ = "stub";
  MeasurementContext context_;
};

}  // namespace twin::discovery::stub
