#include "bench/runs/twin_commands.h"

#include <pthread.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "bench/io/model_loader.h"
#include "bench/io/output_files.h"
#include "bench/io/scenario.h"
#include "calib/common/clock.h"
#include "calib/common/errors.h"
#include "sim/cell/twin_cell.h"
#include "sim/render/gl_context.h"

namespace twin {
namespace {

namespace fs = std::filesystem;

// Small wrist moves of the board robot around its initial pose, for a few distinct views.
JointVector ViewPose(const JointVector& q0, int k) {
  static const double kDeltaDeg[][3] = {{0, 0, 0}, {6, -6, 0}, {-6, 5, 20}, {4, 8, -20}};
  JointVector q = q0;
  const auto& d = kDeltaDeg[k % 4];
  for (int i = 0; i < 3; ++i) q(3 + i) += DegToRad(d[i]) * (1 + k / 4);
  return q;
}

void WritePng(const fs::path& path, const cv::Mat& image) {
  if (!cv::imwrite(path.string(), image)) throw InputError(path.string(), "cannot write PNG");
}

}  // namespace

int RunRender(const RenderOptions& o) {
  if (o.poses < 1) throw InputError("--poses", "must be >= 1, got " + std::to_string(o.poses));
  const Scenario scenario = LoadScenario(o.scenario);
  TwinCell cell(scenario.twin, o.scenario);
  // The robot that moves between views: the board robot, whose board the hand camera sees; in
  // a one-robot cell (no camera) the robot itself, seen in the overviews only.
  const bool camera = scenario.twin.HasCameraAndBoard();
  const int robot = camera ? scenario.twin.board.robot : 0;
  const JointVector q0 = scenario.twin.robots[robot].q_initial;

  // Everything goes to a staging folder first, so a failure leaves no half-written output.
  ValidateOutputFolder(o.out_dir, "--out");
  const fs::path out(o.out_dir);
  const fs::path staging = CreateStagingDirectory(o.out_dir);
  int written = 0;
  try {
    for (int k = 0; k < o.poses; ++k) {
      const MoveResult m = cell.MoveTo(robot, ViewPose(q0, k));
      if (m.status != MoveStatus::kSettled) {
        std::printf("pose %d skipped: %s: %s\n", k, ToString(m.status), m.reason.c_str());
        continue;
      }
      char name[64];
      if (camera) {
        std::snprintf(name, sizeof(name), "hand_camera_%02d.png", k);
        WritePng(staging / name, cell.GrabImage());
      }
      std::snprintf(name, sizeof(name), "overview_%02d.png", k);
      WritePng(staging / name, cell.RenderOverview(o.overview_width, o.overview_height, 135, -25));
      if (camera) {
        std::printf("pose %d: wrote hand_camera_%02d.png and overview_%02d.png\n", k, k, k);
      } else {
        std::printf("pose %d: wrote overview_%02d.png (a one-robot cell has no hand camera)\n",
                    k, k);
      }
      ++written;
    }
    if (written == 0) {
      throw InputError(o.scenario, std::string("no pose of the ") +
                                       (camera ? "board robot" : "robot") +
                                       " could be reached; nothing written");
    }
    PublishDirectory(staging.string(), out.string());
  } catch (...) {
    DiscardStaging(staging.string());
    throw;
  }
  std::printf("%d pose(s) rendered into %s with %s\n", written, o.out_dir.c_str(),
              GlBackendDescription().c_str());
  return 0;
}

namespace {

// A benchmark worker process: its own twin, a warm-up frame (shader compilation), a byte on
// `ready_fd`, then `frames` frames once a byte arrives on `go_fd`. Never returns: exit 0 done,
// 2 refused input, 1 internal error, 3 the parent went away.
[[noreturn]] void RunWorker(const TwinSpec& spec, int frames, int ready_fd, int go_fd) {
  // The parent blocks interrupts for its clean-up thread (bench/io/output_files.h); a worker
  // has no such thread and ends on them.
  sigset_t none;
  sigemptyset(&none);
  pthread_sigmask(SIG_SETMASK, &none, nullptr);
  // A worker's error ends the worker, not a copy of the parent's command.
  try {
    TwinCell cell(spec);
    cell.GrabImage();
    char c = 1;
    const bool told = write(ready_fd, &c, 1) == 1;
    // Ready: this worker's write end closes, so the parent's read() sees the end of the pipe
    // once every worker has either written or died.
    close(ready_fd);
    if (!told || read(go_fd, &c, 1) != 1) _exit(3);
    for (int f = 0; f < frames; ++f) cell.GrabImage();
  } catch (const InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    _exit(2);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "internal error: benchmark-twin worker: %s\n", e.what());
    _exit(1);
  }
  _exit(0);
}

// The parent's side of the workers: the ready and go pipes and the children. Ending it (End,
// or the destructor) closes the go pipe, so a worker still waiting for its byte ends, reaps
// every child and closes the pipes.
struct Workers {
  int ready[2] = {-1, -1}, go[2] = {-1, -1};
  std::vector<pid_t> children;

