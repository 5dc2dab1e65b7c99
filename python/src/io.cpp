// cairn.Trajectory and the readers and writers of trajectories, pose graphs, point clouds and
// bags (io/, bag/). Every reader raises cairn.ParseError naming the file and line on bad input;
// the writers replace a file whole or not at all (io/output_file.hpp).

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <string>
#include <variant>

#include "bindings.hpp"
#include "cairn/bag/bag.hpp"
#include "cairn/bag/bag_info.hpp"
#include "cairn/bag/point_cloud_stream.hpp"
#include "cairn/bag/pose_topic.hpp"
#include "cairn/eval/matrix_trajectory.hpp"
#include "cairn/io/file_format.hpp"
#include "cairn/io/graph_io.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/point_cloud.hpp"
#include "cairn/io/trajectory.hpp"

namespace cairn::python {
namespace {

using eval::MatrixTrajectory;

/// cairn.Trajectory: the matrices the metrics use (eval::MatrixTrajectory, its base, which the
/// evaluation functions take) and, for a trajectory read from TUM, EuRoC or a bag, the poses as
/// read (unit quaternions), so that writing it back gives the CLI's bytes: a rotation taken from
/// its matrix again may differ from the read quaternion in the last bit.
struct TrajectoryObject : MatrixTrajectory {
  TrajectoryObject() = default;
  explicit TrajectoryObject(MatrixTrajectory matrices) : MatrixTrajectory(std::move(matrices)) {}
  explicit TrajectoryObject(const io::Trajectory& read) : MatrixTrajectory(read), as_read(read.poses) {}
  std::vector<core::SE3> as_read;  ///< empty when made from matrices
};

// ---------------------------------------------------------------------------------------------
// Trajectories

/// The format named by `name`, or else told by the file's name or first record (as `cairn eval`).
io::FileFormat trajectory_format(const std::string& path, const std::optional<std::string>& name) {
  std::optional<io::FileFormat> format = name ? io::file_format_from_name(*name) : io::detect_file_format(path);
  if (!format && name) throw_value_error("format: expected 'tum', 'kitti' or 'euroc', found '" + *name + "'");
  if (!format) {
    throw io::ParseError(path, 0, "cannot tell the trajectory format from the name or the first record: give format=");
  }
  if (io::kind_of(*format) != io::FileKind::kTrajectory) {
    throw io::ParseError(path, 0, "not a trajectory format: " + std::string(io::to_string(*format)));
  }
  return *format;
}

/// KITTI poses keep their 3 x 4 blocks as written (the metrics compare them with evo's and the
/// devkit's unprojected matrices, eval/matrix_trajectory.hpp); TUM and EuRoC go through SE3.
TrajectoryObject read_trajectory(const std::string& path, const std::optional<std::string>& format_name,
                                 const std::string& times) {
  const io::FileFormat format = trajectory_format(path, format_name);
  if (!times.empty() && format != io::FileFormat::kKitti) {
    throw_value_error("times= goes with a KITTI trajectory, and " + path + " is " + std::string(io::to_string(format)));
  }
  if (format == io::FileFormat::kKitti) return TrajectoryObject(eval::read_kitti_matrices(path, times));
  return TrajectoryObject(format == io::FileFormat::kTum ? io::read_tum(path) : io::read_euroc(path));
}

io::Trajectory to_se3_trajectory(const TrajectoryObject& trajectory) {
  io::Trajectory out;
  out.stamps = trajectory.stamps;
  if (trajectory.as_read.size() == trajectory.poses.size()) {
    out.poses = trajectory.as_read;
    return out;
  }
  out.poses.reserve(trajectory.poses.size());
  for (const Matrix4& T : trajectory.poses) out.poses.push_back(core::SE3::from_matrix(T));
  return out;
}

void write_trajectory(const std::string& path, const TrajectoryObject& trajectory,
                      const std::optional<std::string>& format_name, const std::string& times) {
  // The format named, or else the extension's (the file does not exist yet: no content to read).
  const std::optional<io::FileFormat> by_extension = io::format_from_extension(path);
  const io::FileFormat format =
      format_name || !by_extension ? trajectory_format(path, format_name)
                                   : trajectory_format(path, std::string(io::to_string(*by_extension)));
  const io::Trajectory poses = to_se3_trajectory(trajectory);
  if (format == io::FileFormat::kKitti) return io::write_kitti(path, poses, times);
  if (!times.empty()) throw_value_error("times= goes with KITTI output; " + path + " holds its times");
  if (!poses.has_stamps()) throw_value_error(path + ": TUM and EuRoC lines need times; the trajectory has none");
  if (format == io::FileFormat::kTum) return io::write_tum(path, poses);
  io::write_euroc(path, poses);
}

TrajectoryObject make_trajectory(const DoubleArray& poses, const std::optional<DoubleArray>& times,
                                 const std::optional<py::array_t<std::int64_t>>& stamps_ns) {
  TrajectoryObject t;
  t.poses = poses_from_array(poses, "poses");
  if (times && stamps_ns) throw_value_error("give times= (seconds) or stamps_ns=, not both");
  if (times) {
    if (times->ndim() != 1 || static_cast<std::size_t>(times->shape(0)) != t.poses.size()) {
      throw_value_error("times: expected one time (s) per pose");
    }
    for (py::ssize_t k = 0; k < times->shape(0); ++k) {
      const double s = times->at(k);
      if (!std::isfinite(s) || std::abs(s) > 9.2e9) throw_value_error("times[" + std::to_string(k) + "] is not a usable time");
      t.stamps.push_back(core::Timestamp::from_seconds(s));
    }
  }
  if (stamps_ns) {
    if (stamps_ns->ndim() != 1 || static_cast<std::size_t>(stamps_ns->shape(0)) != t.poses.size()) {
      throw_value_error("stamps_ns: expected one stamp (ns) per pose");
    }
    for (py::ssize_t k = 0; k < stamps_ns->shape(0); ++k) t.stamps.push_back(core::Timestamp::from_nanoseconds(stamps_ns->at(k)));
  }
  return t;
}

void bind_trajectory(py::module_& m) {
  // The base, which the evaluation functions (eval.cpp) take, and cairn.Trajectory derived from it.
  py::class_<MatrixTrajectory>(m, "_MatrixTrajectory", "The matrices of a cairn.Trajectory (its base class).");
  py::class_<TrajectoryObject, MatrixTrajectory>(m, "Trajectory",
                               "Poses T_world_body (N x 4 x 4) with optional times, as read from TUM, KITTI or EuRoC "
                               "files or made from arrays.")
      .def(py::init(&make_trajectory), py::arg("poses"), py::arg("times") = py::none(),
           py::arg("stamps_ns") = py::none(),
           "From an N x 4 x 4 array and, optionally, times in seconds or integer nanoseconds.")
      .def_property_readonly("poses", [](const MatrixTrajectory& t) { return poses_to_array(t.poses); },
                             "N x 4 x 4 float64 (a copy).")
      .def_property_readonly("stamps_ns",
                             [](const MatrixTrajectory& t) {
                               py::array_t<std::int64_t> out(static_cast<py::ssize_t>(t.stamps.size()));
                               for (std::size_t k = 0; k < t.stamps.size(); ++k) out.mutable_at(static_cast<py::ssize_t>(k)) = t.stamps[k].nanoseconds();
                               return out;
                             },
                             "The stamps in integer nanoseconds (empty without times).")
      .def_property_readonly("times",
                             [](const MatrixTrajectory& t) {
                               std::vector<double> s;
                               for (const auto& stamp : t.stamps) s.push_back(stamp.seconds());
                               return vector_to_array(s);
                             },
                             "The stamps in seconds (empty without times).")
      .def_property_readonly("positions",
                             [](const MatrixTrajectory& t) {
                               std::vector<Eigen::Vector3d> p;
                               for (const Matrix4& T : t.poses) p.push_back(T.block<3, 1>(0, 3));
                               return points_to_array(p);
                             },
                             "N x 3: the translations.")
      .def("has_times", &MatrixTrajectory::has_stamps)
      .def("__len__", &MatrixTrajectory::size)
      .def("__repr__", [](const MatrixTrajectory& t) {
        return "Trajectory(" + std::to_string(t.size()) + " poses" + (t.has_stamps() ? ", with times)" : ")");
      });
  m.def("read_trajectory", &read_trajectory, py::arg("path"), py::arg("format") = py::none(), py::arg("times") = "",
        "Reads a TUM, KITTI or EuRoC trajectory (format from the name or the first record unless given); times= a "
        "KITTI times file. Raises cairn.ParseError naming the file and line.");
  m.def("write_trajectory", &write_trajectory, py::arg("path"), py::arg("trajectory"), py::arg("format") = py::none(),
        py::arg("times") = "",
        "Writes a TUM, KITTI or EuRoC trajectory as `cairn` does (format from the extension unless given; times= a "
        "KITTI times file). The file is replaced whole or not at all.");
}

// ---------------------------------------------------------------------------------------------
// Pose graphs

using Graph = PoseGraphObject;

template <class Group>
py::array_t<double> group_matrices(const std::vector<Group>& poses) {
  constexpr int n = Group::kDoF == 3 ? 3 : 4;
  py::array_t<double> out({static_cast<py::ssize_t>(poses.size()), py::ssize_t{n}, py::ssize_t{n}});
  auto view = out.mutable_unchecked<3>();
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const auto M = poses[k].matrix();
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < n; ++c) view(static_cast<py::ssize_t>(k), r, c) = M(r, c);
    }
  }
  return out;
}

