// Scoring one candidate term (internal to calib/diagnosis; model_discovery.h, step 3): the base
// model with the term where the data has its context, its fit on all the data (with the
// dormant-term restart of calib/identification/dormant_restart.h), its parameters and size
// test, whether it raises the rank, how nearly it is the geometry in disguise, and its
// region-disjoint held-out score against the step's base. Whether the scores make it
// acceptable is decided elsewhere, once (selection.h, Judge).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "calib/diagnosis/discovery_data.h"

namespace twin::discovery {

/// The size test of a candidate (CandidateScore::size_p_value): Wald's chi-square of its size
/// measures (ErrorTerm::SizeMeasures: by default its amplitude parameters; a warm-up's growth
/// by the data's latest time stamp `session_s`) against zero, their covariance J C J^T from
/// the term's covariance block C (first, its parameters) by the delta method, with its
/// pseudo-inverse over the numerical rank (a combination the data cannot see has no variance
/// there and counts for nothing). A term can raise the rank and still have a size the data
/// cannot tell from zero: on the paper cell's optical axes (a 4 min session; the undeclared
/// mount deflection, trial 19) a warm-up started at 10 min, its growth nearly a scale of the
/// joint links (canonical correlation 0.99997), fitted a growth of 0.1 sigma (Wald p = 0.92)
/// yet won 38 % of the held-out sum of squares; added, it moved the physical-truth error from
/// 0.09 to 0.56 mm. The warm-up's final growth alone is the wrong measure the other way: for a
/// time constant long against the session it trades off against the time constant, and on
/// synthetic data a warm-up that explained 75 % of the held-out loss had p = 0.1 on it.
/// Requires `first` + the term's parameters within the fit's covariance; a term without
/// parameters leaves the test at its defaults.
void SizeTest(const IdentificationResult& fit, int first, const ErrorTerm& term, double session_s,
              CandidateScore* c);

/// Whether the term of `spec` has parameters that act only once others are non-zero
/// (ErrorTerm::has_dormant_parameters: a warm-up's time constant). Throws InputError where the
/// term cannot be made for start's chain.
bool HasDormantParameters(const TermSpec& spec, const RobotModel& start);

/// Sets `model` to `base` with the term of `spec`; false (c->applicable false, c->note why)
/// where the term cannot be made or the data lacks the context it needs.
bool BuildCandidateModel(const Data& data, const RobotModel& base, const TermSpec& spec,
                         RobotModel* model, CandidateScore* c);

/// A candidate's model and its fit on every unit of data.
struct CandidateFit {
  RobotModel model;  ///< the base with the term (restarted: from its first fit's term values)
  Fit all;           ///< the fit on every unit
  int added = 0;     ///< the term's parameters
  int first = 0;     ///< index of its first parameter in the model
  int rank = 0;      ///< of the all-data fit
};

/// Fits the candidate's `model` (the base, of rank `base_rank`, with the term last) on all
/// the data; where the term has dormant parameters and the rank rose by less than its
/// parameter count, restarts from that first solution's term values (FitWithDormantRestart).
/// Sets c->driver and c->restarted.
CandidateFit FitCandidate(const Data& data, RobotModel model, int base_rank, CandidateScore* c);

/// Records the term's parameters as fitted on all the data and its size test (SizeTest) at
/// the data's latest time stamp (NaN where the data has none).
void RecordParametersAndSize(const Data& data, const CandidateFit& f, CandidateScore* c);

/// Whether the term raises the rank above `base_rank` (else c->identifiable false); the note
/// says why not, or that it does only partly.
bool RaisesRank(const Data& data, const CandidateFit& f, int base_rank, CandidateScore* c);

/// Disguise of the geometry: the largest canonical correlation of the term's rank-raising
/// directions with the geometric columns (TermGeometryDependence), and the geometric
/// parameter nearest it.
void MeasureGeometryDisguise(const CandidateFit& f, int base_rank, CandidateScore* c);

/// The term's detection limit at the end point (CandidateScore::detection_limit_m) at level
/// `alpha`, from the all-data fit's TermGeometryDependence and the end point's Jacobian at
/// each unit's context.
void MeasureDetectionLimit(const Data& data, const CandidateFit& f, double alpha,
                           CandidateScore* c);

/// The candidate's region cross-validation against the base's `base_cv`: held-out RMS, gain
/// (reduction of the held-out loss sum [%]) and Wilcoxon's one-sided p on the per-unit loss
/// differences; c->tested true.
void TestHeldOut(const Data& data, const RobotModel& model, const std::vector<int>& region,
                 int folds, const CrossValidation& base_cv, CandidateScore* c);

/// Scores one candidate against the step's base (its region cross-validation `base_cv`);
/// without `cross_validate` (screening) it is fitted on all the data only. Throws InputError
/// where an identification of it refuses the data.
CandidateScore ScoreCandidate(const Data& data, const RobotModel& base, int base_rank,
                              const TermSpec& spec, const std::vector<int>& region, int folds,
                              const CrossValidation& base_cv, bool cross_validate, double alpha);

/// Every candidate of `specs` scored beside `current` (ScoreCandidate), `jobs` at a time, in
/// the order of `specs` whatever `jobs`; a candidate whose identification refuses the data
/// (InputError) is reported unidentifiable with the reason (an outcome, not an error); any
/// other exception is a bug and is rethrown once the workers have ended. `say` gets a
/// progress line per candidate done.
std::vector<CandidateScore> ScoreAll(const Data& data, const RobotModel& current, int base_rank,
                                     const std::vector<TermSpec>& specs,
                                     const std::vector<int>& region, int folds,
                                     const CrossValidation& base_cv, bool cross_validate,
                                     double alpha, int jobs,
                                     const std::function<void(const std::string&)>& say,
                                     const std::string& what);

}  // namespace twin::discovery
