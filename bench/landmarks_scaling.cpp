// Landmark SLAM scaling: time per step of EKF-SLAM and of one graph-SLAM Levenberg-Marquardt
// iteration against the number of landmarks (100 ... 5,000). Not a Google Benchmark program:
// each size needs minutes of set-up and one measurement is enough to show the growth.
//
//   cmake -S . -B build-bench -DCAIRN_BUILD_BENCH=ON && cmake --build build-bench --target bench_landmarks_scaling
//   ./build-bench/bench/bench_landmarks_scaling [max_landmarks] [plot.png]   # CSV on stdout
//
// EKF: a filter restored with n landmarks (dense covariance), then steps of one prediction and
// 10 range-bearing updates (about what the simulator's landmark world gives per step); the cost
// is O(n^2) per update (Joseph form over the dense P).
// Graph: a circular route whose length grows with n (0.4 m of route per landmark, landmarks within
// 6 m of it, a pose every 0.5 m, observations within 8 m), so the landmark density and the
// observations per pose stay constant; the time of one LM iteration (linearise, factorise, solve)
// of the batch problem. A back end that re-solves at every step pays about this per step.

#include <cairo.h>

#include <algorithm>
#include <chrono>
#include <string>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <random>
#include <vector>

#include "cairn/backend/landmark_graph.hpp"
#include "cairn/core/so2.hpp"
#include "cairn/filter/ekf_slam.hpp"