py::array_t<double> vertex_poses(const Graph& g) {
  return std::visit([](const auto& graph) {
    using Group = std::decay_t<decltype(graph.vertices.front().T_world_pose)>;
    std::vector<Group> poses;
    for (const auto& v : graph.vertices) poses.push_back(v.T_world_pose);
    return group_matrices(poses);
  }, g.graph);
}

py::array_t<double> edge_measurements(const Graph& g) {
  return std::visit([](const auto& graph) {
    using Group = std::decay_t<decltype(graph.edges.front().T_from_to)>;
    std::vector<Group> poses;
    for (const auto& e : graph.edges) poses.push_back(e.T_from_to);
    return group_matrices(poses);
  }, g.graph);
}

py::array_t<double> edge_information(const Graph& g) {
  return std::visit([](const auto& graph) {
    const py::ssize_t d = graph.kDimension == 2 ? 3 : 6;
    py::array_t<double> out({static_cast<py::ssize_t>(graph.edges.size()), d, d});
    auto view = out.mutable_unchecked<3>();
    for (std::size_t k = 0; k < graph.edges.size(); ++k) {
      for (py::ssize_t r = 0; r < d; ++r) {
        for (py::ssize_t c = 0; c < d; ++c) view(static_cast<py::ssize_t>(k), r, c) = graph.edges[k].information(r, c);
      }
    }
    return out;
  }, g.graph);
}

