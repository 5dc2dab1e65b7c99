// cairn.optimize: one pose-graph optimisation (backend/pose_graph_job.hpp), with the options of
// `cairn optimize` as keywords and its report (backend/pose_graph_report.hpp) as the summary.
// The GIL is released during the job; Ctrl-C (SIGINT) stops it at the next iteration, as in the
// CLI, and raises KeyboardInterrupt.

#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include <optional>
#include <string>
#include <variant>

#include "bindings.hpp"
#include "cairn/backend/pose_graph_job.hpp"
#include "cairn/backend/pose_graph_report.hpp"
#include "cairn/io/graph_io.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::python {
namespace {

/// The keywords of cairn.optimize, with `cairn optimize`'s defaults (cli/optimize_flags.hpp).
struct OptimizeArguments {
  std::string init = "auto";
  std::string solver = "lm";
  std::string objective = "geodesic";
  std::string robust = "none";
  double robust_scale = 1.0;
  int max_iterations = 100;
  int threads = 0;
  bool certify = false;
  bool polish_geodesic = false;
  std::vector<std::int64_t> covariance;
  std::function<void(py::dict)> progress;
};

/// What cairn.optimize returns.
struct OptimizeResult {
  PoseGraphObject graph;
  py::object summary;  ///< the report's dict
  double chi2 = 0.0;
  double f_chordal = 0.0;
  std::optional<bool> certified;
};

template <class T>
T pick(const std::string& what, const std::string& value, std::initializer_list<std::pair<const char*, T>> choices) {
  std::string names;
  for (const auto& [name, choice] : choices) {
    if (value == name) return choice;
    names += (names.empty() ? "'" : ", '") + std::string(name) + "'";
  }
  throw_value_error(what + ": expected one of " + names + ", found '" + value + "'");
}

backend::PoseGraphJobOptions job_options(const OptimizeArguments& a) {
  using backend::Initialization;
  backend::PoseGraphJobOptions job;
  job.initialization = pick<std::optional<Initialization>>(
      "init", a.init,
      {{"auto", std::nullopt}, {"file", Initialization::kFile}, {"odometry", Initialization::kOdometry},
       {"chordal", Initialization::kChordal}});
  job.solver.algorithm = pick<backend::Algorithm>("solver", a.solver,
                              {{"lm", backend::Algorithm::kLevenbergMarquardt},
                               {"gn", backend::Algorithm::kGaussNewton},
                               {"dogleg", backend::Algorithm::kDogleg}});
  job.solver.objective = pick<backend::Objective>("objective", a.objective,
                              {{"geodesic", backend::Objective::kGeodesic}, {"chordal", backend::Objective::kChordal}});
  job.solver.kernel = pick<backend::RobustKernel>("robust", a.robust,
                           {{"none", backend::RobustKernel::kNone},
                            {"huber", backend::RobustKernel::kHuber},
                            {"cauchy", backend::RobustKernel::kCauchy},
                            {"geman-mcclure", backend::RobustKernel::kGemanMcClure},
                            {"gnc", backend::RobustKernel::kNone}});
  job.gnc = a.robust == "gnc";
  job.solver.kernel_scale = a.robust_scale;
  job.solver.max_iterations = a.max_iterations;
  job.solver.threads = a.threads;
  job.certify = a.certify;
  job.polish_geodesic = a.polish_geodesic;
  job.covariance_ids = a.covariance;
  if (std::string why; !job.is_valid(&why)) throw_value_error(why);
  return job;
}

/// Python callbacks from the solver: each takes the GIL. A pending signal (Ctrl-C) stops the
/// solve at the next iteration and stays set, to be raised when the job returns.
void add_python_callbacks(backend::PoseGraphJobOptions& job, const OptimizeArguments& a) {
  job.solver.should_stop = [] {
    py::gil_scoped_acquire gil;
    return PyErr_Occurred() != nullptr || PyErr_CheckSignals() != 0;
  };
  if (!a.progress) return;
  job.solver.progress = [progress = a.progress](const backend::IterationSummary& it) {
    py::gil_scoped_acquire gil;
    if (PyErr_Occurred() != nullptr) return;  // an earlier call raised: the solve is stopping
    py::dict d;
    d["iteration"] = it.iteration;
    d["cost"] = it.cost;
    d["cost_change"] = it.cost_change;
    d["gradient_max_norm"] = it.gradient_max_norm;
    d["step_norm"] = it.step_norm;
    d["lambda"] = it.lambda;
    d["step_accepted"] = it.step_accepted;
    d["iteration_s"] = it.iteration_s;
    try {
      progress(d);
    } catch (py::error_already_set& e) {
      e.restore();  // raised again when the job returns
    }
  };
}

template <class Group>
OptimizeResult run(const io::PoseGraphT<Group>& graph, const std::string& name, const backend::PoseGraphJobOptions& job) {
  std::optional<backend::PoseGraphJobResult<Group>> result;
  {
    py::gil_scoped_release release;
    result.emplace(backend::run_pose_graph_job(graph, name, job));
  }
  if (PyErr_Occurred() != nullptr) throw py::error_already_set();  // a signal, or an exception in progress
  const backend::PoseGraphJobSummary& s = result->summary;
  if (!s.is_solution_usable()) throw io::ParseError(name, 0, "the solve failed (" + s.solve.message + ")");
  OptimizeResult out;
  out.graph.graph = std::move(result->optimized);
  out.summary = json_to_python(backend::pose_graph_report_json(s, job));
  out.chi2 = s.final_chi2_geodesic;
  out.f_chordal = s.final_f_chordal;
  if (s.staircase) out.certified = s.staircase->certified;
  return out;
}

OptimizeResult optimize(const PoseGraphObject& graph, const std::string& name, const OptimizeArguments& arguments) {
  backend::PoseGraphJobOptions job = job_options(arguments);
  add_python_callbacks(job, arguments);
  return std::visit([&](const auto& g) { return run(g, name, job); }, graph.graph);
}

/// A path is read as `cairn optimize` reads it: the chordal objective reads only the diagonal
/// blocks, so the matrices are kept as written there.
OptimizeResult optimize_file(const std::string& path, const OptimizeArguments& arguments) {
  io::GraphReadOptions options;
  if (arguments.objective == "chordal") options.information_policy = io::InformationPolicy::kKeep;
  io::GraphFile file = io::read_graph(path, options);
  PoseGraphObject graph{std::move(file.graph), std::move(file.report.warnings)};
  return optimize(graph, path, arguments);
}

/// The keyword arguments shared by both overloads, in one place.
template <class GraphArgument, class F>
auto with_arguments(F f) {
  return [f](const GraphArgument& graph, const std::string& init, const std::string& solver, const std::string& objective,
             const std::string& robust, double robust_scale, int max_iterations, int threads, bool certify,
             bool polish_geodesic, const std::vector<std::int64_t>& covariance,
             const std::function<void(py::dict)>& progress) {
    return f(graph, OptimizeArguments{init, solver, objective, robust, robust_scale, max_iterations, threads, certify,
                                      polish_geodesic, covariance, progress});
  };
}

constexpr const char* kOptimizeDoc =
    "Optimises a pose graph (a cairn.PoseGraph, or a path read as `cairn optimize` reads it) as `cairn optimize` "
    "does: init 'auto' | 'file' | 'odometry' | 'chordal'; solver 'lm' | 'gn' | 'dogleg'; objective 'geodesic' "
    "(g2o's chi2) | 'chordal' (SE-Sync's f); robust 'none' | 'huber' | 'cauchy' | 'geman-mcclure' | 'gnc'; certify: "
    "SE-Sync's certificate (and the staircase); covariance: ids whose marginal covariance goes into the summary; "
    "progress: called with a dict per iteration. Returns an OptimizeResult; raises cairn.ParseError when the solve "
    "fails, KeyboardInterrupt on Ctrl-C.";

}  // namespace