namespace {

using Clock = std::chrono::steady_clock;
using cairn::Matrix2;
using cairn::Matrix3;
using cairn::Vector2;
using cairn::Vector3;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

double ekf_seconds_per_step(int n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> uniform(-8.0, 8.0);
  const Eigen::Index size = 3 + 2 * n;
  Eigen::VectorXd x(size);
  x.head<3>().setZero();
  for (Eigen::Index k = 3; k < size; ++k) x(k) = uniform(rng);
  // A valid (diagonally dominant) covariance with every entry non-zero: the cost does not
  // depend on the values, only on the size.
  Eigen::MatrixXd P = Eigen::MatrixXd::Constant(size, size, 1e-6);
  P.diagonal().setConstant(1e-2);
  cairn::filter::EkfSlam ekf = cairn::filter::EkfSlam::from_state(x, P);
  const int steps = n >= 2000 ? 2 : n >= 500 ? 5 : 20;
  const auto start = Clock::now();
  for (int s = 0; s < steps; ++s) {
    ekf.predict(Vector3(0.1, 0.0, 0.01), Matrix3(Vector3(1e-4, 1e-5, 1e-5).asDiagonal()));
    for (int k = 0; k < 10; ++k) {
      const std::size_t landmark = static_cast<std::size_t>((s * 10 + k) % n);
      const Vector2 z = cairn::filter::range_bearing(ekf.pose(), ekf.landmark(landmark));
      ekf.update(landmark, Vector2(z.x() + 0.01, z.y() + 0.001));
    }
  }
  return seconds_since(start) / steps;
}

struct GraphTiming {
  double seconds_per_iteration = 0.0;
  std::size_t poses = 0;
  std::size_t observations = 0;
};

GraphTiming graph_seconds_per_iteration(int n, std::mt19937_64& rng) {
  const double circumference = 0.4 * n;
  const double radius = circumference / (2 * std::numbers::pi);
  std::uniform_real_distribution<double> angle(0.0, 2 * std::numbers::pi);
  std::uniform_real_distribution<double> offset(-6.0, 6.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  cairn::backend::LandmarkGraph2D graph;
  std::vector<Vector2> truth_landmarks;
  for (int l = 0; l < n; ++l) {
    const double a = angle(rng);
    const double r = radius + offset(rng);
    truth_landmarks.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  const int pose_count = static_cast<int>(circumference / 0.5);
  std::vector<Vector3> truth_poses;
  for (int k = 0; k < pose_count; ++k) {
    const double a = 2 * std::numbers::pi * k / pose_count;
    truth_poses.emplace_back(radius * std::cos(a), radius * std::sin(a), cairn::core::wrap_angle(a + std::numbers::pi / 2));
  }
  graph.poses = truth_poses;
  for (std::size_t k = 1; k < graph.poses.size(); ++k) graph.poses[k] += Vector3(0.05 * noise(rng), 0.05 * noise(rng), 0.01 * noise(rng));
  // Landmarks grouped by angle so the visibility search is local.
  std::vector<std::vector<int>> buckets(static_cast<std::size_t>(pose_count));
  for (int l = 0; l < n; ++l) {
    double a = std::atan2(truth_landmarks[static_cast<std::size_t>(l)].y(), truth_landmarks[static_cast<std::size_t>(l)].x());
    if (a < 0) a += 2 * std::numbers::pi;
    buckets[static_cast<std::size_t>(a / (2 * std::numbers::pi) * pose_count) % buckets.size()].push_back(l);
  }
  std::vector<int> variable(static_cast<std::size_t>(n), -1);
  const Matrix2 information = Vector2(1.0 / (0.05 * 0.05), 1.0 / (0.01 * 0.01)).asDiagonal();
  for (int k = 0; k < pose_count; ++k) {
    if (k > 0) {
      cairn::backend::OdometryFactor2D f;
      f.from = static_cast<std::size_t>(k - 1);
      f.to = static_cast<std::size_t>(k);
      const Vector3& a = truth_poses[f.from];
      const Vector3& b = truth_poses[f.to];
      const double c = std::cos(a.z());
      const double s = std::sin(a.z());
      const Vector2 d = b.head<2>() - a.head<2>();
      f.u = Vector3(c * d.x() + s * d.y(), -s * d.x() + c * d.y(), cairn::core::wrap_angle(b.z() - a.z()));
      f.information = Vector3(1e4, 4e4, 1e5).asDiagonal();
      graph.odometry.push_back(f);
    }
    for (int b = -20; b <= 20; ++b) {
      for (const int l : buckets[static_cast<std::size_t>((k + b + pose_count) % pose_count)]) {
        const Vector2 d = truth_landmarks[static_cast<std::size_t>(l)] - truth_poses[static_cast<std::size_t>(k)].head<2>();
        if (d.norm() > 8.0 || d.norm() < 0.3) continue;
        if (variable[static_cast<std::size_t>(l)] < 0) {
          variable[static_cast<std::size_t>(l)] = static_cast<int>(graph.landmarks.size());
          graph.landmarks.push_back(truth_landmarks[static_cast<std::size_t>(l)] + Vector2(0.1 * noise(rng), 0.1 * noise(rng)));
        }
        cairn::backend::RangeBearingFactor2D f;
        f.pose = static_cast<std::size_t>(k);
        f.landmark = static_cast<std::size_t>(variable[static_cast<std::size_t>(l)]);
        f.z = Vector2(d.norm() + 0.05 * noise(rng),
                      cairn::core::wrap_angle(std::atan2(d.y(), d.x()) - truth_poses[static_cast<std::size_t>(k)].z() + 0.01 * noise(rng)));
        f.information = information;
        graph.observations.push_back(f);
      }
    }
  }
  cairn::backend::LandmarkGraphOptions options;
  options.max_iterations = 3;
  const auto start = Clock::now();
  const cairn::backend::LandmarkGraphSummary summary = cairn::backend::optimize(graph, options);
  GraphTiming timing;
  timing.seconds_per_iteration = seconds_since(start) / std::max(1, summary.iterations);
  timing.poses = graph.poses.size();
  timing.observations = graph.observations.size();
  return timing;
}

struct Row {
  int landmarks = 0;
  double ekf_s = 0.0;
  double graph_s = 0.0;
};

// Log-log plot of both timings (cairo, PNG).
void plot(const std::vector<Row>& rows, const std::string& path) {
  const int width = 720;
  const int height = 480;
  const double left = 80;
  const double right = 30;
  const double top = 40;
  const double bottom = 60;
  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height);
  cairo_t* cr = cairo_create(surface);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  const double x0 = std::log10(100.0);
  const double x1 = std::log10(5000.0);
  const double y0 = -4.0;  // 0.1 ms
  const double y1 = 1.0;   // 10 s
  const auto px = [&](double n) { return left + (std::log10(n) - x0) / (x1 - x0) * (width - left - right); };
  const auto py = [&](double s) { return height - bottom - (std::log10(s) - y0) / (y1 - y0) * (height - top - bottom); };
  cairo_set_font_size(cr, 12);
  cairo_set_line_width(cr, 1.0);
  for (int e = -4; e <= 1; ++e) {  // horizontal grid, one line per decade
    cairo_set_source_rgb(cr, 0.85, 0.85, 0.85);
    cairo_move_to(cr, left, py(std::pow(10.0, e)));
    cairo_line_to(cr, width - right, py(std::pow(10.0, e)));
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_move_to(cr, 10, py(std::pow(10.0, e)) + 4);
    const std::string label = "1e" + std::to_string(e) + " s";
    cairo_show_text(cr, label.c_str());
  }
  for (const int n : {100, 200, 500, 1000, 2000, 5000}) {
    cairo_set_source_rgb(cr, 0.85, 0.85, 0.85);
    cairo_move_to(cr, px(n), top);
    cairo_line_to(cr, px(n), height - bottom);
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_move_to(cr, px(n) - 12, height - bottom + 18);
    cairo_show_text(cr, std::to_string(n).c_str());
  }
  cairo_move_to(cr, width / 2.0 - 60, height - 15);
  cairo_show_text(cr, "number of landmarks");
  const auto series = [&](double r, double g, double b, auto value, const char* name, double legend_y) {
    cairo_set_source_rgb(cr, r, g, b);
    cairo_set_line_width(cr, 2.0);
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const double x = px(rows[k].landmarks);
      const double y = py(value(rows[k]));
      if (k == 0) {
        cairo_move_to(cr, x, y);
      } else {
        cairo_line_to(cr, x, y);
      }
    }
    cairo_stroke(cr);
    for (const Row& row : rows) {
      cairo_arc(cr, px(row.landmarks), py(value(row)), 3.5, 0, 2 * std::numbers::pi);
      cairo_fill(cr);
    }
    cairo_move_to(cr, left + 10, legend_y);
    cairo_show_text(cr, name);
  };
  series(0.85, 0.1, 0.1, [](const Row& row) { return row.ekf_s; }, "EKF-SLAM: seconds per step (1 prediction + 10 updates)", top + 15);
  series(0.1, 0.3, 0.85, [](const Row& row) { return row.graph_s; }, "graph SLAM: seconds per LM iteration (whole batch)", top + 32);
  cairo_surface_write_to_png(surface, path.c_str());
  cairo_destroy(cr);
  cairo_surface_destroy(surface);
}

}  // namespace

int main(int argc, char** argv) {
  const int max_landmarks = argc > 1 ? std::atoi(argv[1]) : 5000;
  std::mt19937_64 rng(1);
  std::printf("landmarks,ekf_seconds_per_step,graph_seconds_per_lm_iteration,graph_poses,graph_observations\n");
  std::vector<Row> rows;
  for (const int n : {100, 200, 500, 1000, 2000, 5000}) {
    if (n > max_landmarks) break;
    const double ekf = ekf_seconds_per_step(n, rng);
    const GraphTiming graph = graph_seconds_per_iteration(n, rng);
    std::printf("%d,%.6g,%.6g,%zu,%zu\n", n, ekf, graph.seconds_per_iteration, graph.poses, graph.observations);
    std::fflush(stdout);
    rows.push_back({n, ekf, graph.seconds_per_iteration});
  }
  if (argc > 2) plot(rows, argv[2]);
  return 0;
}
