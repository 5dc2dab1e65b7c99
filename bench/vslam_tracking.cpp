// Visual SLAM time per frame on the real sequences: ORB, stereo matching / depth lookup, tracking
// and mapping per frame, medians and 90th percentiles over 3 repetitions, images
// decoded before the clock starts; each sequence with local mapping in its own thread (the
// default) and within the keyframe's frame (local_mapping_thread off), interleaved. Usage:
//   bench_vslam_tracking [DATA_ROOT]   (default $CAIRN_DATA_ROOT or ../shared/data)
// The TUM run uses a vocabulary trained on the KITTI images (never on TUM's). With the thread, a
// keyframe's mapping is counted in the next frame's "mapping" (its join); "wall" is the run's
// wall clock per frame, which also covers what the thread did between frames.

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "cairn/core/timer.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/vision/features.hpp"
#include "cairn/vision/vocabulary.hpp"
#include "cairn/vslam/visual_slam.hpp"

namespace {

using namespace cairn;

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5)];
}

struct Stage {
  std::vector<double> orb, stereo, tracking, mapping, total;
};

void print(const char* name, const char* mode, const Stage& s, std::size_t frames, double wall_ms) {
  std::printf("| %s | %s | %zu | %.1f / %.1f | %.1f / %.1f | %.1f / %.1f | %.1f / %.1f | %.1f / %.1f | %.1f |\n", name, mode, frames,
              1e3 * quantile(s.orb, 0.5), 1e3 * quantile(s.orb, 0.9), 1e3 * quantile(s.stereo, 0.5), 1e3 * quantile(s.stereo, 0.9),
              1e3 * quantile(s.tracking, 0.5), 1e3 * quantile(s.tracking, 0.9), 1e3 * quantile(s.mapping, 0.5),
              1e3 * quantile(s.mapping, 0.9), 1e3 * quantile(s.total, 0.5), 1e3 * quantile(s.total, 0.9), wall_ms);
}

void add(Stage& s, const vslam::FrameResult& r) {
  s.orb.push_back(r.times.features_s);
  s.stereo.push_back(r.times.stereo_s);
  s.tracking.push_back(r.times.tracking_s);
  s.mapping.push_back(r.times.mapping_s);
  s.total.push_back(r.times.total_s);
}

}  // namespace

int main(int argc, char** argv) {
  const char* env = std::getenv("CAIRN_DATA_ROOT");
  const std::filesystem::path root = argc > 1 ? argv[1] : (env ? env : "../shared/data");
  const io::ImageSequence kitti = io::read_kitti_stereo((root / "visual/kitti_extract_seq2").string());
  std::vector<std::pair<cv::Mat, cv::Mat>> pairs;
  for (const auto& f : kitti.frames) pairs.emplace_back(vision::read_gray_image(f.image), vision::read_gray_image(f.right_image));
  const io::ImageSequence tum = io::read_tum_rgbd((root / "visual/tum_fr1_desk_every4th").string());
  std::vector<std::pair<cv::Mat, cv::Mat>> rgbd;
  for (const auto& f : tum.frames) rgbd.emplace_back(vision::read_gray_image(f.image), vision::read_depth_image(f.depth_image));
  std::vector<cv::Mat> training;
  const vision::OrbExtractor orb(vision::OrbOptions{1000});
  for (const auto& p : pairs) training.push_back(orb.extract(p.first).descriptors);
  vision::VocabularyOptions vo;
  vo.depth = 4;
  const auto vocabulary = std::make_shared<const vision::Vocabulary>(vision::Vocabulary::train(training, vo));

  std::printf("| sequence | local mapping | frames | ORB ms (median / p90) | stereo or depth | tracking | mapping | total | wall per frame (mean) |\n"
              "|---|---|---|---|---|---|---|---|---|\n");
  io::CameraCalibration camera{517.306408, 516.469215, 318.643040, 255.313989, 0.262383, -0.953104, -0.005358, 0.002628, 1.163314};
  camera.depth_units_per_m = 5000.0;
  camera.virtual_baseline_m = 40.0 / camera.fx;
  Stage stages[2][2];
  double wall_s[2][2] = {{0.0, 0.0}, {0.0, 0.0}};
  for (int repetition = 0; repetition < 3; ++repetition) {
    for (int threaded = 1; threaded >= 0; --threaded) {
      vslam::VisualSlamOptions kitti_options;
      kitti_options.local_mapping_thread = threaded == 1;
      const auto kitti_start = core::Clock::now();
      {
        vslam::VisualSlam slam(kitti.calibration, kitti.kind, kitti_options);
        for (std::size_t k = 0; k < pairs.size(); ++k) add(stages[0][threaded], slam.add_stereo(kitti.frames[k].time, pairs[k].first, pairs[k].second));
        slam.summary();  // the last keyframe's mapping
      }
      wall_s[0][threaded] += core::seconds_since(kitti_start);
      vslam::VisualSlamOptions options;
      options.orb.features = 1000;
      options.close_depth_baselines = 40.0;
      options.vocabulary = vocabulary;
      options.local_mapping_thread = threaded == 1;
      const auto tum_start = core::Clock::now();
      {
        vslam::VisualSlam slam(camera, io::SequenceKind::kRgbd, options);
        for (std::size_t k = 0; k < rgbd.size(); ++k) add(stages[1][threaded], slam.add_rgbd(tum.frames[k].time, rgbd[k].first, rgbd[k].second));
        slam.summary();
      }
      wall_s[1][threaded] += core::seconds_since(tum_start);
    }
  }
  for (int threaded = 1; threaded >= 0; --threaded) {
    const char* mode = threaded ? "own thread" : "in the frame";
    print("KITTI extract, stereo, 2000 ORB", mode, stages[0][threaded], pairs.size(), 1e3 * wall_s[0][threaded] / (3.0 * static_cast<double>(pairs.size())));
  }
  for (int threaded = 1; threaded >= 0; --threaded) {
    const char* mode = threaded ? "own thread" : "in the frame";
    print("TUM fr1/desk every 4th, RGB-D, 1000 ORB, vocabulary", mode, stages[1][threaded], rgbd.size(),
          1e3 * wall_s[1][threaded] / (3.0 * static_cast<double>(rgbd.size())));
  }
  return 0;
}