py::array_t<std::int64_t> vertex_ids(const Graph& g) {
  return std::visit([](const auto& graph) {
    py::array_t<std::int64_t> out(static_cast<py::ssize_t>(graph.vertices.size()));
    for (std::size_t k = 0; k < graph.vertices.size(); ++k) out.mutable_at(static_cast<py::ssize_t>(k)) = graph.vertices[k].id;
    return out;
  }, g.graph);
}

py::array_t<std::int64_t> edge_ids(const Graph& g) {
  return std::visit([](const auto& graph) {
    py::array_t<std::int64_t> out({static_cast<py::ssize_t>(graph.edges.size()), py::ssize_t{2}});
    auto view = out.mutable_unchecked<2>();
    for (std::size_t k = 0; k < graph.edges.size(); ++k) {
      view(static_cast<py::ssize_t>(k), 0) = graph.edges[k].from;
      view(static_cast<py::ssize_t>(k), 1) = graph.edges[k].to;
    }
    return out;
  }, g.graph);
}

Graph read_graph(const std::string& path, const std::optional<std::string>& format, const std::string& information) {
  io::GraphReadOptions options;
  if (format) {
    options.format = io::graph_format_from_name(*format);
    if (!options.format) throw_value_error("format: expected 'g2o' or 'toro', found '" + *format + "'");
  }
  if (information == "keep") options.information_policy = io::InformationPolicy::kKeep;
  else if (information == "reject") options.information_policy = io::InformationPolicy::kReject;
  else if (information != "project") throw_value_error("information: expected 'project', 'keep' or 'reject'");
  io::GraphFile file = io::read_graph(path, options);
  return Graph{std::move(file.graph), std::move(file.report.warnings)};
}

