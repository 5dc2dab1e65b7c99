// VisualSlam in Python (bindings.hpp): fed one frame at a time, as `cairn vslam` feeds it, and the
// readers that give exactly what that command feeds (read_image_sequence, read_gray_image,
// read_depth_image) and its calibrations. The GIL is released while it works; each VisualSlam
// serialises its own calls (pipeline_support.hpp locked), so Python threads may share one.

#include <pybind11/stl.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "cairn/inertial/euroc_files.hpp"
#include "cairn/io/calibration_yaml.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/vision/features.hpp"
#include "cairn/vision/vocabulary.hpp"
#include "cairn/vslam/config.hpp"
#include "cairn/vslam/map_file.hpp"
#include "cairn/vslam/outputs.hpp"
#include "cairn/vslam/visual_slam.hpp"
#include "pipeline_support.hpp"

namespace cairn::python {
namespace {

io::SequenceKind sequence_kind(const std::string& word) {
  if (word == "stereo") return io::SequenceKind::kStereo;
  if (word == "rgbd" || word == "rgb-d") return io::SequenceKind::kRgbd;
  if (word == "monocular" || word == "mono") return io::SequenceKind::kMonocular;
  throw_value_error("kind: expected 'stereo', 'rgbd' or 'monocular', found '" + word + "'");
}

/// A numpy image and the cv::Mat viewing its buffer (the array keeps the buffer alive).
struct ImageView {
  py::array array;
  cv::Mat mat;
};

/// A 2-D array of T as a cv::Mat of `type` over the same memory: no copy when the array is
/// C-contiguous, else one. Another dtype or shape is a ValueError naming `what`.
template <class T>
ImageView image_view(const py::array& image, int type, const char* what, const char* dtype) {
  if (!py::isinstance<py::array_t<T>>(image)) {
    throw_value_error(std::string(what) + ": expected a " + dtype + " array, found dtype " + py::str(image.dtype()).cast<std::string>());
  }
  if (image.ndim() != 2) {
    throw_value_error(std::string(what) + ": expected a 2-D (grey) image, found " + std::to_string(image.ndim()) +
                      " dimensions (colour: convert to grey, e.g. with cairn.read_gray_image)");
  }
  ImageView view;
  view.array = py::array_t<T, py::array::c_style>::ensure(image);
  if (!view.array) throw_value_error(std::string(what) + ": could not be read as a contiguous array");
  view.mat = cv::Mat(static_cast<int>(view.array.shape(0)), static_cast<int>(view.array.shape(1)), type,
                     const_cast<void*>(view.array.data()));  // read only: VisualSlam takes const cv::Mat&
  return view;
}

ImageView gray_view(const py::array& image, const char* what) { return image_view<std::uint8_t>(image, CV_8UC1, what, "uint8"); }

/// A depth image: uint16 in the calibration's depth units, viewed; float metres converted once
/// to those units as cairn converts a 32FC1 depth message (vslam/image_message.cpp): rounded,
/// NaN, infinity, <= 0 and beyond 16 bits as 0 (no depth).
ImageView depth_view(const py::array& depth, double units_per_m) {
  if (py::isinstance<py::array_t<std::uint16_t>>(depth)) return image_view<std::uint16_t>(depth, CV_16UC1, "depth", "uint16");
  if (!py::isinstance<py::array_t<float>>(depth) && !py::isinstance<py::array_t<double>>(depth)) {
    throw_value_error("depth: expected a uint16 (depth units) or float (metres) array, found dtype " +
                      py::str(depth.dtype()).cast<std::string>());
  }
  const auto metres = DoubleArray::ensure(depth);
  if (!metres) throw_value_error("depth: could not be read as an array of numbers");
  if (metres.ndim() != 2) throw_value_error("depth: expected a 2-D image, found " + std::to_string(metres.ndim()) + " dimensions");
  ImageView view;
  view.mat = cv::Mat(static_cast<int>(metres.shape(0)), static_cast<int>(metres.shape(1)), CV_16UC1);
  const double* in = metres.data();
  for (int y = 0; y < view.mat.rows; ++y) {
    auto* out = view.mat.ptr<std::uint16_t>(y);
    for (int x = 0; x < view.mat.cols; ++x) {
      const double units = std::round(*in++ * units_per_m);
      out[x] = std::isfinite(units) && units > 0.0 && units <= 65535.0 ? static_cast<std::uint16_t>(units) : std::uint16_t{0};
    }
  }
  return view;
}

/// A cv::Mat as a 2-D numpy array over its memory (the array owns the Mat).
template <class T>
py::array_t<T> mat_to_array(cv::Mat mat) {
  auto* owner = new cv::Mat(std::move(mat));
  const py::capsule free_when_done(owner, [](void* p) { delete static_cast<cv::Mat*>(p); });
  return py::array_t<T>({static_cast<py::ssize_t>(owner->rows), static_cast<py::ssize_t>(owner->cols)},
                        {static_cast<py::ssize_t>(owner->step[0]), static_cast<py::ssize_t>(sizeof(T))}, owner->ptr<T>(),
                        free_when_done);
}

/// The options `cairn vslam` starts from for the dataset (vslam::dataset_options), then the file
/// and the keys; the vocabulary, when given, for loop closure and relocalisation.
vslam::VisualSlamOptions vslam_configuration(const std::string& dataset, io::SequenceKind kind, const py::object& config,
                                             const py::object& set, const py::object& vocabulary) {
  vslam::VisualSlamOptions options = vslam::dataset_options(dataset, kind);
  apply_configuration(vslam::configuration(), options, config, set);
  if (std::string problems; !options.is_valid(&problems)) throw_value_error("invalid configuration: " + problems);
  if (!vocabulary.is_none()) {
    options.vocabulary = std::make_shared<const vision::Vocabulary>(vision::Vocabulary::load(fspath(vocabulary)));
  }
  return options;
}

nlohmann::json vslam_summary_json(const vslam::VisualSlamSummary& s) {
  nlohmann::json loops = nlohmann::json::array();
  for (const vslam::LoopRecord& l : s.loops) {
    loops.push_back({{"keyframe", l.keyframe}, {"candidate", l.candidate}, {"frame", l.frame},
                     {"candidate_frame", l.candidate_frame}, {"score", l.score}, {"pnp_inliers", l.pnp_inliers},
                     {"matches", l.matches}, {"decision", l.decision}, {"reason", l.reason}, {"merge", l.merge},
                     {"correction_m", l.correction_m}, {"correction_deg", l.correction_deg}});
  }
  return {{"frames", s.frames}, {"frames_ok", s.frames_ok}, {"frames_degraded", s.frames_degraded},
          {"frames_lost", s.frames_lost}, {"keyframes", s.keyframes}, {"keyframes_culled", s.keyframes_culled},
          {"map_points", s.map_points}, {"map_points_culled", s.map_points_culled}, {"local_bas", s.local_bas},
          {"relocalisations", s.relocalisations}, {"loop_queries", s.loop_queries}, {"loops_accepted", s.loops_accepted},
          {"revisits_verified", s.revisits_verified}, {"maps_started", s.maps_started}, {"maps_merged", s.maps_merged},
          {"global_bas", s.global_bas}, {"local_ba_s", s.local_ba_s}, {"loop_s", s.loop_s},
          {"global_ba_s", s.global_ba_s}, {"loops", loops},
          {"frames_carried_by_imu", s.frames_carried_by_imu}, {"frames_contradicting_imu", s.frames_contradicting_imu},
          {"inertial_estimates", s.inertial_estimates}, {"inertial_estimates_refused", s.inertial_estimates_refused},
          {"inertial_refusal", s.inertial_refusal}, {"frames_scale_drifted", s.frames_scale_drifted}};
}

/// VisualSlamOptions with the IMU on (cairn vslam --imu's options, vslam/inertial_input.hpp):
/// the camera in the IMU's frame and the noise of a sensor.yaml (default: EuRoC's ADIS16448).
void enable_imu(vslam::VisualSlamOptions& options, const py::object& T_imu_camera, const py::object& imu_calibration) {
  options.inertial.enabled = true;
  if (!T_imu_camera.is_none()) {
    const Matrix4 T = matrix4_from_array(T_imu_camera.cast<DoubleArray>(), "T_imu_camera");
    if (!T.allFinite()) throw_value_error("T_imu_camera: expected finite values");
    options.inertial.T_body_camera = core::SE3::from_matrix(T);
  }
  if (!imu_calibration.is_none()) options.inertial.noise = inertial::read_euroc_imu_calibration(fspath(imu_calibration)).noise;
  if (std::string problems; !options.is_valid(&problems)) throw_value_error("invalid configuration: " + problems);
}

/// VisualSlam fed as `cairn vslam` feeds it (cmd_vslam.cpp, vslam/image_input.hpp add_frame).
class VisualSession {
 public:
  VisualSession(const io::CameraCalibration& camera, io::SequenceKind kind, vslam::VisualSlamOptions options)
      : camera_(camera), kind_(kind), options_(std::move(options)), slam_(camera_, kind_, options_) {}
  /// Localisation in a saved map (vslam::VisualSlam(const SavedVisualMap&, ...)).
  VisualSession(const vslam::SavedVisualMap& map, const vslam::VisualSlamOptions& options)
      : camera_(map.camera), kind_(map.kind), slam_(map, options) {
    options_ = slam_.options();
  }

