#include "bench/runs/bench_cell.h"

#include <fstream>
#include <utility>

#include "bench/runs/recording_cell.h"
#include "bench/runs/replay_cell.h"
#include "calib/common/errors.h"
#include "remote/grpc_cell.h"

namespace twin {

namespace {

// The scenario's twin, built here and owned by the cell that drives it.
struct TwinHolder {
  TwinHolder(const TwinSpec& spec, const std::string& where)
      : twin(std::make_unique<TwinCell>(spec, where)) {}
  std::unique_ptr<TwinCell> twin;
};

class OwnedLocalTwinCell : private TwinHolder, public LocalTwinCell {
 public:
  OwnedLocalTwinCell(const TwinSpec& spec, const std::string& where)
      : TwinHolder(spec, where), LocalTwinCell(*twin) {}
};

// A cell served over the cell protocol (remote/grpc_cell.h), its truth over the bench's truth
// channel.
class RemoteBenchCell : public BenchCell {
 public:
  RemoteBenchCell(const std::string& address, const remote::GrpcCellCredentials& credentials,
                  const std::string& where)
      : cell_(address, credentials, where) {}
  MoveResult MoveTo(int robot, const JointVector& q) override { return cell_.MoveTo(robot, q); }
  JointVector ReadEncoders(int robot) override { return cell_.ReadEncoders(robot); }
  cv::Mat GrabImage() override { return cell_.GrabImage(); }
  cv::Mat GrabImageRegion(const cv::Rect& roi) override { return cell_.GrabImageRegion(roi); }
  MoveResult ExchangeTools() override { return cell_.ExchangeTools(); }
  int CameraRobot() override { return cell_.CameraRobot(); }
  MoveResult JogTipToContact(int jogged_robot) override {
    return cell_.JogTipToContact(jogged_robot);
  }
  MoveResult MountTarget(BracketTarget target) override { return cell_.MountTarget(target); }
  double ClockSeconds() override { return cell_.ClockSeconds(); }
  double ReadTemperatureC(int robot) override { return cell_.ReadTemperatureC(robot); }
  TrackerReading MeasureTracker(int robot) override { return cell_.MeasureTracker(robot); }
  TwinTruth Truth() override { return cell_.Truth(); }
  bool HasTruth() override { return cell_.HasTruth(); }
  bool SetOperatorAlignmentError(double sigma_m) override {
    return cell_.SetOperatorAlignmentError(sigma_m);
  }

 private:
  remote::GrpcCell cell_;
};

// "HOST:PORT" of "grpc://HOST:PORT" (HOST may be [v6]); InputError naming --cell otherwise.
std::string GrpcHostPort(const std::string& address) {
  const std::string scheme = "grpc://";
  const auto bad = [&](const std::string& why) {
    return InputError("--cell", "'" + address + "': " + why +
                                    " (expected grpc://HOST:PORT, e.g. grpc://127.0.0.1:50051)");
  };
  if (address.compare(0, scheme.size(), scheme) != 0) throw bad("not a grpc:// address");
  const std::string rest = address.substr(scheme.size());
  const auto colon = rest.rfind(':');
  if (colon == std::string::npos || colon == 0) throw bad("no host and port");
  const std::string host = rest.substr(0, colon), port = rest.substr(colon + 1);
  if (port.empty() || port.size() > 5 ||
      port.find_first_not_of("0123456789") != std::string::npos || std::stoi(port) == 0 ||
      std::stoi(port) > 65535) {
    throw bad("the port must be a number from 1 to 65535");
  }
  if (host.find_first_of("/ \t@?#") != std::string::npos) throw bad("not a host name");
  return rest;
}

void RequireReadable(const std::string& path, const std::string& flag) {
  if (path.empty()) return;
  std::ifstream in(path);
  if (!in) throw InputError(flag, "cannot read '" + path + "'");
}

}  // namespace

std::unique_ptr<BenchCell> OpenBenchCell(const TwinSpec& twin, const std::string& where,
                                         const CellOptions& options) {
  // A recording played back: no cell at all (a replay records nothing).
  if (!options.replay_dir.empty()) return std::make_unique<ReplayCell>(options.replay_dir);
  std::unique_ptr<BenchCell> cell;
  if (options.address.empty()) {
    for (const auto& [value, flag] :
         {std::pair{&options.tls_ca_file, "--cell-ca"},
          std::pair{&options.tls_cert_file, "--cell-cert"},
          std::pair{&options.tls_key_file, "--cell-key"},
          std::pair{&options.token_file, "--cell-token-file"}}) {
      if (!value->empty()) {
        throw InputError(flag, "a credential of a served cell; give the cell with --cell "
                               "grpc://HOST:PORT (without --cell the run drives the scenario's "
                               "twin in this process)");
      }
    }
    cell = std::make_unique<OwnedLocalTwinCell>(twin, where);
  } else {
    const std::string host_port = GrpcHostPort(options.address);
    RequireReadable(options.tls_ca_file, "--cell-ca");
    RequireReadable(options.tls_cert_file, "--cell-cert");
    RequireReadable(options.tls_key_file, "--cell-key");
    RequireReadable(options.token_file, "--cell-token-file");
    remote::GrpcCellCredentials credentials;
    credentials.ca_file = options.tls_ca_file;
    credentials.cert_file = options.tls_cert_file;
    credentials.key_file = options.tls_key_file;
    credentials.token_file = options.token_file;
    cell = std::make_unique<RemoteBenchCell>(host_port, credentials, "--cell " + options.address);
  }
  if (!options.record_dir.empty()) {
    cell = std::make_unique<RecordingCell>(std::move(cell), options.record_dir,
                                           options.record_info);
  }
  return cell;
}

}  // namespace twin
