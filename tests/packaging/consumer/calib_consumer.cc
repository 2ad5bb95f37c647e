// Links twinbench::calib from an installed package: builds the nominal model of an installed
// model YAML (the improved-DH links of models/*.yaml), computes its end pose by forward
// kinematics, checks it against known values and an IK round trip, and prints the pose in the
// format of `twinbench fk` so that the packaging test can compare the two.
//   calib_consumer MODEL.yaml Q1,...,QN(deg)
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "calib/kinematics/forward_kinematics.h"
#include "calib/kinematics/inverse_kinematics.h"
#include "calib/kinematics/kinematic_model.h"

namespace {

int Fail(const std::string& what) {
  std::fprintf(stderr, "calib_consumer: FAIL: %s\n", what.c_str());
  return 1;
}

double Angle(const YAML::Node& node, const char* key, double scale) {
  return node[key] ? node[key].as<double>() * scale : 0.0;
}

twin::DhParameters Dh(const YAML::Node& node, double angle_scale) {
  twin::DhParameters dh;
  dh.theta_offset = Angle(node, "theta_offset", angle_scale);
  dh.d = node["d"] ? node["d"].as<double>() : 0.0;
  dh.a = node["a"] ? node["a"].as<double>() : 0.0;
  dh.alpha = Angle(node, "alpha", angle_scale);
  dh.beta = Angle(node, "beta", angle_scale);
  return dh;
}

twin::KinematicModel LoadModel(const std::string& path) {
  const YAML::Node robot = YAML::LoadFile(path)["robot"];
  const double scale =
      robot["angle_unit"] && robot["angle_unit"].as<std::string>() == "deg" ? M_PI / 180.0 : 1.0;
  const YAML::Node links = robot["links"];
  twin::KinematicModel model(static_cast<int>(links.size()));
  model.name = robot["name"].as<std::string>();
  for (std::size_t i = 0; i < links.size(); ++i) {
    model.links[i].name = links[i]["name"].as<std::string>();
    model.links[i].dh = Dh(links[i], scale);
    const auto limits = links[i]["limits"].as<std::vector<double>>();
    model.links[i].limits = {limits.at(0) * scale, limits.at(1) * scale};
  }
  if (robot["tool"]) model.tool().dh = Dh(robot["tool"], scale);
  twin::ValidateModel(model, path);
  return model;
}

twin::JointVector ParseDeg(const std::string& text, int n) {
  twin::JointVector q(n);
  std::stringstream in(text);
  std::string item;
  int i = 0;
  while (std::getline(in, item, ',')) {
    if (i >= n) throw std::runtime_error("too many joint angles in " + text);
    q(i++) = std::stod(item) * M_PI / 180.0;
  }
  if (i != n) throw std::runtime_error("need " + std::to_string(n) + " joint angles: " + text);
  return q;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) return Fail("usage: calib_consumer MODEL.yaml Q1,...,QN (deg)");
  try {
    const twin::KinematicModel model = LoadModel(argv[1]);
    if (model.num_joints() != 6 || model.num_parameters() != 35) {
      return Fail("expected a six-axis model with 35 parameters");
    }
    // The Reinovo-like r1 at q = 0 (models/reinovo_r1.yaml: d1 + a2 + d4 ... by hand):
    // the end frame at (410, 60, 426) mm.
    if (model.name == "r1") {
      const twin::Vector3 p0 = twin::EndPose(model, twin::ZeroJoints(model)).translation();
      if ((p0 - twin::Vector3(0.410, 0.060, 0.426)).norm() > 1e-9) {
        return Fail("r1 end frame at q = 0 is not (410, 60, 426) mm");
      }
    }
    const twin::JointVector q = ParseDeg(argv[2], model.num_joints());
    const twin::Transform X = twin::EndPose(model, q);
    const twin::IkResult ik = twin::SolveIk(model, X, twin::MidRange(model));
    if (ik.status != twin::IkStatus::kSuccess) return Fail("IK failed: " + ik.reason);
    const double ik_error = (twin::EndPose(model, ik.q).translation() - X.translation()).norm();
    if (ik_error > 1e-6) return Fail("IK round trip off by " + std::to_string(ik_error) + " m");
    const twin::Vector3 p = X.translation() * 1e3;
    std::printf("end frame: xyz [%.4f, %.4f, %.4f] mm\n", p.x(), p.y(), p.z());
    std::printf("IK round trip: %.2e m\n", ik_error);
  } catch (const std::exception& e) {
    return Fail(e.what());
  }
  return 0;
}
