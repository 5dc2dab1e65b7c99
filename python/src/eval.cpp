// The evaluation part of the `cairn` Python module (bindings.hpp): evo's APE and RPE, the KITTI
// devkit's metric and the trajectory alignments of src/cairn/eval/. Keyword names are evo's
// (evo/main_ape.py ape(), evo/main_rpe.py rpe(), evo/core/geometry.py umeyama_alignment) and
// pose relations and delta units take evo's `-r` / `-u` names, so an evo script ports by changing
// its imports. The library reports an expected failure as an Outcome (eval/status.hpp); here a
// failed Outcome becomes a ValueError carrying cairn's message. The evaluations run without the
// GIL: every argument is a C++ value by then, and results become Python objects after it.

#include <cstdint>
#include <iomanip>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "bindings.hpp"
#include "cairn/eval/alignment.hpp"
#include "cairn/eval/ape.hpp"
#include "cairn/eval/association.hpp"
#include "cairn/eval/kitti_metric.hpp"
#include "cairn/eval/matrix_trajectory.hpp"
#include "cairn/eval/pose_relation.hpp"
#include "cairn/eval/rpe.hpp"
#include "cairn/eval/statistics.hpp"
#include "cairn/eval/status.hpp"

namespace cairn::python {
namespace {

using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// ---------------------------------------------------------------------------------------------
// Names and keywords -> cairn's options. These run with the GIL released (call_guard), so they
// touch no Python object; a C++ exception thrown here is translated after the GIL is back.

eval::PoseRelation relation_named(const std::string& name) {
  if (const auto relation = eval::pose_relation_from_name(name)) return *relation;
  throw_value_error("pose_relation: unknown name '" + name +
                    "'; expected one of 'trans_part', 'angle_rad', 'angle_deg', 'rot_part', 'full' (evo's -r names)");
}

eval::DeltaUnit delta_unit_named(const std::string& name) {
  if (const auto unit = eval::delta_unit_from_name(name)) return *unit;
  throw_value_error("delta_unit: unknown unit '" + name +
                    "'; expected 'f' (frames) or 'm' (metres) (evo's -u 'd' and 'r' are not supported)");
}

// Python names of the alignments: cairn's, with evo's word "origin" for kFirstPose.
std::string_view method_name(eval::AlignmentMethod method) {
  return method == eval::AlignmentMethod::kFirstPose ? "origin" : eval::to_string(method);
}

eval::AlignmentMethod method_named(const std::string& name) {
  if (name == "origin") return eval::AlignmentMethod::kFirstPose;
  if (const auto method = eval::alignment_method_from_name(name)) return *method;
  throw_value_error("method: unknown alignment '" + name + "'; expected one of 'se3', 'sim3', 'se2', 'origin', 'none'");
}

// evo's n_to_align / n: -1 means every pair (cairn's 0).
std::size_t pairs_to_align(std::int64_t n, const char* what) {
  if (n == 0 || n < -1) {
    throw_value_error(std::string(what) + " must be -1 (all pairs) or >= 1, found " + std::to_string(n));
  }
  return n < 0 ? 0 : static_cast<std::size_t>(n);
}

// evo's ape()/rpe() keywords. evo applies Umeyama and then align_origin when both are given, and
// scales alone for correct_scale without align (-s); cairn applies one alignment and has no
// scale-only one, so those combinations are refused rather than silently changed.
eval::AlignmentOptions alignment_options(bool align, bool correct_scale, bool align_origin, std::int64_t n_to_align) {
  if (align_origin && (align || correct_scale)) {
    throw_value_error("align_origin cannot be combined with align or correct_scale: cairn applies one alignment");
  }
  if (correct_scale && !align) {
    throw_value_error("correct_scale without align is evo's scale-only correction (-s), which cairn does not have; "
                      "use align=True, correct_scale=True for the Sim(3) alignment (-as)");
  }
  eval::AlignmentOptions options;
  options.method = align ? (correct_scale ? eval::AlignmentMethod::kSim3 : eval::AlignmentMethod::kSE3)
                         : (align_origin ? eval::AlignmentMethod::kFirstPose : eval::AlignmentMethod::kNone);
  options.num_poses = pairs_to_align(n_to_align, "n_to_align");
  return options;
}

eval::AssociationOptions association_options(double t_max_diff, double t_offset, bool by_index) {
  eval::AssociationOptions options;
  options.max_time_difference_s = t_max_diff;
  options.offset_s = t_offset;
  options.by_index = by_index;
  return options;
}

void raise_if_failed(const eval::Outcome& outcome) {
  if (!outcome.ok()) throw_value_error(outcome.message + " [" + std::string(eval::to_string(outcome.status)) + "]");
}

// ---------------------------------------------------------------------------------------------
// Arrays

std::string shape_text(const py::array& array) {
  std::string s = "(";
  for (py::ssize_t k = 0; k < array.ndim(); ++k) s += (k ? ", " : "") + std::to_string(array.shape(k));
  return s + (array.ndim() == 1 ? ",)" : ")");
}

py::array_t<double> matrix_array(const Eigen::MatrixXd& matrix) {
  py::array_t<double> out({static_cast<py::ssize_t>(matrix.rows()), static_cast<py::ssize_t>(matrix.cols())});
  Eigen::Map<RowMajorMatrix>(out.mutable_data(), matrix.rows(), matrix.cols()) = matrix;
  return out;
}

py::array_t<double> column_array(const Eigen::VectorXd& vector) {
  return vector_to_array(std::vector<double>(vector.data(), vector.data() + vector.size()));
}

py::array_t<std::int64_t> index_array(const std::vector<std::size_t>& indices) {
  py::array_t<std::int64_t> out(static_cast<py::ssize_t>(indices.size()));
  auto view = out.mutable_unchecked<1>();
  for (std::size_t k = 0; k < indices.size(); ++k) {
    view(static_cast<py::ssize_t>(k)) = static_cast<std::int64_t>(indices[k]);
  }
  return out;
}

py::array_t<std::int64_t> pairs_array(const std::vector<eval::IndexPair>& pairs) {
  py::array_t<std::int64_t> out({static_cast<py::ssize_t>(pairs.size()), py::ssize_t{2}});
  auto view = out.mutable_unchecked<2>();
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    view(static_cast<py::ssize_t>(k), 0) = static_cast<std::int64_t>(pairs[k].first);
    view(static_cast<py::ssize_t>(k), 1) = static_cast<std::int64_t>(pairs[k].second);
  }
  return out;
}

/// An m x n array of n points (evo's umeyama_alignment layout), m = 2 or 3.
Eigen::MatrixXd points_matrix(const DoubleArray& array, const char* what) {
  if (array.ndim() != 2 || (array.shape(0) != 2 && array.shape(0) != 3) || array.shape(1) < 1) {
    throw_value_error(std::string(what) +
                      ": expected an array of shape (m, n), m = 2 or 3 coordinates of n >= 1 points, found " +
                      shape_text(array));
  }
  Eigen::MatrixXd points = Eigen::Map<const RowMajorMatrix>(array.data(), array.shape(0), array.shape(1));
  if (!points.allFinite()) throw_value_error(std::string(what) + ": holds a NaN or infinity");
  return points;
}

std::vector<Matrix4> finite_poses(const DoubleArray& array, const char* what) {
  std::vector<Matrix4> poses = poses_from_array(array, what);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    if (!poses[k].allFinite()) {
      throw_value_error(std::string(what) + ": pose " + std::to_string(k) + " holds a NaN or infinity");
    }
  }
  return poses;
}

