// The `cairn` command: one subcommand per job. Library code never prints; this file and the
// commands are where results and errors meet the terminal.
//
// Two binaries are built from this file. `cairn-suite` holds every command. `cairn` (compiled
// with CAIRN_CLI_FRONT) holds the commands whose libraries load fast -- info, convert, corrupt,
// optimize, ba: the back end, CHOLMOD, TBB -- and hands every other command to the cairn-suite
// beside it by exec (the same process, its arguments unchanged), as git runs git-<command>.
// Loading cairo (X11, fontconfig, freetype) and OpenCV costs every process 5-8 ms of dynamic
// linking, more than a whole solve of a small pose graph (docs/benchmarks.md, "Certified global
// optimality"); a command that does not draw or see should not pay it.

#include <malloc.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "cairn/cli/commands.hpp"
#include "cairn/cli/interrupt.hpp"
#include "cairn/io/parse_error.hpp"

namespace {

#ifdef CAIRN_CLI_FRONT
// The commands cairn-suite runs (their registrars are not linked into the front).
#define CAIRN_SUITE(registrar) nullptr
#else
#define CAIRN_SUITE(registrar) registrar
#endif

// Replaces this process by cairn-suite, beside this binary, with the same arguments. Returns
// only on failure, with the exit status.
[[maybe_unused]] int run_in_suite(char** argv) {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  const std::filesystem::path suite = (ec ? std::filesystem::path(argv[0]) : self).parent_path() / "cairn-suite";
  std::cout.flush();
  std::fflush(stdout);
  ::execv(suite.c_str(), argv);
  const int error = errno;
  std::cerr << "cairn: error: this command runs in " << suite.string() << ", which cannot be started: "
            << std::strerror(error) << " (it is built beside cairn: keep the two together)\n";
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  // Large buffers (a scan's 120,000 points are 3 MB) come from the heap and stay there: with
  // glibc's defaults each one is a fresh mmap whose pages fault in again on every scan, which on
  // this project's 2-core VM cost localize3d 6 of its 9 ms of preparation per scan (docs/lidar3d.md,
  // "Tracking time"). Fixed thresholds also stop glibc from raising them on its own.
  mallopt(M_MMAP_THRESHOLD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
  CLI::App app{
      "cairn: SLAM that tells you how good its answer is.\n"
      "Pose graphs (g2o, TORO) and trajectories (TUM, KITTI, EuRoC) in, maps and reports out."};
  app.set_version_flag("--version", "cairn " CAIRN_VERSION);
  app.require_subcommand(1);
  app.fallthrough(false);

  app.name("cairn");
  std::map<CLI::App*, cairn::cli::Runner> runners;
  std::vector<CLI::App*> handed_over;  // the commands cairn-suite runs
  auto add = [&](cairn::cli::Runner (*registrar)(CLI::App&), const char* name, const char* help) {
    CLI::App* command = app.add_subcommand(name, help);
    if (registrar != nullptr) {
      runners[command] = registrar(*command);
      return;
    }
    // Run by cairn-suite: every argument after the command name is passed on untouched, --help
    // included.
    command->set_help_flag();
    command->prefix_command();
    handed_over.push_back(command);
    runners[command] = [argv] { return run_in_suite(argv); };
  };
  add(cairn::cli::register_info, "info", "Describe a pose graph or trajectory file");
  add(cairn::cli::register_convert, "convert", "Convert between graph formats or between trajectory formats");
  add(cairn::cli::register_corrupt, "corrupt", "Add random false loop closures to a pose graph (robustness experiments)");
  add(cairn::cli::register_optimize, "optimize", "Optimise a pose graph (LM / GN / dog-leg, chordal initialisation)");
  add(CAIRN_SUITE(cairn::cli::register_slam2d), "slam2d", "2D LiDAR SLAM on a CARMEN log: map, trajectory, pose graph, report");
  add(CAIRN_SUITE(cairn::cli::register_localize2d), "localize2d", "Localise a CARMEN log in a map saved by slam2d --save-map: pose, health and confidence per scan, relocalisation, report");
  add(CAIRN_SUITE(cairn::cli::register_localize3d), "localize3d", "Localise 3D LiDAR scans in a map saved by slam3d --save-map: pose, health and fit per scan, relocalisation, report");
  add(CAIRN_SUITE(cairn::cli::register_slam3d), "slam3d", "3D LiDAR SLAM on a folder of scans (KISS-ICP-style odometry, Scan Context loops verified by ICP, GNC): trajectory, map, picture, report");
  add(CAIRN_SUITE(cairn::cli::register_vslam), "vslam", "Stereo (KITTI layout) or RGB-D (TUM layout) visual SLAM on an image folder: trajectory, keyframes, map points, pictures, report");
  add(CAIRN_SUITE(cairn::cli::register_vocabulary), "vocabulary", "Train (hierarchical k-means++ on ORB descriptors) or describe a bag-of-words vocabulary for cairn vslam's place recognition");
  add(CAIRN_SUITE(cairn::cli::register_eval), "eval", "Evaluate a trajectory: APE, RPE, KITTI t_err/r_err, relations metric; tables, JSON, plots");
  add(CAIRN_SUITE(cairn::cli::register_landmarks), "landmarks", "Landmark SLAM (EKF or graph; known, NN or JCBB association) on a simulated landmark run");
  add(cairn::cli::register_ba, "ba", "Bundle adjustment of a BAL problem (points eliminated by Schur complement)");
  add(CAIRN_SUITE(cairn::cli::register_register), "register", "Register one point cloud onto another (GICP or point-to-plane ICP, from a guess or --global): T_target_source, fitness, degeneracy, covariance");
  add(CAIRN_SUITE(cairn::cli::register_imu), "imu", "Examine an IMU recording: rates, gaps, saturation, static initialisation, Allan deviation, preintegration against ground truth");
  add(CAIRN_SUITE(cairn::cli::register_navigate), "navigate", "A ground vehicle's trajectory from a bag's IMU, wheel odometry and GNSS (fixed-lag smoother); --withhold-gnss measures dead reckoning");
  add(CAIRN_SUITE(cairn::cli::register_simulate), "simulate", "Simulate a world, a trajectory and sensor logs (CARMEN, TUM, g2o, relations, PNG)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  }

  // A command of cairn-suite: hand over before anything else happens in this process.
  for (CLI::App* command : handed_over) {
    if (command->parsed()) return runners[command]();
  }
  // The commands with safe points stop at the first SIGINT/SIGTERM; the others end at once.
  for (const auto& [command, run] : runners) {
    const std::string name = command->get_name();
    if (command->parsed() && (name == "slam2d" || name == "localize2d" || name == "localize3d" || name == "slam3d" || name == "vslam" || name == "optimize" ||
                               name == "landmarks" || name == "ba")) {
      cairn::cli::use_stop_points();
    }
  }
  cairn::cli::install_signal_handlers();
  int status = 1;
  try {
    for (const auto& [command, run] : runners) {
      if (command->parsed()) {
        status = run();
        break;
      }
    }
  } catch (const cairn::cli::UsageError& e) {
    std::cerr << "cairn: error: " << e.what() << '\n';
    status = 2;
  } catch (const cairn::io::ParseError& e) {
    std::cerr << "cairn: error: " << e.what() << '\n';
    status = 1;
  } catch (const std::exception& e) {
    std::cerr << "cairn: error: " << e.what() << '\n';
    status = 1;
  }
  // What went to standard output through stdio or iostreams is checked too (a full disk or a
  // closed pipe behind `> file` or `| head`).
  std::cout.flush();
  errno = 0;
  if (std::fflush(stdout) != 0 || std::ferror(stdout) || !std::cout) {
    const int error = errno;
    std::cerr << "cairn: error: cannot write standard output" << (error != 0 ? std::string(": ") + std::strerror(error) : "")
              << '\n';
    if (status == 0) status = 1;
  }
  return status;
}
