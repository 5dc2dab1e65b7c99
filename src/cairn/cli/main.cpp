// The `cairn` command: one binary, one subcommand per job. Library code never prints; this file
// and the commands are where results and errors meet the terminal.

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>
#include <map>
#include <string>

#include "cairn/cli/commands.hpp"
#include "cairn/cli/interrupt.hpp"
#include "cairn/io/parse_error.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "cairn: SLAM that tells you how good its answer is.\n"
      "Pose graphs (g2o, TORO) and trajectories (TUM, KITTI, EuRoC) in, maps and reports out."};
  app.set_version_flag("--version", "cairn 0.1.0");
  app.require_subcommand(1);
  app.fallthrough(false);

  std::map<CLI::App*, cairn::cli::Runner> runners;
  auto add = [&](cairn::cli::Runner (*registrar)(CLI::App&), const char* name, const char* help) {
    CLI::App* command = app.add_subcommand(name, help);
    runners[command] = registrar(*command);
  };
  add(cairn::cli::register_info, "info", "Describe a pose graph or trajectory file");
  add(cairn::cli::register_convert, "convert", "Convert between graph formats or between trajectory formats");
  add(cairn::cli::register_corrupt, "corrupt", "Add random false loop closures to a pose graph (robustness experiments)");
  add(cairn::cli::register_optimize, "optimize", "Optimise a pose graph (LM / GN / dog-leg, chordal initialisation)");
  add(cairn::cli::register_slam2d, "slam2d", "2D LiDAR SLAM on a CARMEN log: map, trajectory, pose graph, report");
  add(cairn::cli::register_localize2d, "localize2d", "Localise a CARMEN log in a map saved by slam2d --save-map: pose, health and confidence per scan, relocalisation, report");
  add(cairn::cli::register_slam3d, "slam3d", "3D LiDAR SLAM on a folder of scans (KISS-ICP-style odometry, Scan Context loops verified by ICP, GNC): trajectory, map, picture, report");
  add(cairn::cli::register_vslam, "vslam", "Stereo (KITTI layout) or RGB-D (TUM layout) visual SLAM on an image folder: trajectory, keyframes, map points, pictures, report");
  add(cairn::cli::register_vocabulary, "vocabulary", "Train (hierarchical k-means++ on ORB descriptors) or describe a bag-of-words vocabulary for cairn vslam's place recognition");
  add(cairn::cli::register_eval, "eval", "Evaluate a trajectory: APE, RPE, KITTI t_err/r_err, relations metric; tables, JSON, plots");
  add(cairn::cli::register_landmarks, "landmarks", "Landmark SLAM (EKF or graph; known, NN or JCBB association) on a simulated landmark run");
  add(cairn::cli::register_ba, "ba", "Bundle adjustment of a BAL problem (points eliminated by Schur complement)");
  add(cairn::cli::register_simulate, "simulate", "Simulate a world, a trajectory and sensor logs (CARMEN, TUM, g2o, relations, PNG)");

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

  // The commands with safe points stop at the first SIGINT/SIGTERM; the others end at once.
  for (const auto& [command, run] : runners) {
    const std::string name = command->get_name();
    if (command->parsed() && (name == "slam2d" || name == "localize2d" || name == "optimize" || name == "landmarks" || name == "ba")) {
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
