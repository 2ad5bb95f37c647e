#include "calib/planning/plan_store.h"

#include <cstdio>
#include <sstream>

namespace twin {
namespace {

// %a: the exact binary value as text (round trips, no decimal rounding).
std::string Hex(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%a", v);
  return buf;
}

void Write(std::ostringstream& os, const std::string& key, double v) {
  os << key << ' ' << Hex(v) << '\n';
}

void WriteTransform(std::ostringstream& os, const std::string& key, const Transform& X) {
  os << key;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) os << ' ' << Hex(X.matrix()(r, c));
  }
  os << '\n';
}

void WriteModel(std::ostringstream& os, const std::string& key, const KinematicModel& m) {
  os << key << ".name " << m.name << '\n';
  os << key << ".joints " << m.num_joints() << '\n';
  WriteTransform(os, key + ".X_BL0", m.X_BL0);
  WriteTransform(os, key + ".X_LtE", m.X_LtE);
  for (int i = 0; i < m.num_links(); ++i) {
    const Link& l = m.links[i];
    const std::string k = key + ".link" + std::to_string(i + 1);
    Write(os, k + ".theta", l.dh.theta_offset);
    Write(os, k + ".d", l.dh.d);
    Write(os, k + ".a", l.dh.a);
    Write(os, k + ".alpha", l.dh.alpha);
    Write(os, k + ".beta", l.dh.beta);
    Write(os, k + ".lower", l.limits.lower);
    Write(os, k + ".upper", l.limits.upper);
  }
}

}  // namespace

std::string PlanInputsText(const PlanInputs& in) {
  std::ostringstream os;
  os << "plan_inputs 1\n";
  WriteModel(os, "active", in.active);
  WriteModel(os, "passive", in.passive);
  WriteTransform(os, "X_BaBp", in.X_BaBp);
  WriteTransform(os, "X_FC", in.X_FC);
  const PosePlannerOptions& o = in.options;
  os << "num_axes " << o.num_axes << "\npositions_per_axis " << o.positions_per_axis
     << "\nswarm_size " << o.swarm_size << "\niterations " << o.iterations << "\nruns "
     << o.runs << '\n';
  // The run selection only when it is not the paper's, so the keys of plans made before it
  // existed stay the same.
  if (o.select_run != PosePlannerOptions::RunSelection::kBestFitness) {
    os << "select_run predicted_error\nprediction_configurations "
       << o.prediction_configurations << "\nprediction_seed " << o.prediction_seed << '\n';
  }
  Write(os, "inertia", o.inertia);
  Write(os, "learning_personal", o.learning_personal);
  Write(os, "learning_global", o.learning_global);
  Write(os, "max_velocity_fraction", o.max_velocity_fraction);
  Write(os, "min_joint_limit_distance", o.min_joint_limit_distance);
  Write(os, "min_singular_value", o.min_singular_value);
  Write(os, "max_visibility_angle", o.max_visibility_angle);
  Write(os, "min_distance", o.min_distance);
  Write(os, "max_distance", o.max_distance);
  Write(os, "planning_max_distance", o.planning_max_distance);
  Write(os, "distance_step", o.distance_step);
  Write(os, "camera_reach", o.camera_reach);
  Write(os, "camera_height", o.camera_height);
  Write(os, "camera_region_half_extent", o.camera_region_half_extent);
  Write(os, "axis_cone_half_angle", o.axis_cone_half_angle);
  for (int i = 0; i < 3; ++i) Write(os, "board_normal_in_E." + std::to_string(i), o.board_normal_in_E(i));
  // The IK seeds only where given, so the keys of plans made before they existed stay the same.
  for (const auto& [name, seed] : {std::pair<const char*, const JointVector*>{"active_ik_seed", &o.active_ik_seed},
                                   {"passive_ik_seed", &o.passive_ik_seed}}) {
    for (int i = 0; i < seed->size(); ++i) Write(os, std::string(name) + "." + std::to_string(i), (*seed)(i));
  }
  // Written when on (not the default): the keys of the iterative IK's plans stay as they were.
  if (o.closed_form_ik) os << "ik.closed_form 1\n";
  os << "max_draws_per_axis " << o.max_draws_per_axis << "\nredraws_after_update "
     << o.redraws_after_update << '\n';
  Write(os, "rank_tolerance", o.rank_tolerance);
  const IkOptions& ik = o.ik;
  Write(os, "ik.position_tolerance", ik.position_tolerance);
  Write(os, "ik.orientation_tolerance", ik.orientation_tolerance);
  os << "ik.max_iterations " << ik.max_iterations << '\n';
  Write(os, "ik.damping", ik.damping);
  Write(os, "ik.max_step", ik.max_step);
  Write(os, "ik.orientation_weight", ik.orientation_weight);
  os << "ik.position_only " << ik.position_only << "\nik.random_restarts " << ik.random_restarts
     << "\nik.seed " << ik.seed << "\nseed " << o.seed << '\n';
  return os.str();
}

}  // namespace twin