  /// vslam::write_saved_map of the main map (what `cairn vslam --save-map` writes).
  void save_map(const std::string& path) {
    const vslam::SavedVisualMap map = locked(mutex_, [&] {
      if (slam_.keyframe_poses().empty()) throw_value_error("VisualSlam.save_map(): no keyframe yet: nothing to save");
      return slam_.saved_map(vslam::configuration().json(options_).dump(), "python");
    });
    vslam::write_saved_map(path, map);
  }
  bool localization_only() const { return slam_.localization_only(); }

  /// `second`: the right image (stereo), the depth image (RGB-D) or empty (monocular).
  vslam::FrameResult add(double time_s, const cv::Mat& image, const cv::Mat& second) {
    const core::Timestamp time = timestamp_of(time_s, "time");
    check_plausible(image);
    return locked(mutex_, [&] {
      vslam::FrameResult r = kind_ == io::SequenceKind::kStereo ? slam_.add_stereo(time, image, second)
                             : kind_ == io::SequenceKind::kRgbd ? slam_.add_rgbd(time, image, second)
                                                                : slam_.add_monocular(time, image);
      times_.push_back(time_s);
      return r;
    });
  }

  vslam::FrameResult add_frame(const py::array& image, double time_s, const py::object& depth) {
    if (kind_ == io::SequenceKind::kStereo) throw_value_error("a stereo VisualSlam takes add_frame(left, right, time)");
    if (kind_ == io::SequenceKind::kRgbd && depth.is_none()) throw_value_error("depth: an RGB-D VisualSlam needs the depth image");
    if (kind_ == io::SequenceKind::kMonocular && !depth.is_none()) throw_value_error("depth: a monocular VisualSlam takes no depth");
    const ImageView gray = gray_view(image, "image");
    const ImageView second = depth.is_none() ? ImageView{} : depth_view(depth.cast<py::array>(), camera_.depth_units_per_m);
    return add(time_s, gray.mat, second.mat);
  }