py::dict statistics_dict(const eval::Statistics& s) {
  py::dict d;
  d["rmse"] = s.rmse;
  d["mean"] = s.mean;
  d["median"] = s.median;
  d["std"] = s.std;
  d["min"] = s.min;
  d["max"] = s.max;
  d["sse"] = s.sse;
  d["count"] = s.count;
  return d;
}

// [[s R, t], [0, 1]]: evo's lie_algebra.sim3(R, t, s), the alignment_transformation of ape().
Matrix4 similarity_matrix(const eval::Alignment& alignment) {
  Matrix4 S = Matrix4::Identity();
  S.topLeftCorner<3, 3>() = alignment.scale * alignment.R;
  S.topRightCorner<3, 1>() = alignment.t;
  return S;
}

// ---------------------------------------------------------------------------------------------
// The functions bound

py::array_t<double> apply_alignment(const eval::Alignment& alignment, const DoubleArray& poses) {
  if (poses.ndim() == 2) {
    return matrix_array(alignment.apply(matrix4_from_array(poses, "poses")));
  }
  return poses_to_array(eval::apply_alignment(alignment, poses_from_array(poses, "poses")));
}

eval::Alignment align_arrays(const DoubleArray& reference, const DoubleArray& estimate, const std::string& method,
                      std::int64_t n) {
  const std::vector<Matrix4> reference_poses = finite_poses(reference, "reference");
  const std::vector<Matrix4> estimate_poses = finite_poses(estimate, "estimate");
  eval::AlignmentOptions options;
  options.method = method_named(method);
  options.num_poses = pairs_to_align(n, "n");
  eval::Alignment alignment;
  {
    py::gil_scoped_release release;  // the arrays were read above, with the GIL
    alignment = eval::align(reference_poses, estimate_poses, options);
  }
  raise_if_failed(alignment.outcome);
  return alignment;
}