void write_graph(const std::string& path, const Graph& graph, const std::optional<std::string>& format) {
  io::GraphFormat out = io::GraphFormat::kG2o;
  if (format) {
    const auto named = io::graph_format_from_name(*format);
    if (!named) throw_value_error("format: expected 'g2o' or 'toro', found '" + *format + "'");
    out = *named;
  } else if (io::format_from_extension(path) == io::FileFormat::kToro) {
    out = io::GraphFormat::kToro;
  }
  io::write_graph(path, graph.graph, out);
}

void bind_graph(py::module_& m) {
  py::class_<Graph>(m, "PoseGraph", "A 2-D or 3-D pose graph (g2o or TORO). Poses are homogeneous matrices: "
                                    "N x 3 x 3 in 2-D, N x 4 x 4 in 3-D.")
      .def_property_readonly("dimension", [](const Graph& g) { return io::dimension(g.graph); }, "2 or 3.")
      .def_property_readonly("ids", &vertex_ids, "The vertex ids, in file order.")
      .def_property_readonly("poses", &vertex_poses, "T_world_pose of every vertex, in the order of ids.")
      .def_property_readonly("edges", &edge_ids, "M x 2: (from, to) ids of every edge.")
      .def_property_readonly("measurements", &edge_measurements, "T_from_to of every edge.")
      .def_property_readonly("information", &edge_information, "The information matrix of every edge "
                                                               "(translation first).")
      .def_property_readonly("fixed", [](const Graph& g) { return std::visit([](const auto& x) { return x.fixed; }, g.graph); },
                             "Ids of the fixed vertices.")
      .def_readonly("warnings", &Graph::warnings, "What the reader repaired or ignored (as `cairn` prints them).")
      .def("__repr__", [](const Graph& g) {
        return std::visit([&](const auto& x) {
          return "PoseGraph(" + std::to_string(io::dimension(g.graph)) + "-D, " + std::to_string(x.vertices.size()) +
                 " poses, " + std::to_string(x.edges.size()) + " edges)";
        }, g.graph);
      });
  m.def("read_graph", &read_graph, py::arg("path"), py::arg("format") = py::none(), py::arg("information") = "project",
        "Reads a g2o or TORO pose graph (format from the name or content unless given). information: what to do with "
        "an indefinite information matrix: 'project' (nearest PSD, the default), 'keep', 'reject' (an error, the CLI's "
        "--strict). Raises cairn.ParseError naming the file and line.");
  m.def("write_graph", &write_graph, py::arg("path"), py::arg("graph"), py::arg("format") = py::none(),
        "Writes a pose graph as g2o (or TORO for .graph or format='toro'); replaced whole or not at all.");
}

// ---------------------------------------------------------------------------------------------
// Point clouds