  vslam::FrameResult add_stereo(const py::array& left, const py::array& right, double time_s) {
    if (kind_ != io::SequenceKind::kStereo) throw_value_error("add_frame(left, right, time) needs a stereo VisualSlam");
    const ImageView l = gray_view(left, "left");
    const ImageView r = gray_view(right, "right");
    return add(time_s, l.mat, r.mat);
  }

  py::array_t<double> trajectory() { return poses_to_array(locked(mutex_, [&] { return slam_.trajectory(); })); }
  py::array_t<double> times() { return vector_to_array(locked(mutex_, [&] { return times_; })); }
  py::array_t<double> keyframe_poses() { return poses_to_array(locked(mutex_, [&] { return slam_.keyframe_poses(); })); }
  py::array_t<std::int64_t> keyframe_frames() { return indices_to_array(locked(mutex_, [&] { return slam_.keyframe_frames(); })); }
  std::vector<int> frame_segments() { return locked(mutex_, [&] { return slam_.frame_segments(); }); }
  int main_segment() { return locked(mutex_, [&] { return slam_.main_segment(); }); }
  py::array_t<double> map_points() { return points_to_array(locked(mutex_, [&] { return slam_.map_points(); })); }
  py::object summary() { return json_to_python(locked(mutex_, [&] { return vslam_summary_json(slam_.summary()); })); }