py::tuple umeyama_arrays(const DoubleArray& x, const DoubleArray& y, bool with_scale) {
  const Eigen::MatrixXd x_points = points_matrix(x, "x");
  const Eigen::MatrixXd y_points = points_matrix(y, "y");
  if (x_points.rows() != y_points.rows() || x_points.cols() != y_points.cols()) {
    throw_value_error("x and y must have the same shape, found " + shape_text(x) + " and " + shape_text(y));
  }
  const eval::UmeyamaResult result = eval::umeyama(x_points, y_points, with_scale);
  raise_if_failed(result.outcome);
  return py::make_tuple(matrix_array(result.R), column_array(result.t), result.scale);
}

eval::ApeResult ape(const eval::MatrixTrajectory& reference, const eval::MatrixTrajectory& estimate,
                    const std::string& pose_relation, bool align, bool correct_scale, bool align_origin,
                    std::int64_t n_to_align, double t_max_diff, double t_offset, bool by_index) {
  eval::ApeOptions options;
  options.relation = relation_named(pose_relation);
  options.alignment = alignment_options(align, correct_scale, align_origin, n_to_align);
  options.association = association_options(t_max_diff, t_offset, by_index);
  eval::ApeResult result = eval::evaluate_ape(reference, estimate, options);
  raise_if_failed(result.outcome);
  return result;
}

eval::RpeResult rpe(const eval::MatrixTrajectory& reference, const eval::MatrixTrajectory& estimate,
                    const std::string& pose_relation, double delta, const std::string& delta_unit, bool all_pairs,
                    double rel_delta_tol, bool pairs_from_reference, bool align, bool correct_scale,
                    bool align_origin, std::int64_t n_to_align, double t_max_diff, double t_offset, bool by_index) {
  eval::RpeOptions options;
  options.relation = relation_named(pose_relation);
  options.delta = delta;
  options.delta_unit = delta_unit_named(delta_unit);
  options.all_pairs = all_pairs;
  options.relative_delta_tolerance = rel_delta_tol;
  options.pairs_from_reference = pairs_from_reference;
  options.alignment = alignment_options(align, correct_scale, align_origin, n_to_align);
  options.association = association_options(t_max_diff, t_offset, by_index);
  // evaluate_rpe validates the options itself and reports every problem (kInvalidOptions).
  eval::RpeResult result = eval::evaluate_rpe(reference, estimate, options);
  raise_if_failed(result.outcome);
  return result;
}

eval::KittiResult kitti_metric(const eval::MatrixTrajectory& ground_truth, const eval::MatrixTrajectory& result,
                               const DoubleArray& lengths_m, std::int64_t step_frames, double frame_period_s,
                               double t_max_diff, double t_offset, bool by_index) {
  if (lengths_m.ndim() != 1) throw_value_error("lengths_m: expected a 1-D array, found " + shape_text(lengths_m));
  if (step_frames < 1) throw_value_error("step_frames must be >= 1, found " + std::to_string(step_frames));
  eval::KittiOptions options;
  options.lengths_m.assign(lengths_m.data(), lengths_m.data() + lengths_m.size());
  options.step_frames = static_cast<std::size_t>(step_frames);
  options.frame_period_s = frame_period_s;
  options.association = association_options(t_max_diff, t_offset, by_index);
  eval::KittiResult kitti;
  {
    // Released here, not by call_guard: lengths_m is a numpy array, read above with the GIL.
    py::gil_scoped_release release;
    kitti = eval::evaluate_kitti(ground_truth, result, options);
  }
  raise_if_failed(kitti.outcome);
  return kitti;
}

// ---------------------------------------------------------------------------------------------
// Classes

std::string number_text(double value) {
  std::ostringstream out;
  out << std::setprecision(6) << value;
  return out.str();
}

