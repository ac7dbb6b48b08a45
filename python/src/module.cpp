// sphxr._sphxr: the pybind11 extension under the sphxr package (python/sphxr/__init__.py wraps it).
// docs/user/python.md describes the API. Arrays come out as NumPy arrays the module owns (copies: the
// solver's buffers change order every step). Errors are sphxr.Error with the one-line Status message;
// the GIL is released while the solver works, and Ctrl-C stops a long stepping call or a settle after
// the step in progress (KeyboardInterrupt). Numbers and file names are checked by app/run_arguments.h,
// as the command line checks them.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <stdexcept>

#include "run.h"
#include "sphxr/app/param_registry.h"
#include "sphxr/app/run_arguments.h"
#include "sphxr/app/state_file.h"
#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"
#include "sphxr/sim/openmp_wait.h"

namespace py = pybind11;

namespace sphxr::python {
namespace {

struct Error : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void Check(const Status& s) {
  if (!s) throw Error(app::ShownMessage(s.message()));
}

template <typename T>
py::array_t<T> Array(const std::vector<T>& v, std::vector<py::ssize_t> shape) {
  py::array_t<T> a(shape);
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

/// Runs `work` without the GIL; a Ctrl-C arriving meanwhile stops it after the step in progress
/// (KeyboardInterrupt afterwards, or whatever exception a signal handler raised).
Status Unlocked(const std::function<Status(const KeepGoing&)>& work) {
  bool interrupted = false;
  Status s;
  {
    py::gil_scoped_release release;
    s = work([&] {
      py::gil_scoped_acquire acquire;
      interrupted = PyErr_CheckSignals() != 0;
      return !interrupted;
    });
  }
  if (interrupted) throw py::error_already_set();
  return s;
}

std::unique_ptr<Run> Make(const RunOptions& options) {
  std::unique_ptr<Run> run;
  Check(Unlocked([&](const KeepGoing& go) { return Run::Create(options, &run, go); }));
  return run;
}

py::dict Parameters(const sim::SceneSetup& setup) {
  py::dict d;
  d["method"] = sim::SolverMethodName(setup.method);
  for (const app::ParamDesc& p : app::ParamRegistry()) {
    const double v = p.Get(setup);
    if (p.integer) {
      d[py::str(p.group == "solver" ? p.name : p.key)] = static_cast<long long>(v);
    } else {
      d[py::str(p.group == "solver" ? p.name : p.key)] = v;
    }
  }
  d["reuse.enabled"] = setup.reuse.enabled;
  return d;
}

py::dict ReadState(const std::string& path) {
  Check(app::CheckPathArgument("read_state", path));
  app::StateFile state;
  Status s;
  {
    py::gil_scoped_release release;
    s = app::ReadStateFile(path, &state);
  }
  Check(s);
  const py::ssize_t n = static_cast<py::ssize_t>(state.fluid.size());
  std::vector<float> position(3 * n), velocity(3 * n);
  for (py::ssize_t i = 0; i < n; ++i) {
    const sim::Vec4& p = state.fluid.position[i];
    const sim::Vec4& v = state.fluid.velocity[i];
    position[3 * i] = p.x, position[3 * i + 1] = p.y, position[3 * i + 2] = p.z;
    velocity[3 * i] = v.x, velocity[3 * i + 1] = v.y, velocity[3 * i + 2] = v.z;
  }
  py::dict d;
  d["path"] = state.path;
  d["scene"] = state.scene;
  d["method"] = sim::SolverMethodName(state.method);
  d["time"] = state.clock.time;
  d["step"] = state.step;
  d["spacing"] = state.spacing;
  d["fluid"] = state.fluidCount;
  d["boundary"] = state.boundaryCount;
  d["positions"] = Array(position, {n, 3});
  d["velocities"] = Array(velocity, {n, 3});
  d["densities"] = Array(state.fluid.density, {n});
  d["pressures"] = Array(state.fluid.pressure, {n});
  d["ids"] = Array(state.fluid.id, {n});
  return d;
}


void BindRunOptions(py::module_& m) {
  py::class_<RunOptions>(m, "RunOptions")
      .def(py::init<>())
      .def_readwrite("scene", &RunOptions::scene)
      .def_readwrite("scene_json", &RunOptions::sceneJson)
      .def_readwrite("origin", &RunOptions::origin)
      .def_readwrite("install_dir", &RunOptions::installDir)
      .def_readwrite("sets", &RunOptions::sets)
      .def_readwrite("device", &RunOptions::device)
      .def_readwrite("threads", &RunOptions::threads)
      .def_readwrite("validate", &RunOptions::validate)
      .def_readwrite("settle", &RunOptions::settle)
      .def_readwrite("load_state", &RunOptions::loadState)
      .def_readwrite("probes_csv", &RunOptions::probesCsv)
      .def_readwrite("record_dam_break", &RunOptions::recordDamBreak);
}

// A run's steps and its saved state.
void BindRunSteps(py::class_<Run>& run) {
  run.def(py::init(&Make), py::arg("options"))
      .def(
          "step",
          [](Run& r, int64_t n) {
            Check(sphxr::app::CheckRunArgument("step", static_cast<double>(n)));
            Check(Unlocked([&](const KeepGoing& go) { return r.Step(n, 0.0, go); }));
          },
          py::arg("n") = 1)
      .def(
          "run_to",
          [](Run& r, double t) {
            Check(sphxr::app::CheckRunArgument("run_to", t));
            Check(Unlocked([&](const KeepGoing& go) { return r.Step(-1, t, go); }));
          },
          py::arg("time"))
      .def("run_scene", [](Run& r) { Check(Unlocked([&](const KeepGoing& go) { return r.RunScene(go); })); })
      .def(
          "save_state",
          [](Run& r, const std::string& path) { Check(Unlocked([&](const KeepGoing&) { return r.SaveState(path); })); },
          py::arg("path"));
}

// What a run has recorded: its particles, probe rows, step rows and dam-break measures, as NumPy arrays.
void BindRunTables(py::class_<Run>& run) {
  run.def("particles",
           [](Run& r) {
             Particles p;
             Check(Unlocked([&](const KeepGoing&) { return r.Download(&p); }));
             const py::ssize_t n = static_cast<py::ssize_t>(p.id.size());
             py::dict d;
             d["positions"] = Array(p.position, {n, 3});
             d["velocities"] = Array(p.velocity, {n, 3});
             d["densities"] = Array(p.density, {n});
             d["pressures"] = Array(p.pressure, {n});
             d["ids"] = Array(p.id, {n});
             return d;
           })
      .def("probe_table",
           [](Run& r) {
             ProbeTable t;
             Check(Unlocked([&](const KeepGoing&) { return r.Probes(&t); }));
             std::vector<double> flat;
             for (const auto& row : t.rows) flat.insert(flat.end(), row.begin(), row.end());
             return py::make_tuple(t.columns, Array(flat, {static_cast<py::ssize_t>(t.rows.size()),
                                                           static_cast<py::ssize_t>(t.columns.size())}));
           })
      .def("step_table",
           [](Run& r) {
             const std::vector<StepRecord> h = r.StepHistory();
             const py::ssize_t n = static_cast<py::ssize_t>(h.size());
             std::vector<double> time(n), dt(n), speed(n), mean(n), max(n), active(n), iterations(n);
             for (py::ssize_t i = 0; i < n; ++i) {
               time[i] = h[i].time, dt[i] = h[i].dt, speed[i] = h[i].maxSpeed, mean[i] = h[i].meanDensityError;
               max[i] = h[i].maxDensityError, active[i] = h[i].activeFraction, iterations[i] = h[i].solve.densityIterations;
             }
             py::dict d;
             d["time"] = Array(time, {n});
             d["dt"] = Array(dt, {n});
             d["max_speed"] = Array(speed, {n});
             d["mean_density_error"] = Array(mean, {n});
             d["max_density_error"] = Array(max, {n});
             d["active_fraction"] = Array(active, {n});
             d["density_iterations"] = Array(iterations, {n});
             return d;
           })
      .def("dam_break_table",
           [](Run& r) {
             const auto h = r.DamBreakHistory();
             std::vector<double> flat;
             for (const auto& row : h) flat.insert(flat.end(), row.begin(), row.end());
             return Array(flat, {static_cast<py::ssize_t>(h.size()), 3});
           });
}

// A run's summary, parameters and scene.
void BindRunProperties(py::class_<Run>& run) {
  run.def("summary", &Run::Summary)
      .def("parameters", [](Run& r) { return Parameters(r.Setup()); })
      .def_property_readonly("time", &Run::Time)
      .def_property_readonly("steps", &Run::Steps)
      .def_property_readonly("fluid_count", &Run::FluidCount)
      .def_property_readonly("boundary_count", &Run::BoundaryCount)
      .def_property_readonly("device", &Run::Device)
      .def_property_readonly("scene_name", [](Run& r) { return r.Scene().name; })
      .def_property_readonly("scene_path", [](Run& r) { return r.Scene().path; })
      .def_property_readonly("run_time", [](Run& r) { return r.Scene().runTime; })
      .def_property_readonly("run_steps", [](Run& r) { return r.Scene().runSteps; })
      .def_property_readonly("has_probes", [](Run& r) { return r.Scene().probes.has_value(); })
      .def_property_readonly("dam_break_column_width",
                             [](Run& r) -> py::object {
                               if (!r.Scene().damBreak) return py::none();
                               return py::float_(r.Scene().damBreak->columnWidth);
                             })
      .def_property_readonly("gravity", [](Run& r) {
        const auto& g = r.Setup().gravity;
        return py::make_tuple(g.x, g.y, g.z);
      });
}

// State files and scenes: read, found, described.
void BindScenes(py::module_& m) {
  m.def("read_state", &ReadState, py::arg("path"));
  m.def(
      "scene_info",
      [](const std::string& name, const std::string& installDir, const std::vector<std::string>& sets) {
        Check(sphxr::app::CheckPathArgument("scene_info", name));
        sphxr::app::SceneFile scene;
        std::string path;
        Check(sphxr::app::FindScene(name, &path, installDir));
        Check(sphxr::app::LoadScene(path, &scene));
        for (const std::string& set : sets) Check(sphxr::app::SetSolverParam(&scene.setup, set));
        py::dict d;
        d["path"] = path;
        d["name"] = scene.name;
        d["run_time"] = scene.runTime;
        d["run_steps"] = scene.runSteps;
        d["run_settle"] = scene.runSettle;
        d["probe_columns"] = scene.probes ? py::cast(sphxr::app::ProbeCsvHeader(scene.probes->set)) : py::none();
        d["dam_break_column_width"] = scene.damBreak ? py::cast(scene.damBreak->columnWidth) : py::none();
        d["parameters"] = Parameters(scene.setup);
        return d;
      },
      py::arg("name"), py::arg("install_dir") = "", py::arg("sets") = std::vector<std::string>{});
  m.def(
      "find_scene",
      [](const std::string& name, const std::string& installDir) {
        Check(sphxr::app::CheckPathArgument("find_scene", name));
        std::string path;
        Check(sphxr::app::FindScene(name, &path, installDir));
        return path;
      },
      py::arg("name"), py::arg("install_dir") = "");
  m.def("scene_dirs", &sphxr::app::SceneSearchDirs, py::arg("install_dir") = "");
}

// The log level, the run arguments' checks, the escaping of shown text, the limits and the names.
void BindChecks(py::module_& m) {
  m.def("set_log_level", [](const std::string& level) {
    static const std::pair<const char*, sphxr::LogLevel> kLevels[] = {
        {"debug", sphxr::LogLevel::kDebug}, {"info", sphxr::LogLevel::kInfo}, {"warn", sphxr::LogLevel::kWarn},
        {"error", sphxr::LogLevel::kError}, {"off", sphxr::LogLevel::kOff}};
    for (const auto& [name, value] : kLevels) {
      if (level == name) return sphxr::SetLogLevel(value);
    }
    throw Error("set_log_level " + sphxr::ShowText(level) + ": must be debug, info, warn, error or off");
  }, py::arg("level"));
  // The run arguments' one check and parser (app/run_arguments.h), for the package and the sweeps: the
  // value (a float) when it passes, else sphxr.Error with the command line's message.
  m.def(
      "check_argument",
      [](const std::string& name, double value) {
        Check(sphxr::app::CheckRunArgument(name, value));
        return value;
      },
      py::arg("name"), py::arg("value"));
  m.def(
      "parse_argument",
      [](const std::string& name, const std::string& text) {
        double value = 0.0;
        Check(sphxr::app::ParseRunArgument(name, text, &value));
        return value;
      },
      py::arg("name"), py::arg("text"));
  m.def(
      "show_text", [](const std::string& text, size_t maxBytes) { return sphxr::ShowText(text, maxBytes); },
      py::arg("text"), py::arg("max_bytes") = sphxr::kShownLength);
  m.def("max_threads", &sphxr::sim::MaxSolverThreads);
  m.def("parameter_names", [] {
    std::vector<std::string> names = {"method", "density"};
    for (const sphxr::app::ParamDesc& p : sphxr::app::ParamRegistry()) names.push_back(p.group == "solver" ? p.name : p.key);
    return names;
  });
}

}  // namespace
}  // namespace sphxr::python

PYBIND11_MODULE(_sphxr, m) {
  using namespace sphxr::python;
  m.doc() = "sphxr: SPH water runs from Python (docs/user/python.md); use the sphxr package, not _sphxr";
  py::register_exception<Error>(m, "Error", PyExc_RuntimeError);
  m.attr("build_scenes_dir") = SPHXR_SCENES_DIR;
  m.attr("max_scene_depth") = sphxr::app::kMaxSceneDepth;
  m.attr("max_run_time") = sphxr::app::kMaxRunTime;
  BindRunOptions(m);
  py::class_<Run> run(m, "Run");
  BindRunSteps(run);
  BindRunTables(run);
  BindRunProperties(run);
  BindScenes(m);
  BindChecks(m);
}
