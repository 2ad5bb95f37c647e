#include "bench/runs/serve_cell.h"

#include <cstdio>

#include "bench/io/output_files.h"
#include "bench/io/scenario.h"
#include "bench/runs/handclasp_run.h"
#include "remote/cell_server.h"
#include "sim/cell/twin_cell.h"

namespace twin {

namespace {

// What Describe says of the scenario's twin.
remote::CellDescription DescribeTwin(const Scenario& sc) {
  remote::CellDescription d;
  d.cell_name = sc.name;
  const TwinSpec& spec = sc.twin;
  for (int k = 0; k < spec.num_robots; ++k) {
    const bool named = k < static_cast<int>(sc.robot_names.size());
    d.robot_names.push_back(named ? sc.robot_names[k] : "r" + std::to_string(k + 1));
    const KinematicModel& model = spec.robots[k].model;
    std::vector<JointLimits> limits;
    for (int i = 0; i < model.num_joints(); ++i) limits.push_back(model.links[i].limits);
    d.limits.push_back(limits);
  }
  d.has_camera = spec.HasCameraAndBoard();
  if (d.has_camera) {
    d.image_width_px = spec.camera.intrinsics.width;
    d.image_height_px = spec.camera.intrinsics.height;
  }
  d.has_tracker = spec.tracker.present;
  d.has_handclasp = spec.num_robots == kMaxRobots;
  d.has_clock = true;
  return d;
}

// Host of HOST:PORT (as given, brackets kept).
std::string HostOf(const std::string& listen) {
  const auto colon = listen.rfind(':');
  return colon == std::string::npos ? listen : listen.substr(0, colon);
}

}  // namespace

int RunServeCell(const ServeCellOptions& o) {
  Scenario sc = LoadScenario(o.scenario);
  ApplyTrial(o.trial, &sc);
  // The scenario's simulated operator (its handclasp section's operator_error), also with
  // --no-truth, where no client can set it; parsed before the twin is built (bad input: exit 2).
  const double operator_sigma_m =
      IsPresent(sc.handclasp) ? ParseHandclaspConfig(sc).operator_error_m : 0.0;
  TwinCell twin(sc.twin, sc.path);
  twin.SetRealtime(o.realtime);
  twin.SetOperatorAlignmentError(operator_sigma_m);
  remote::ServerOptions server_options;
  server_options.listen = o.listen;
  server_options.tls_cert_file = o.tls_cert_file;
  server_options.tls_key_file = o.tls_key_file;
  server_options.client_ca_file = o.client_ca_file;
  server_options.token_file = o.token_file;
  server_options.heartbeat_timeout_s = o.heartbeat_timeout_s;
  server_options.stop_motion = [&twin] { twin.RequestStop(); };
  if (o.truth) {  // the bench channel: the truth, and the twin's simulated operator
    server_options.truth = [&twin] { return twin.Truth(); };
    server_options.set_operator_error = [&twin](double sigma_m) {
      twin.SetOperatorAlignmentError(sigma_m);
    };
  }
  remote::CellServer server(twin, DescribeTwin(sc), server_options);
  // SIGINT / SIGTERM / SIGHUP (waited for by bench/io/output_files' thread): shut down and
  // return 0 instead of ending by the signal.
  SetInterruptHandler([&server](int) { server.Shutdown(); });
  std::printf("serving %s on %s:%d\n", sc.name.c_str(), HostOf(o.listen).c_str(),
              server.BoundPort());
  std::fflush(stdout);
  server.Wait();
  server.Shutdown();
  SetInterruptHandler({});
  return 0;
}

}  // namespace twin