  /// IMU readings: one (time, 3, 3) or many (N, N x 3, N x 3), IMU frame, rad/s and m/s^2.
  void add_imu(const DoubleArray& time, const DoubleArray& gyro, const DoubleArray& accel) {
    if (!options_.inertial.enabled) throw_value_error("add_imu: this VisualSlam was made without imu=True");
    const bool one = time.ndim() == 0;
    const py::ssize_t n = one ? 1 : (time.ndim() == 1 ? time.shape(0) : -1);
    auto rows_ok = [&](const DoubleArray& a) {
      return one ? (a.ndim() == 1 && a.shape(0) == 3) : (a.ndim() == 2 && a.shape(0) == n && a.shape(1) == 3);
    };
    if (n < 0 || !rows_ok(gyro) || !rows_ok(accel)) {
      throw_value_error("add_imu: expected time (float or N), gyro and accel (3 or N x 3)");
    }
    std::vector<inertial::ImuSample> samples(static_cast<std::size_t>(n));
    const double* t = time.data();
    const double* g = gyro.data();
    const double* a = accel.data();
    for (py::ssize_t k = 0; k < n; ++k) {
      inertial::ImuSample& sample = samples[static_cast<std::size_t>(k)];
      sample.stamp = timestamp_of(t[k], "time");
      sample.gyro_rad_s = Eigen::Vector3d(g[3 * k], g[3 * k + 1], g[3 * k + 2]);
      sample.accel_mps2 = Eigen::Vector3d(a[3 * k], a[3 * k + 1], a[3 * k + 2]);
    }
    locked(mutex_, [&] {
      for (const inertial::ImuSample& sample : samples) slam_.add_imu(sample);
      return 0;
    });
  }

  /// The inertial estimate: whether it exists, gravity in the map's frame and the biases.
  py::object inertial_state() {
    return json_to_python(locked(mutex_, [&] {
      nlohmann::json j = {{"enabled", options_.inertial.enabled}, {"initialised", slam_.inertial_initialised()}};
      j.update(vslam::inertial_estimate_json(slam_));  // report.json's fields and names
      return j;
    }));
  }
  py::object config() const { return json_to_python(vslam::configuration().json(options_)); }
  const io::CameraCalibration& calibration() const { return camera_; }
  std::string kind() const { return std::string(io::to_string(kind_)); }

 private:
  /// As `cairn vslam` before any work (vslam::check_calibration_plausible): a calibration no real
  /// camera has would be tracked "ok" while measuring nothing. At the first frame, for its size
  /// unless the calibration gives one.
  void check_plausible(const cv::Mat& image) {
    if (checked_) return;
    const int width = camera_.width > 0 ? camera_.width : image.cols;
    const int height = camera_.height > 0 ? camera_.height : image.rows;
    const std::string implausible = camera_.implausibilities(width, height, kind_ == io::SequenceKind::kStereo);
    if (!implausible.empty()) throw_value_error("implausible calibration: " + implausible);
    checked_ = true;
  }