void bind_alignment(py::module_& m) {
  py::class_<eval::Alignment>(m, "Alignment",
                              "How an estimate was moved onto its reference: p_reference = scale * R @ p_estimate + t "
                              "(Umeyama 1991 as evo's umeyama_alignment, or evo's align_origin).")
      .def_property_readonly(
          "method", [](const eval::Alignment& a) { return std::string(method_name(a.method)); },
          "'se3' (evo -a), 'sim3' (-as), 'se2' (cairn's planar variant), 'origin' (--align_origin) or 'none'.")
      .def_property_readonly(
          "R", [](const eval::Alignment& a) { return matrix_array(a.R); },
          "Rotation, 3 x 3 float64 (an exact rotation).")
      .def_property_readonly(
          "t", [](const eval::Alignment& a) { return column_array(a.t); }, "Translation, shape (3,), metres.")
      .def_readonly("scale", &eval::Alignment::scale, "Scale factor; 1.0 unless 'sim3'.")
      .def_property_readonly(
          "matrix", [](const eval::Alignment& a) { return matrix_array(similarity_matrix(a)); },
          "[[scale * R, t], [0, 0, 0, 1]], 4 x 4 float64: evo's alignment_transformation (lie_algebra.sim3).")
      .def_readonly("pairs_used", &eval::Alignment::pairs_used, "Pose pairs the alignment was estimated from.")
      .def("apply", &apply_alignment, py::arg("poses"),
           "The poses (N x 4 x 4, or one 4 x 4) moved into the reference frame: rotation R @ R_pose, position "
           "scale * R @ p + t (evo's scale() then transform(); the rotation block is not scaled).")
      .def("__repr__", [](const eval::Alignment& a) {
        return "Alignment(method='" + std::string(method_name(a.method)) + "', scale=" + number_text(a.scale) +
               ", pairs_used=" + std::to_string(a.pairs_used) + ")";
      });
}

void bind_association(py::module_& m) {
  py::class_<eval::Association>(m, "Association",
                                "Which reference pose pairs with which estimated pose (evo's "
                                "sync.associate_trajectories, or by index without timestamps).")
      .def_property_readonly(
          "reference_indices", [](const eval::Association& a) { return index_array(a.reference_indices); },
          "Index into the reference of each pair, int64 array.")
      .def_property_readonly(
          "estimate_indices", [](const eval::Association& a) { return index_array(a.estimate_indices); },
          "Index into the estimate of each pair, int64 array.")
      .def_readonly("by_time", &eval::Association::by_time, "True when paired by timestamps, False when by index.")
      .def_readonly("max_pairs", &eval::Association::max_pairs,
                    "Poses of the shorter trajectory: the most pairs possible.")
      .def_property_readonly("size", &eval::Association::size, "Number of pairs.")
      .def("__len__", &eval::Association::size)
      .def("__repr__", [](const eval::Association& a) {
        return "Association(pairs=" + std::to_string(a.size()) + ", max_pairs=" + std::to_string(a.max_pairs) +
               ", by_time=" + (a.by_time ? "True" : "False") + ")";
      });
}

// The members APE and RPE results share.
template <class Result>
void add_pose_error_members(py::class_<Result>& c) {
  c.def_property_readonly(
       "errors", [](const Result& r) { return vector_to_array(r.errors); }, "Error of each pair, float64 array.")
      .def_property_readonly(
          "statistics", [](const Result& r) { return statistics_dict(r.statistics); },
          "evo's statistics of errors: dict with rmse, mean, median, std (population), min, max, sse, and count.")
      .def_property_readonly(
          "reference", [](const Result& r) { return poses_to_array(r.reference); },
          "The paired reference poses, N x 4 x 4 float64.")
      .def_property_readonly(
          "estimate", [](const Result& r) { return poses_to_array(r.estimate); },
          "The paired estimated poses after the alignment, N x 4 x 4 float64.")
      .def_readonly("alignment", &Result::alignment, "The Alignment applied to the estimate (method 'none' if none).")
      .def_readonly("association", &Result::association, "How the poses were paired.")
      .def_property_readonly(
          "pose_relation", [](const Result& r) { return std::string(eval::to_string(r.relation)); },
          "What was measured, evo's -r name: 'trans_part', 'angle_rad', 'angle_deg', 'rot_part' or 'full'.")
      .def_property_readonly(
          "unit", [](const Result& r) { return std::string(eval::unit_of(r.relation)); },
          "Unit of the errors: 'm', 'rad', 'deg', or '' (dimensionless).");
}