void bind_backend(py::module_& m) {
  py::class_<OptimizeResult>(m, "OptimizeResult", "The optimised graph and the summary of cairn.optimize.")
      .def_readonly("graph", &OptimizeResult::graph, "The graph with its optimised poses (a cairn.PoseGraph).")
      .def_readonly("summary", &OptimizeResult::summary, "The report `cairn optimize --report` writes, as a dict.")
      .def_readonly("chi2", &OptimizeResult::chi2, "The final geodesic chi2 (g2o's).")
      .def_readonly("f_chordal", &OptimizeResult::f_chordal, "The final value of SE-Sync's chordal objective f.")
      .def_readonly("certified", &OptimizeResult::certified,
                    "With certify=True: whether the solution is certified globally optimal; else None.");
  auto keywords = [](py::module_& module, auto function, auto graph_argument, const char* first) {
    using GraphArgument = decltype(graph_argument);
    module.def("optimize", with_arguments<GraphArgument>(function), py::arg(first), py::kw_only(), py::arg("init") = "auto",
               py::arg("solver") = "lm", py::arg("objective") = "geodesic", py::arg("robust") = "none",
               py::arg("robust_scale") = 1.0, py::arg("max_iterations") = 100, py::arg("threads") = 0,
               py::arg("certify") = false, py::arg("polish_geodesic") = false,
               py::arg("covariance") = std::vector<std::int64_t>{}, py::arg("progress") = py::none(), kOptimizeDoc);
  };
  keywords(m, [](const PoseGraphObject& g, const OptimizeArguments& a) { return optimize(g, "<PoseGraph>", a); },
           PoseGraphObject{}, "graph");
  keywords(m, [](const std::string& path, const OptimizeArguments& a) { return optimize_file(path, a); },
           std::string{}, "graph");
}

}  // namespace cairn::python