/// A read-only numpy view of `values` that keeps `owner` (the Python object holding them) alive.
template <class T>
py::array view_of(const std::vector<T>& values, py::handle owner) {
  py::array_t<T> out(static_cast<py::ssize_t>(values.size()), values.data(), owner);
  py::detail::array_proxy(out.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return out;
}

template <class T>
std::vector<T> optional_column(const std::optional<py::array_t<T, py::array::c_style | py::array::forcecast>>& a,
                               std::size_t n, const char* what) {
  if (!a) return {};
  if (a->ndim() != 1 || static_cast<std::size_t>(a->shape(0)) != n) {
    throw_value_error(std::string(what) + ": expected one value per point (" + std::to_string(n) + ")");
  }
  return std::vector<T>(a->data(), a->data() + n);
}

io::PointCloud make_point_cloud(const FloatArray& points, const std::optional<FloatArray>& intensity,
                                const std::optional<FloatArray>& time_s,
                                const std::optional<py::array_t<std::uint16_t, py::array::c_style | py::array::forcecast>>& ring) {
  io::PointCloud cloud;
  cloud.points = points_from_array(points, "points");
  cloud.intensity = optional_column(intensity, cloud.size(), "intensity");
  cloud.time_s = optional_column(time_s, cloud.size(), "time_s");
  cloud.ring = optional_column(ring, cloud.size(), "ring");
  return cloud;
}

void write_point_cloud(const std::string& path, const io::PointCloud& cloud) {
  const auto dot = path.rfind('.');
  const std::string extension = dot == std::string::npos ? "" : path.substr(dot);
  if (extension != ".ply" && extension != ".pcd") throw_value_error(path + ": expected a .ply or .pcd name");
  io::OutputFile file(path);
  file.write([&](std::ostream& out) {
    if (extension == ".ply") io::write_ply(out, cloud.points);
    else io::write_pcd(out, cloud);
  });
  file.commit();
}

void bind_point_cloud(py::module_& m) {
  py::class_<io::PointCloud>(m, "PointCloud", "Points in the sensor frame (N x 3 float32, metres) with optional "
                                              "per-point intensity, time in the sweep (s) and ring. The arrays are "
                                              "read-only views into the cloud.")
      .def(py::init(&make_point_cloud), py::arg("points"), py::arg("intensity") = py::none(),
           py::arg("time_s") = py::none(), py::arg("ring") = py::none())
      .def_property_readonly("points", [](py::object self) {
        const auto& cloud = self.cast<const io::PointCloud&>();
        py::array_t<float> out({static_cast<py::ssize_t>(cloud.size()), py::ssize_t{3}},
                               cloud.points.empty() ? nullptr : cloud.points.front().data(), self);
        py::detail::array_proxy(out.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
        return out;
      })
      .def_property_readonly("intensity", [](py::object self) { return view_of(self.cast<const io::PointCloud&>().intensity, self); })
      .def_property_readonly("time_s", [](py::object self) { return view_of(self.cast<const io::PointCloud&>().time_s, self); })
      .def_property_readonly("ring", [](py::object self) { return view_of(self.cast<const io::PointCloud&>().ring, self); })
      .def("__len__", &io::PointCloud::size)
      .def("__repr__", [](const io::PointCloud& c) { return "PointCloud(" + std::to_string(c.size()) + " points)"; });
  m.def("read_point_cloud", [](const std::string& path) { return io::read_point_cloud(path); }, py::arg("path"),
        "Reads PCD (ascii, binary, binary_compressed), PLY or KITTI .bin, compressed or not (format from the bytes). "
        "Raises cairn.ParseError naming the file and byte offset or line.",
        py::call_guard<py::gil_scoped_release>());
  m.def("write_point_cloud", &write_point_cloud, py::arg("path"), py::arg("cloud"),
        "Writes binary PLY (x y z) or PCD (with the optional fields) by the extension; replaced whole or not at all.");
}

// ---------------------------------------------------------------------------------------------
// Bags

/// ROS 1 bags, rosbag2 (SQLite3, MCAP) and MCAP files: the topics, the point clouds of one
/// topic in order, and poses of an odometry/pose topic as a trajectory.
void bind_bag(py::module_& m) {
  m.def("bag_info", [](const std::string& path) { return json_to_python(bag::bag_info_json(bag::Bag::open(path))); },
        py::arg("path"), "What `cairn info BAG --json` prints: format, files, topics with types and counts.");
  m.def("read_bag_poses", [](const std::string& path, const std::string& topic) {
          return TrajectoryObject(bag::read_pose_topic(path, topic));
        }, py::arg("path"), py::arg("topic"),
        "The poses of a nav_msgs/Odometry, geometry_msgs/PoseStamped (...) topic as a Trajectory.");
  py::class_<bag::PointCloudStream>(m, "BagPointClouds",
                                    "The sensor_msgs/PointCloud2 messages of one topic of a bag, in order: iterate "
                                    "for (stamp_ns, PointCloud).")
      .def(py::init<const std::string&, const std::string&>(), py::arg("path"), py::arg("topic"))
      .def("__len__", &bag::PointCloudStream::size)
      .def("__iter__", [](py::object self) { return self; })
      .def("__next__", [](bag::PointCloudStream& stream) {
        io::PointCloud cloud;
        std::int64_t stamp_ns = 0;
        bool more = false;
        {
          py::gil_scoped_release release;
          more = stream.next(&cloud, &stamp_ns);
        }
        if (!more) throw py::stop_iteration();
        return py::make_tuple(stamp_ns, std::move(cloud));
      });
}

}  // namespace

void bind_io(py::module_& m) {
  bind_trajectory(m);
  bind_graph(m);
  bind_point_cloud(m);
  bind_bag(m);
}

}  // namespace cairn::python