template <class Result>
std::string result_repr(const char* name, const Result& r) {
  return std::string(name) + "(pose_relation='" + std::string(eval::to_string(r.relation)) +
         "', count=" + std::to_string(r.statistics.count) + ", rmse=" + number_text(r.statistics.rmse) +
         (eval::unit_of(r.relation).empty() ? "" : " " + std::string(eval::unit_of(r.relation))) + ")";
}

void bind_ape_result(py::module_& m) {
  py::class_<eval::ApeResult> c(m, "ApeResult", "Absolute pose error per pose pair, as evo's APE metric (evo_ape).");
  add_pose_error_members(c);
  c.def_property_readonly(
       "times", [](const eval::ApeResult& r) { return vector_to_array(r.time_s); },
       "Time of each pair, seconds since the first paired reference stamp (the pair index without stamps).")
      .def("__repr__", [](const eval::ApeResult& r) { return result_repr("ApeResult", r); });
}

std::vector<double> pair_end_times(const eval::RpeResult& r) {
  std::vector<double> times;
  times.reserve(r.pairs.size());
  for (const auto& pair : r.pairs) times.push_back(r.time_s[pair.second]);
  return times;
}

void bind_rpe_result(py::module_& m) {
  py::class_<eval::RpeResult> c(m, "RpeResult", "Relative pose error per index pair, as evo's RPE metric (evo_rpe).");
  add_pose_error_members(c);
  c.def_property_readonly(
       "pairs", [](const eval::RpeResult& r) { return pairs_array(r.pairs); },
       "Index pairs (i, j) into reference/estimate, N x 2 int64; errors[k] belongs to pairs[k].")
      .def_property_readonly(
          "times", [](const eval::RpeResult& r) { return vector_to_array(pair_end_times(r)); },
          "Time of each pair's second pose j (evo's delta_ids), seconds since the first paired reference stamp "
          "(the pose index without stamps).")
      .def_property_readonly(
          "pose_times", [](const eval::RpeResult& r) { return vector_to_array(r.time_s); },
          "Time of every paired pose (reference/estimate rows), as times.")
      .def("__repr__", [](const eval::RpeResult& r) { return result_repr("RpeResult", r); });
}

py::dict segments_dict(const std::vector<eval::KittiSegment>& segments) {
  std::vector<std::size_t> first;
  std::vector<std::size_t> last;
  std::vector<double> length;
  std::vector<double> r_err;
  std::vector<double> t_err;
  std::vector<double> speed;
  for (const eval::KittiSegment& s : segments) {
    first.push_back(s.first_frame);
    last.push_back(s.last_frame);
    length.push_back(s.length_m);
    r_err.push_back(s.rotation_error_rad_per_m);
    t_err.push_back(s.translation_error_m_per_m);
    speed.push_back(s.speed_m_per_s);
  }
  py::dict d;
  d["first_frame"] = index_array(first);
  d["last_frame"] = index_array(last);
  d["length_m"] = vector_to_array(length);
  d["rotation_error_rad_per_m"] = vector_to_array(r_err);
  d["translation_error_m_per_m"] = vector_to_array(t_err);
  d["speed_m_per_s"] = vector_to_array(speed);
  return d;
}

py::dict per_length_dict(const std::vector<eval::KittiLengthError>& per_length) {
  std::vector<double> length;
  std::vector<std::size_t> count;
  std::vector<double> t_err;
  std::vector<double> r_err;
  py::array_t<bool> reported(static_cast<py::ssize_t>(per_length.size()));
  bool* flag = reported.mutable_data();
  for (const eval::KittiLengthError& e : per_length) {
    length.push_back(e.length_m);
    count.push_back(e.segments);
    t_err.push_back(e.translation_error_m_per_m);
    r_err.push_back(e.rotation_error_rad_per_m);
    *flag++ = e.reported_by_devkit;
  }
  py::dict d;
  d["length_m"] = vector_to_array(length);
  d["segments"] = index_array(count);
  d["translation_error_m_per_m"] = vector_to_array(t_err);
  d["rotation_error_rad_per_m"] = vector_to_array(r_err);
  d["reported_by_devkit"] = reported;
  return d;
}