  io::CameraCalibration camera_;
  io::SequenceKind kind_;
  vslam::VisualSlamOptions options_;
  vslam::VisualSlam slam_;
  std::vector<double> times_;
  bool checked_ = false;
  std::mutex mutex_;
};

/// A dataset folder as `cairn vslam FOLDER` reads it (cli/vslam_input.cpp read_sequence). EuRoC
/// pairs need rectifying (vision::StereoRectifier), which these bindings do not do.
io::ImageSequence read_image_sequence(const py::object& folder) {
  const std::string path = fspath(folder);
  const py::gil_scoped_release release;
  const std::string layout = io::detect_image_layout(path);
  if (layout == "euroc") {
    throw std::invalid_argument(path + ": EuRoC's stereo pairs are not rectified, and the Python bindings do not rectify: use cairn vslam");
  }
  return layout == "kitti" ? io::read_kitti_stereo(path) : layout == "folder" ? io::read_image_folder(path) : io::read_tum_rgbd(path);
}

std::vector<std::string> frame_files(const io::ImageSequence& sequence, std::string io::ImageFrame::*file) {
  std::vector<std::string> files;
  for (const io::ImageFrame& frame : sequence.frames) files.push_back(frame.*file);
  return files;
}

// ---------------------------------------------------------------------------------------------
// The Python classes

void bind_calibration(py::module_& m) {
  using C = io::CameraCalibration;
  py::class_<C>(m, "CameraCalibration", "A pinhole camera with Brown-Conrady distortion (io::CameraCalibration).")
      .def(py::init([](double fx, double fy, double cx, double cy, double k1, double k2, double p1, double p2, double k3, int width,
                       int height, double baseline_m, double depth_units_per_m, double virtual_baseline_m) {
             return C{fx, fy, cx, cy, k1, k2, p1, p2, k3, width, height, baseline_m, depth_units_per_m, virtual_baseline_m};
           }),
           py::arg("fx"), py::arg("fy"), py::arg("cx"), py::arg("cy"), py::kw_only(), py::arg("k1") = 0.0, py::arg("k2") = 0.0,
           py::arg("p1") = 0.0, py::arg("p2") = 0.0, py::arg("k3") = 0.0, py::arg("width") = 0, py::arg("height") = 0,
           py::arg("baseline_m") = 0.0, py::arg("depth_units_per_m") = 0.0, py::arg("virtual_baseline_m") = 0.0)
      .def_readwrite("fx", &C::fx).def_readwrite("fy", &C::fy).def_readwrite("cx", &C::cx).def_readwrite("cy", &C::cy)
      .def_readwrite("k1", &C::k1).def_readwrite("k2", &C::k2).def_readwrite("p1", &C::p1).def_readwrite("p2", &C::p2)
      .def_readwrite("k3", &C::k3)
      .def_readwrite("width", &C::width, "Pixels; 0: from the first image.").def_readwrite("height", &C::height)
      .def_readwrite("baseline_m", &C::baseline_m, "Stereo: between the rectified cameras, metres.")
      .def_readwrite("depth_units_per_m", &C::depth_units_per_m, "RGB-D: depth units per metre (TUM: 5000).")
      .def_readwrite("virtual_baseline_m", &C::virtual_baseline_m, "RGB-D: ORB-SLAM's bf / fx.")
      .def("problems", [](const C& c) { std::string why; c.is_valid(&why); return why; }, "'' when usable, else every problem.")
      .def("implausibilities", &C::implausibilities, py::arg("width"), py::arg("height"), py::arg("stereo"),
           "'' when plausible for a real camera taking width x height images.")
      .def("__repr__", [](const C& c) {
        return "CameraCalibration(fx=" + std::to_string(c.fx) + ", fy=" + std::to_string(c.fy) + ", cx=" + std::to_string(c.cx) +
               ", cy=" + std::to_string(c.cy) + ", baseline_m=" + std::to_string(c.baseline_m) + ")";
      });
  m.def("read_calibration_yaml", [](const py::object& path) { return io::read_calibration_yaml(fspath(path)); }, py::arg("path"),
        "A calibration YAML as `cairn vslam --calib` reads it (fx, fy, cx, cy; k1..k3, p1, p2, width, height, baseline_m, ...).");
  m.def("read_kitti_calibration", [](const py::object& path) { return io::read_kitti_calibration(fspath(path)); }, py::arg("path"),
        "KITTI odometry's calib.txt (P0, P1): fx, fy, cx, cy and the baseline.");
  m.def("tum_calibration", &io::tum_calibration_preset, py::arg("name"),
        "The published calibration of a TUM RGB-D Kinect: 'tum-fr1', 'tum-fr2' or 'tum-fr3' (`cairn vslam --camera`).");
}

void bind_image_input(py::module_& m) {
  using Q = io::ImageSequence;
  py::class_<Q>(m, "ImageSequence", "An image dataset on disk (io::ImageSequence): KITTI stereo, TUM RGB-D or a plain folder.")
      .def_property_readonly("kind", [](const Q& q) { return std::string(io::to_string(q.kind)); }, "'stereo', 'rgbd' or 'monocular'.")
      .def_readonly("layout", &Q::layout, "'kitti', 'tum' or 'folder'.")
      .def_readonly("folder", &Q::folder)
      .def_readonly("calibration", &Q::calibration, "The dataset's (KITTI); zero where the dataset ships none (give one).")
      .def_readonly("calibration_from_dataset", &Q::calibration_from_dataset)
      .def_property_readonly("times", [](const Q& q) {
            std::vector<double> seconds;
            for (const io::ImageFrame& f : q.frames) seconds.push_back(f.time.seconds());
            return vector_to_array(seconds);
          }, "Seconds, one per frame.")
      .def_property_readonly("images", [](const Q& q) { return frame_files(q, &io::ImageFrame::image); }, "Left, colour or only image files.")
      .def_property_readonly("right_images", [](const Q& q) { return frame_files(q, &io::ImageFrame::right_image); })
      .def_property_readonly("depth_images", [](const Q& q) { return frame_files(q, &io::ImageFrame::depth_image); })
      .def_readonly("ground_truth_path", &Q::ground_truth_path)
      .def_readonly("notes", &Q::notes, "How the folder was read (assumed times, skipped lines).")
      .def("__len__", [](const Q& q) { return q.frames.size(); });
  m.def("read_image_sequence", &read_image_sequence, py::arg("folder"),
        "A KITTI odometry, TUM RGB-D or plain image folder as `cairn vslam FOLDER` reads it (EuRoC: not here).");
  m.def("read_gray_image", [](const py::object& path) {
          const std::string file = fspath(path);
          return mat_to_array<std::uint8_t>([&] { const py::gil_scoped_release release; return vision::read_gray_image(file); }());
        }, py::arg("path"), "A PNG or JPEG as the 8-bit grey image `cairn vslam` makes of it (H x W uint8).");
  m.def("read_depth_image", [](const py::object& path) {
          const std::string file = fspath(path);
          return mat_to_array<std::uint16_t>([&] { const py::gil_scoped_release release; return vision::read_depth_image(file); }());
        }, py::arg("path"), "A 16-bit depth PNG as `cairn vslam` reads it (H x W uint16, the file's units; 0: no depth).");
}

void bind_vslam_result(py::module_& m) {
  using R = vslam::FrameResult;
  py::class_<R>(m, "VisualFrameResult", "What VisualSlam.add_frame says about one frame (vslam::FrameResult).")
      .def_readonly("frame", &R::frame, "Index in add_frame order.")
      .def_property_readonly("time", [](const R& r) { return r.time.seconds(); }, "Seconds.")
      .def_readonly("tracked", &R::tracked, "False: the pose is the motion model's guess.")
      .def_property_readonly("health", [](const R& r) { return health_word(r.health); }, "'ok', 'degraded' or 'lost'.")
      .def_property_readonly("pose", [](const R& r) { return matrix_to_array(r.T_world_camera.matrix()); },
                             "T_world_camera (4 x 4) when tracked; world = the first camera (x right, y down, z forward).")
      .def_readonly("features", &R::features)
      .def_readonly("stereo_points", &R::stereo_points, "Keypoints with a stereo match or depth.")
      .def_readonly("inliers", &R::inliers, "Map-point matches after the local map's pose optimisation.")
      .def_readonly("inlier_ratio", &R::inlier_ratio)
      .def_readonly("keyframe", &R::keyframe)
      .def_readonly("relocalised", &R::relocalised)
      .def_readonly("relocalisation_refused", &R::relocalisation_refused,
                    "A relocalisation candidate was refused (ambiguous, or too few inliers); the reason is in note.")
      .def_readonly("loop_closed", &R::loop_closed)
      .def_readonly("new_map", &R::new_map, "This frame started a new map segment.")
      .def_readonly("segment", &R::segment)
      .def_readonly("sigma_position_m", &R::sigma_position_m)
      .def_readonly("note", &R::note, "Why lost or degraded.")
      .def_property_readonly("keypoints", [](const R& r) {
            py::array_t<float> out({static_cast<py::ssize_t>(r.keypoints.size()), py::ssize_t{2}});
            auto view = out.mutable_unchecked<2>();
            for (std::size_t k = 0; k < r.keypoints.size(); ++k) {
              view(static_cast<py::ssize_t>(k), 0) = r.keypoints[k].pt.x;
              view(static_cast<py::ssize_t>(k), 1) = r.keypoints[k].pt.y;
            }
            return out;
          }, "Keypoint positions (K x 2, pixels).")
      .def_property_readonly("keypoint_states", [](const R& r) {
            py::array_t<std::int8_t> out(static_cast<py::ssize_t>(r.keypoint_states.size()));
            if (!r.keypoint_states.empty()) std::memcpy(out.mutable_data(), r.keypoint_states.data(), r.keypoint_states.size());
            return out;
          }, "Per keypoint: 0 unmatched, 1 stereo/depth point only, 2 matched to a map point.")
      .def_property_readonly("timings", [](const R& r) {
            py::dict d;
            d["features_s"] = r.times.features_s;
            d["stereo_s"] = r.times.stereo_s;
            d["tracking_s"] = r.times.tracking_s;
            d["mapping_s"] = r.times.mapping_s;
            d["total_s"] = r.times.total_s;
            return d;
          }, "Seconds per stage.")
      .def("__repr__", [](const R& r) {
        return "VisualFrameResult(frame=" + std::to_string(r.frame) + ", health='" + health_word(r.health) +
               "', inliers=" + std::to_string(r.inliers) + ", keyframe=" + (r.keyframe ? "True" : "False") + ")";
      });
}

void bind_visual_slam(py::module_& m) {
  bind_vslam_result(m);
  py::class_<VisualSession>(m, "VisualSlam",
                            "Stereo, RGB-D or monocular visual SLAM after ORB-SLAM2 (vslam::VisualSlam), one frame at a time.")
      .def(py::init([](const io::CameraCalibration& calibration, const std::string& kind, const py::object& config,
                       const py::object& set, const std::string& dataset, const py::object& vocabulary, bool imu,
                       const py::object& T_imu_camera, const py::object& imu_calibration) {
             const io::SequenceKind k = sequence_kind(kind);
             vslam::VisualSlamOptions options = vslam_configuration(dataset, k, config, set, vocabulary);
             if (imu) {
               enable_imu(options, T_imu_camera, imu_calibration);
             } else if (!T_imu_camera.is_none() || !imu_calibration.is_none()) {
               throw_value_error("T_imu_camera and imu_calibration go with imu=True");
             }
             return std::make_unique<VisualSession>(calibration, k, std::move(options));
           }),
           py::arg("calibration"), py::arg("kind") = "stereo", py::arg("config") = py::none(), py::arg("set") = py::none(),
           py::kw_only(), py::arg("dataset") = "folder", py::arg("vocabulary") = py::none(), py::arg("imu") = false,
           py::arg("T_imu_camera") = py::none(), py::arg("imu_calibration") = py::none(),
           "calibration: a cairn.CameraCalibration (rectified stereo needs baseline_m; RGB-D depth_units_per_m and "
           "virtual_baseline_m); kind 'stereo', 'rgbd' or 'monocular'; the options as `cairn vslam` makes them from the "
           "dataset's layout ('kitti': 2000 features, others 1000), --config and --set; vocabulary: a bag-of-words file "
           "(loop closure, relocalisation). imu=True: visual-inertial tracking as `cairn vslam --imu` (feed add_imu "
           "before each frame), T_imu_camera the camera's pose in the IMU's frame (4 x 4), imu_calibration a "
           "Kalibr/EuRoC sensor.yaml with the noise (default: EuRoC's ADIS16448).")
      .def_static("localize_in",
                  [](const py::object& map_path, const py::object& config, const py::object& set, const std::string& dataset,
                     const py::object& vocabulary) {
                    const vslam::SavedVisualMap map = vslam::read_saved_map(fspath(map_path));
                    return std::make_unique<VisualSession>(map, vslam_configuration(dataset, map.kind, config, set, vocabulary));
                  },
                  py::arg("map"), py::arg("config") = py::none(), py::arg("set") = py::none(), py::kw_only(), py::arg("dataset") = "folder",
                  py::arg("vocabulary") = py::none(),
                  "Localisation in a map saved by `cairn vslam --save-map` or VisualSlam.save_map (ORB-SLAM2's localisation "
                  "mode, as `cairn vslam --localize-in`): frames are tracked against the map and relocalised by bag of words "
                  "(vocabulary) when lost; nothing is added to the map. The map's camera, kind and ORB settings are used.")
      .def("save_map", [](VisualSession& s, const py::object& path) { s.save_map(fspath(path)); }, py::arg("path"),
           "Writes the main map (keyframes, map points, descriptors, covisibility, the vocabulary's identity) for "
           "VisualSlam.localize_in and `cairn vslam --localize-in`, whole or not at all.")
      .def_property_readonly("localization_only", &VisualSession::localization_only,
                             "True when made by localize_in: the map is never changed.")
      .def("add_frame", &VisualSession::add_frame, py::arg("image"), py::arg("time"), py::arg("depth") = py::none(),
           "A grey image (H x W uint8, viewed without a copy) at `time` seconds; RGB-D: with its depth (uint16 in "
           "depth_units_per_m, or float metres). Releases the GIL.")
      .def("add_frame", &VisualSession::add_stereo, py::arg("left"), py::arg("right"), py::arg("time"),
           "A rectified stereo pair (H x W uint8 each).")
      .def("trajectory", &VisualSession::trajectory,
           "Every frame's T_world_camera (N x 4 x 4) through its reference keyframe's current pose (trajectory.kitti).")
      .def("times", &VisualSession::times, "Every frame's time, seconds (N).")
      .def("keyframe_poses", &VisualSession::keyframe_poses, "The keyframes in the map (K x 4 x 4).")
      .def("keyframe_frames", &VisualSession::keyframe_frames, "The frame index of each keyframe (K).")
      .def("frame_segments", &VisualSession::frame_segments, "Per frame, its map segment now (-1: before the first keyframe).")
      .def_property_readonly("main_segment", &VisualSession::main_segment)
      .def("map_points", &VisualSession::map_points, "The good map points in the world frame (M x 3 float64).")
      .def_property_readonly("summary", &VisualSession::summary, "Frame and keyframe counts, loops and their decisions, as a dict.")
      .def("add_imu", &VisualSession::add_imu, py::arg("time"), py::arg("gyro"), py::arg("accel"),
           "IMU readings in the IMU's frame: one (time s, gyro (3) rad/s, accel (3) m/s^2) or many (N, N x 3, N x 3), "
           "in time order, each before the frames it spans (a frame at t needs a reading at or after t).")
      .def_property_readonly("inertial", &VisualSession::inertial_state,
                             "With imu=True: {'enabled', 'initialised'} and, once initialised, gravity_world_mps2 (the map's "
                             "frame), gyro_bias_rad_s and accel_bias_mps2, named as in report.json's 'inertial'.")
      .def("config", &VisualSession::config, "The options in effect, {section: {key: value}}.")
      .def_property_readonly("calibration", &VisualSession::calibration)
      .def_property_readonly("kind", &VisualSession::kind);
}

}  // namespace

void bind_vslam(py::module_& m) {
  bind_calibration(m);
  bind_image_input(m);
  bind_visual_slam(m);
}

}  // namespace cairn::python