  Workers() {
    if (pipe(ready) != 0 || pipe(go) != 0) {
      End(false);
      throw std::runtime_error("pipe failed");
    }
  }
  ~Workers() { End(true); }

  // Returns true when a child ended with exit 2 (refused the input); `kill_them`: SIGTERM first.
  bool End(bool kill_them) {
    bool refused = false;
    CloseFd(&go[1]);
    for (pid_t pid : children) {
      if (kill_them) kill(pid, SIGTERM);
      int status = 0;
      waitpid(pid, &status, 0);
      refused = refused || (WIFEXITED(status) && WEXITSTATUS(status) == 2);
    }
    children.clear();
    for (int* fd : {&ready[0], &ready[1], &go[0]}) CloseFd(fd);
    return refused;
  }
  static void CloseFd(int* fd) {
    if (*fd >= 0) close(*fd);
    *fd = -1;
  }
};

// Frames per second of `workers` processes, each with its own twin, grabbing `frames` frames
// after a warm-up frame. Workers report ready on one pipe and start on a go byte from the
// other, so the clock covers exactly the rendering of all of them.
double WorkerFps(const TwinSpec& spec, int workers, int frames) {
  Workers w;
  for (int k = 0; k < workers; ++k) {
    const pid_t pid = fork();
    if (pid < 0) throw std::runtime_error("fork failed");  // ~Workers ends the others
    if (pid == 0) {
      close(w.ready[0]);
      close(w.go[1]);
      RunWorker(spec, frames, w.ready[1], w.go[0]);
    }
    w.children.push_back(pid);
  }
  // Only the workers hold the ready pipe's write end now (and no one but them reads go).
  Workers::CloseFd(&w.ready[1]);
  Workers::CloseFd(&w.go[0]);
  char c = 1;
  for (int k = 0; k < workers; ++k) {
    if (read(w.ready[0], &c, 1) != 1) {
      if (w.End(false)) {
        throw InputError("benchmark-twin", "a worker process refused the input (its error is "
                                           "above)");
      }
      throw std::runtime_error("a worker process failed to start");
    }
  }
  const auto t0 = Clock::now();
  for (int k = 0; k < workers; ++k) {
    if (write(w.go[1], &c, 1) != 1) throw std::runtime_error("cannot start the workers");
  }
  bool ok = true;
  for (pid_t pid : w.children) {
    int status = 0;
    waitpid(pid, &status, 0);
    ok = ok && WIFEXITED(status) && WEXITSTATUS(status) == 0;
  }
  const double seconds = SecondsSince(t0);
  w.children.clear();
  if (!ok) throw std::runtime_error("a worker process failed");
  return workers * frames / seconds;
}

}  // namespace