void bind_kitti_result(py::module_& m) {
  py::class_<eval::KittiResult>(m, "KittiResult",
                                "The KITTI odometry metric exactly as the official devkit (evaluate_odometry.cpp) "
                                "computes it: segments of 100..800 m, errors per metre.")
      .def_property_readonly(
          "segments", [](const eval::KittiResult& r) { return segments_dict(r.segments); },
          "The devkit's errors/NN.txt as a dict of arrays: first_frame, last_frame (int64), length_m, "
          "rotation_error_rad_per_m, translation_error_m_per_m, speed_m_per_s.")
      .def_property_readonly(
          "per_length", [](const eval::KittiResult& r) { return per_length_dict(r.per_length); },
          "Mean errors per nominal length (the devkit's NN_tl.txt / NN_rl.txt) as a dict of arrays: length_m, "
          "segments, translation_error_m_per_m, rotation_error_rad_per_m, reported_by_devkit (>= 3 segments).")
      .def_readonly("translation_error_m_per_m", &eval::KittiResult::translation_error_m_per_m,
                    "t_err of the devkit's stats.txt: mean over all segments, m/m.")
      .def_readonly("rotation_error_rad_per_m", &eval::KittiResult::rotation_error_rad_per_m,
                    "r_err of the devkit's stats.txt: mean over all segments, rad/m.")
      .def_property_readonly("translation_error_percent", &eval::KittiResult::translation_error_percent,
                             "t_err in %, as the KITTI benchmark table.")
      .def_property_readonly("rotation_error_deg_per_m", &eval::KittiResult::rotation_error_deg_per_m,
                             "r_err in deg/m, as the KITTI benchmark table.")
      .def_property_readonly("rotation_error_deg_per_100m", &eval::KittiResult::rotation_error_deg_per_100m,
                             "r_err in deg/100 m.")
      .def_property_readonly(
          "path_length_m", [](const eval::KittiResult& r) { return vector_to_array(r.path_length_m); },
          "Ground-truth path length at each paired frame, metres (accumulated in float, as the devkit).")
      .def_property_readonly(
          "reference", [](const eval::KittiResult& r) { return poses_to_array(r.reference); },
          "The paired ground-truth poses, N x 4 x 4 float64.")
      .def_property_readonly(
          "estimate", [](const eval::KittiResult& r) { return poses_to_array(r.estimate); },
          "The paired result poses, N x 4 x 4 float64 (never aligned: the metric is relative).")
      .def_readonly("association", &eval::KittiResult::association, "How the poses were paired.")
      .def("__repr__", [](const eval::KittiResult& r) {
        return "KittiResult(segments=" + std::to_string(r.segments.size()) +
               ", t_err=" + number_text(r.translation_error_percent()) +
               " %, r_err=" + number_text(r.rotation_error_deg_per_100m()) + " deg/100m)";
      });
}

// ---------------------------------------------------------------------------------------------
// Functions

constexpr const char* kApeDoc =
    "Absolute pose error of estimate against reference, as evo_ape / evo.main_ape.ape: associate (by time, or by "
    "index without stamps), align, then the error of each pair under pose_relation, and evo's statistics.\n\n"
    "pose_relation: evo's -r: 'trans_part' (m, the ATE), 'angle_rad', 'angle_deg', 'rot_part', 'full'.\n"
    "align: SE(3) Umeyama alignment (evo -a); with correct_scale, Sim(3) (evo -as).\n"
    "align_origin: move the first estimated pose onto the first reference pose (evo --align_origin).\n"
    "n_to_align: align on the first n pairs only; -1 = all (evo --n_to_align).\n"
    "t_max_diff, t_offset: association tolerance and estimate time offset, seconds (evo --t_max_diff, "
    "--t_offset).\n"
    "by_index: pair by index even with timestamps (equal lengths needed; no evo flag).\n\n"
    "Raises ValueError (with cairn's message) for no common stamps, mismatched lengths, NaN, unsorted stamps, a "
    "degenerate alignment or an unknown name. Runs without the GIL.";

constexpr const char* kRpeDoc =
    "Relative pose error, as evo_rpe / evo.main_rpe.rpe: after association and optional alignment, index pairs "
    "(i, j) delta apart on the estimate, and the error of (Q_i^-1 Q_j)^-1 (P_i^-1 P_j) under pose_relation.\n\n"
    "delta, delta_unit: pair distance in 'f' frames (a whole number) or 'm' metres of path (evo -d, -u).\n"
    "all_pairs: every overlapping pair instead of consecutive ones (evo --all_pairs).\n"
    "rel_delta_tol: with metres and all_pairs, accept |path - delta| <= delta * rel_delta_tol (evo's "
    "rel_delta_tol).\n"
    "pairs_from_reference: choose the pairs on the reference's path (evo --pairs_from_reference).\n"
    "The other keywords are those of ape(). Raises ValueError as ape() does, and when delta selects no pair.";

