#include "bench/report/plan_file.h"

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>

#include "calib/common/errors.h"

namespace twin {
using json = nlohmann::json;

namespace {

json Hex(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%a", v);
  return buf;
}

double FromHex(const json& j, const std::string& where) {
  if (!j.is_string()) throw InputError(where, "expected a hex-float string, got " + j.dump());
  const std::string s = j.get<std::string>();
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (end == s.c_str() || *end != '\0') throw InputError(where, "not a number: '" + s + "'");
  return v;
}

json Vec(const Eigen::Ref<const Eigen::VectorXd>& v) {
  json a = json::array();
  for (int i = 0; i < v.size(); ++i) a.push_back(Hex(v(i)));
  return a;
}

Eigen::VectorXd ReadVec(const json& j, const std::string& where) {
  if (!j.is_array()) throw InputError(where, "expected an array");
  Eigen::VectorXd v(j.size());
  for (std::size_t i = 0; i < j.size(); ++i) v(i) = FromHex(j[i], where);
  return v;
}

JointVector ReadJoints(const json& j, const std::string& where) {
  const Eigen::VectorXd v = ReadVec(j, where);
  if (v.size() < 1 || v.size() > kMaxJoints) throw InputError(where, "bad joint count");
  return JointVector(v);
}

Vector3 ReadVector3(const json& j, const std::string& where) {
  const Eigen::VectorXd v = ReadVec(j, where);
  if (v.size() != 3) throw InputError(where, "expected 3 numbers");
  return Vector3(v);
}

}  // namespace

json PlanToJson(const PosePlanResult& p) {
  json axes = json::array();
  for (const PlannedAxis& a : p.axes) {
    json qp = json::array();
    for (const JointVector& q : a.q_passive) qp.push_back(Vec(q));
    json d = json::array();
    for (double x : a.distances) d.push_back(Hex(x));
    axes.push_back({{"camera_origin", Vec(a.camera_origin)},
                    {"direction", Vec(a.direction)},
                    {"q_active", Vec(a.q_active)},
                    {"q_passive", qp},
                    {"distances", d}});
  }
  json history = json::array();
  for (const auto& run : p.fitness_history) {
    json h = json::array();
    for (double f : run) h.push_back(Hex(f));
    history.push_back(h);
  }
  const RejectionCounts& r = p.rejections;
  json run_fitness = json::array(), run_predicted = json::array(),
       run_predicted_similarity = json::array();
  for (double f : p.run_fitness) run_fitness.push_back(Hex(f));
  for (double e : p.run_predicted_error) run_predicted.push_back(Hex(e));
  for (double e : p.run_predicted_similarity_error) run_predicted_similarity.push_back(Hex(e));
  return json{{"status", ToString(p.status)},
              {"run_fitness", run_fitness},
              {"run_predicted_error", run_predicted},
              {"run_predicted_similarity_error", run_predicted_similarity},
              {"reason", p.reason},
              {"axes", axes},
              {"best_fitness", Hex(p.best_fitness)},
              {"best_run", p.best_run},
              {"fitness_history", history},
              {"rejections",
               {r.active_ik, r.passive_ik, r.c1_joint_limits, r.c2_singularity, r.c3_visibility,
                r.c4_min_distance, r.c5_max_distance}},
              {"evaluations", p.evaluations}};
}

PosePlanResult PlanFromJson(const json& j, const std::string& where) {
  try {
    PosePlanResult p;
    const std::string status = j.at("status").get<std::string>();
    if (status == ToString(PosePlannerStatus::kSuccess)) {
      p.status = PosePlannerStatus::kSuccess;
    } else if (status == ToString(PosePlannerStatus::kNoFeasiblePoses)) {
      p.status = PosePlannerStatus::kNoFeasiblePoses;
    } else {
      throw InputError(where + " status", "unknown plan status '" + status + "'");
    }
    p.reason = j.at("reason").get<std::string>();
    for (const json& a : j.at("axes")) {
      PlannedAxis axis;
      axis.camera_origin = ReadVector3(a.at("camera_origin"), where + " camera_origin");
      axis.direction = ReadVector3(a.at("direction"), where + " direction");
      axis.q_active = ReadJoints(a.at("q_active"), where + " q_active");
      for (const json& q : a.at("q_passive")) {
        axis.q_passive.push_back(ReadJoints(q, where + " q_passive"));
      }
      for (const json& d : a.at("distances")) axis.distances.push_back(FromHex(d, where));
      p.axes.push_back(std::move(axis));
    }
    p.best_fitness = FromHex(j.at("best_fitness"), where + " best_fitness");
    p.best_run = j.at("best_run").get<int>();
    for (const json& run : j.at("fitness_history")) {
      std::vector<double> h;
      for (const json& f : run) h.push_back(FromHex(f, where + " fitness_history"));
      p.fitness_history.push_back(std::move(h));
    }
    // Absent from plans stored before they were recorded.
    for (const json& f : j.value("run_fitness", json::array())) {
      p.run_fitness.push_back(FromHex(f, where + " run_fitness"));
    }
    for (const json& e : j.value("run_predicted_error", json::array())) {
      p.run_predicted_error.push_back(FromHex(e, where + " run_predicted_error"));
    }
    for (const json& e : j.value("run_predicted_similarity_error", json::array())) {
      p.run_predicted_similarity_error.push_back(
          FromHex(e, where + " run_predicted_similarity_error"));
    }
    const json& r = j.at("rejections");
    if (!r.is_array() || r.size() != 7) throw InputError(where, "rejections: expected 7 counts");
    RejectionCounts& c = p.rejections;
    c.active_ik = r[0];
    c.passive_ik = r[1];
    c.c1_joint_limits = r[2];
    c.c2_singularity = r[3];
    c.c3_visibility = r[4];
    c.c4_min_distance = r[5];
    c.c5_max_distance = r[6];
    p.evaluations = j.at("evaluations").get<int>();
    return p;
  } catch (const json::exception& e) {
    throw InputError(where, std::string("malformed plan: ") + e.what());
  }
}


std::string PlanFileText(const std::string& inputs_text, const PosePlanResult& plan) {
  const json j = {{"inputs", inputs_text}, {"plan", PlanToJson(plan)}};
  return j.dump() + "\n";
}

std::optional<PosePlanResult> ReadPlanFile(const std::string& path,
                                           const std::string& inputs_text) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  try {
    const json j = json::parse(in);
    // Not another input with this hash.
    if (j.at("inputs").get<std::string>() == inputs_text) return PlanFromJson(j.at("plan"), path);
  } catch (const std::exception&) {
    // Unreadable or foreign: a miss.
  }
  return std::nullopt;
}

}  // namespace twin