int RunTwinBenchmark(const TwinBenchmarkOptions& o) {
  if (o.frames < 1 || o.moves < 2) throw InputError("benchmark-twin", "need frames >= 1, moves >= 2");
  const Scenario scenario = LoadScenario(o.scenario);
  if (!scenario.twin.HasCameraAndBoard()) {
    throw InputError(o.scenario + " scenario.robots",
                     "benchmark-twin times the hand camera's frames; this cell has one robot "
                     "and no camera (a two-robot scenario has one)");
  }
  // Worker processes first: they must be forked before this process starts its own GL
  // context (llvmpipe's threads do not survive a fork).
  const double fps1 = WorkerFps(scenario.twin, 1, o.frames);
  const double fps2 = WorkerFps(scenario.twin, 2, o.frames);

  TwinCell cell(scenario.twin, o.scenario);
  const cv::Mat first = cell.GrabImage();  // shader compilation: not timed
  cell.RenderBare();

  auto t0 = Clock::now();
  for (int f = 0; f < o.frames; ++f) cell.GrabImage();
  const double grab_ms = 1e3 * SecondsSince(t0) / o.frames;
  t0 = Clock::now();
  for (int f = 0; f < o.frames; ++f) cell.RenderBare();
  const double bare_ms = 1e3 * SecondsSince(t0) / o.frames;
  // A centred region of a fifth of the frame's pixels, about what the servo renders once the
  // board's image position is predicted.
  const cv::Rect roi(first.cols * 0.28, first.rows * 0.28, first.cols * 0.44, first.rows * 0.44);
  cell.GrabImageRegion(roi);
  t0 = Clock::now();
  for (int f = 0; f < o.frames; ++f) cell.GrabImageRegion(roi);
  const double region_ms = 1e3 * SecondsSince(t0) / o.frames;
  // Centred squares of growing side: a line through their times splits a region frame into a
  // fixed cost per frame and a cost per pixel.
  std::vector<std::pair<int, double>> sides;
  for (int side : {32, 128, 256}) {
    if (side > first.rows) break;
    const cv::Rect square((first.cols - side) / 2, (first.rows - side) / 2, side, side);
    cell.GrabImageRegion(square);
    t0 = Clock::now();
    for (int f = 0; f < o.frames; ++f) cell.GrabImageRegion(square);
    sides.emplace_back(side, 1e3 * SecondsSince(t0) / o.frames);
  }

  const int robot = scenario.twin.board.robot;
  const JointVector q0 = scenario.twin.robots[robot].q_initial;
  long steps = 0;
  double sim_s = 0.0;
  int settled = 0;
  t0 = Clock::now();
  for (int k = 0; k < o.moves; ++k) {
    const MoveResult m = cell.MoveTo(robot, ViewPose(q0, k % 2 ? 1 : 0));
    steps += cell.last_move_steps();
    sim_s += m.duration_s;
    settled += m.status == MoveStatus::kSettled;
  }
  const double move_ms = 1e3 * SecondsSince(t0) / o.moves;

  std::printf("twin benchmark: %s, %dx%d image, %d frames per figure\n", o.scenario.c_str(),
              first.cols, first.rows, o.frames);
  std::printf("  GL back end: %s\n", GlBackendDescription().c_str());
  std::printf("  GrabImage (render + read-back + flip + effects): %7.2f ms/frame\n", grab_ms);
  std::printf("  bare mjr_render + mjr_readPixels:                %7.2f ms/frame\n", bare_ms);
  std::printf("  GrabImageRegion, %dx%d centred region:          %7.2f ms/frame\n", roi.width,
              roi.height, region_ms);
  for (const auto& [side, ms] : sides) {
    std::printf("  GrabImageRegion, %dx%d centred square:%*s%7.2f ms/frame\n", side, side,
                side >= 100 ? 10 : 12, "", ms);
  }
  std::printf("  settled move (6-deg wrist moves, %d/%d settled):  %7.2f ms/move, %.0f steps, "
              "%.3f s simulated\n", settled, o.moves, move_ms,
              static_cast<double>(steps) / o.moves, sim_s / o.moves);
  std::printf("  one worker process:                              %7.1f frames/s\n", fps1);
  std::printf("  two worker processes:                            %7.1f frames/s in total\n",
              fps2);
  return 0;
}

}  // namespace twin