constexpr const char* kKittiDoc =
    "The KITTI odometry metric as the official devkit computes it (evaluate_odometry.cpp): from every step_frames-th "
    "frame, segments of each length in lengths_m (default 100, 200, ..., 800) along the ground-truth path; errors "
    "per metre of nominal length. "
    "Poses pair by index (equal lengths), or by time when both trajectories have stamps (t_max_diff, t_offset, "
    "by_index as for ape()). frame_period_s only enters the speeds. Raises ValueError for bad options, mismatched "
    "lengths, or a ground truth shorter than the shortest length. Runs without the GIL.";

constexpr const char* kAlignDoc =
    "The alignment of estimate onto reference (N x 4 x 4 arrays paired by index): 'se3' Umeyama (evo -a), 'sim3' "
    "with scale (evo -as), 'se2' rotation about z and x-y translation, 'origin' first pose onto first pose (evo "
    "--align_origin). n: estimate from the first n pairs, -1 = all (evo's n). Returns an Alignment; "
    "Alignment.apply(poses) moves poses. Raises ValueError for wrong shapes, unequal lengths or degenerate positions.";

constexpr const char* kUmeyamaDoc =
    "Umeyama's least-squares similarity (IEEE PAMI 1991), as evo.core.geometry.umeyama_alignment: x and y are "
    "m x n arrays of n points (m = 2 or 3, columns are points); returns (R, t, c) with y ~ c R x + t (c = 1.0 "
    "without with_scale). Raises ValueError for wrong shapes or degenerate (coincident, collinear) points.";

void bind_functions(py::module_& m) {
  using Release = py::call_guard<py::gil_scoped_release>;
  m.def("ape", &ape, Release(), kApeDoc, py::arg("reference"), py::arg("estimate"), py::kw_only(),
        py::arg("pose_relation") = "trans_part", py::arg("align") = false, py::arg("correct_scale") = false,
        py::arg("align_origin") = false, py::arg("n_to_align") = -1, py::arg("t_max_diff") = 0.01,
        py::arg("t_offset") = 0.0, py::arg("by_index") = false);
  m.def("rpe", &rpe, Release(), kRpeDoc, py::arg("reference"), py::arg("estimate"), py::kw_only(),
        py::arg("pose_relation") = "trans_part", py::arg("delta") = 1.0, py::arg("delta_unit") = "f",
        py::arg("all_pairs") = false, py::arg("rel_delta_tol") = 0.1, py::arg("pairs_from_reference") = false,
        py::arg("align") = false, py::arg("correct_scale") = false, py::arg("align_origin") = false,
        py::arg("n_to_align") = -1, py::arg("t_max_diff") = 0.01, py::arg("t_offset") = 0.0,
        py::arg("by_index") = false);
  const eval::KittiOptions kitti_defaults;
  m.def("kitti_metric", &kitti_metric, kKittiDoc, py::arg("ground_truth"), py::arg("result"), py::kw_only(),
        py::arg_v("lengths_m", vector_to_array(kitti_defaults.lengths_m), "[100.0, 200.0, ..., 800.0]"),
        py::arg("step_frames") = static_cast<std::int64_t>(kitti_defaults.step_frames),
        py::arg("frame_period_s") = kitti_defaults.frame_period_s, py::arg("t_max_diff") = 0.01,
        py::arg("t_offset") = 0.0, py::arg("by_index") = false);
  m.def("align", &align_arrays, kAlignDoc, py::arg("reference"), py::arg("estimate"), py::arg("method") = "se3",
        py::arg("n") = -1);
  m.def("umeyama", &umeyama_arrays, kUmeyamaDoc, py::arg("x"), py::arg("y"), py::arg("with_scale") = false);
}

}  // namespace

void bind_eval(py::module_& m) {
  // Classes first, so that the functions' generated signatures name them.
  bind_alignment(m);
  bind_association(m);
  bind_ape_result(m);
  bind_rpe_result(m);
  bind_kitti_result(m);
  bind_functions(m);
}

}  // namespace cairn::python
