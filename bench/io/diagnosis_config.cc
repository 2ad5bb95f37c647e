#include "bench/io/diagnosis_config.h"

#include "bench/io/scenario_keys.h"
#include "bench/io/term_spec_text.h"
#include "calib/common/errors.h"
#include "calib/model/error_term.h"

namespace twin {

void AddPointMass(double mass_kg, const Vector3& p_com_L, Link* link) {
  const double m0 = link->inertia.mass;
  link->inertia.p_LiCom = (m0 * link->inertia.p_LiCom + mass_kg * p_com_L) / (m0 + mass_kg);
  link->inertia.mass = m0 + mass_kg;
}

void ParseDiagnosisSection(const YamlReader& r, const YamlField& field,
                           const KinematicModel& nominal, DiagnosisConfig* c,
                           DiscoveryOptions* o, bool optical_axes) {
  // Their tables in bench/io/scenario_keys.cc (the scenario schema's source).
  static const YamlKeys kKeys = ScenarioKeyNames("tracker_diagnosis");
  static const YamlKeys kOpticalKeys = ScenarioKeyNames("calibration_diagnosis");
  const YamlMap d(r, field, optical_axes ? kOpticalKeys : kKeys);
  // Stated noise: a sigma below 0.1 um is no camera's, above 10 mm no calibration's.
  const auto sigma_mm = [&](const char* key, double* out) {
    if (const auto v = d.Find(key, false)) {
      const double mm = r.Number(*v);
      if (!(mm >= 1e-4 && mm <= 10.0)) r.Fail(*v, "expected 0.0001 to 10 mm");
      *out = mm / 1000.0;
    }
  };
  sigma_mm("perpendicular_sigma_mm", &o->axis_set.sigma_perpendicular);
  sigma_mm("depth_sigma_mm", &o->axis_set.sigma_depth);
  if (const auto v = d.Find("encoder_sigma_deg", false)) {
    const double deg = r.Number(*v);
    if (!(deg >= 0.0 && deg <= 0.5)) r.Fail(*v, "expected 0 to 0.5 deg");
    o->joint_sigma_rad = DegToRad(deg);
  }
  if (const auto v = d.Find("enabled", false)) c->enabled = r.Bool(*v);
  if (const auto v = d.Find("screen", false)) o->screen_when_noise = r.Bool(*v);
  if (const auto v = d.Find("alpha", false)) o->alpha = r.Number(*v);
  if (const auto v = d.Find("min_gain_percent", false)) o->min_gain_percent = r.Number(*v);
  if (const auto v = d.Find("max_effects", false)) o->max_effects = r.Integer(*v);
  if (const auto v = d.Find("folds", false)) o->folds = r.Integer(*v);
  if (const auto v = d.Find("candidates", false)) {
    if (!v->node.IsSequence() || v->node.size() == 0) {
      r.Fail(*v, "expected a non-empty list of terms TYPE[:JOINT[:ORDERS]]");
    }
    for (std::size_t k = 0; k < v->node.size(); ++k) {
      const YamlField item = v->Item(k);
      const TermSpec spec = ParseTermSpec(r.String(item), r.Where(item));
      MakeErrorTerm(spec, nominal, "check", r.Where(item));
      o->candidates.push_back(spec);
    }
  }
  if (const auto v = d.Find("truth_poses", false)) {
    c->truth_poses = r.Integer(*v);
    if (c->truth_poses < 10 || c->truth_poses > 10000) r.Fail(*v, "expected 10 to 10000");
  }
  try {
    ValidateDiscoveryOptions(*o);
  } catch (const InputError& e) {
    r.Fail(field, e.what());
  }
}

}  // namespace twin
