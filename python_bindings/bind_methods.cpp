// Bindings for native/methods and render/gi_solver.h: the registry of GI methods
// (shgi._shgi.native_methods, make_native_solver) and GiSolver, the interface PhotonLattice and
// ProbeGrid implement. The shgi.methods module adds methods registered from Python (tests,
// plugins) to the native rows; front ends read that module.
//
// GiSolver can be subclassed in Python (a trampoline, as Mitsuba's integrator_v.cpp): a method
// prototyped in Python implements refine, reset, passes, current_field, stage_seconds and
// memory_bytes, and its field may be any native IndirectField.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <map>
#include <mutex>

#include "bind_methods.h"
#include "interruptible.h"
#include "methods/method_registry.h"
#include "scene_use.h"

namespace py = pybind11;

namespace shgi::python {
namespace {

std::mutex casters_mutex;
std::map<std::string, SettingsCaster>& casters() {
    static std::map<std::string, SettingsCaster> table;
    return table;
}

// GiSolver's trampoline: Python subclasses implement the interface.
class PyGiSolver : public GiSolver {
  public:
    void refine(Progress* progress) override {
        PYBIND11_OVERRIDE_PURE(void, GiSolver, refine, progress);
    }
    void reset(Progress* progress) override {
        PYBIND11_OVERRIDE_PURE(void, GiSolver, reset, progress);
    }
    // A property in Python, as on the native solvers.
    uint64_t passes() const override {
        py::gil_scoped_acquire gil;
        return py::cast(static_cast<const GiSolver*>(this)).attr("passes").cast<uint64_t>();
    }
    std::shared_ptr<const IndirectField> current_field() const override {
        PYBIND11_OVERRIDE_PURE(std::shared_ptr<const IndirectField>, GiSolver, current_field);
    }
    std::vector<StageSeconds> stage_seconds() const override { return {}; }
    size_t memory_bytes() const override { return 0; }
};

std::any settings_as_any(const MethodInfo& row, const py::object& settings) {
    if (settings.is_none()) return {};
    const std::string type = py::str(py::type::handle_of(settings).attr("__name__"));
    if (type != row.settings_type)
        throw py::type_error("settings of method " + row.identifier + " must be shgi." +
                             row.settings_type + ", got " + type);
    std::lock_guard<std::mutex> lock(casters_mutex);
    const auto it = casters().find(row.settings_type);
    if (it == casters().end())
        throw std::runtime_error("no binding converts " + row.settings_type);
    return it->second(settings);
}

void bind_gi_solver(py::module_& m) {
    py::class_<GiSolver, PyGiSolver>(m, "GiSolver", R"doc(
The interface every GI method implements (PhotonLattice, ProbeGrid, ...): refine(progress) runs
one refinement pass, reset(progress) forgets every pass, current_field() is the IndirectField to
render (unchanged until the next refine or reset), passes counts the passes, stage_seconds the
wall time of the last pass's stages, memory_bytes what the solution holds. Subclass it in
Python to prototype a method (register it with shgi.register_method).)doc")
        .def(py::init<>(), "For Python subclasses.");
}

void bind_registry(py::module_& m) {
    py::class_<MethodInfo>(m, "NativeMethod",
                           "A row of the native method registry (see shgi.methods()).")
        .def_readonly("identifier", &MethodInfo::identifier)
        .def_readonly("label", &MethodInfo::label)
        .def_readonly("description", &MethodInfo::description)
        .def_readonly("number", &MethodInfo::number, "The enum value .blend files store.")
        .def_readonly("aliases", &MethodInfo::aliases, "Older names still accepted.")
        .def_readonly("settings_type", &MethodInfo::settings_type,
                      "Name of the settings class in shgi.")
        .def_readonly("final_passes", &MethodInfo::final_passes,
                      "Refinement passes of a final solve (F12, bake, CLI).")
        .def_property_readonly("solves_field", &MethodInfo::solves_field,
                               "False for the path tracer, which solves nothing.");
    m.def("native_methods", &registered_methods,
          "The native registry's rows, in menu order (shgi.methods() adds Python ones).");
    m.def("reserved_method_numbers", &reserved_method_numbers,
          "(identifier, number) of methods still to come: their numbers stay reserved.");
    m.def(
        "make_native_solver",
        [](const std::string& method, const Scene& scene, const py::object& settings,
           Progress* progress) {
            const MethodInfo row = find_method(method);
            const std::any typed = settings_as_any(row, settings);
            SceneUse use(scene, SceneUse::Kind::Query, row.identifier.c_str());
            return run_interruptible(progress, [&](Progress* used) {
                return make_solver(row.identifier, scene, typed, used);
            });
        },
        py::arg("method"), py::arg("scene"), py::arg("settings") = py::none(),
        py::arg("progress") = py::none(), py::keep_alive<0, 2>(),
        "The solver of a native method on a committed scene (settings None: the defaults); use "
        "shgi.make_solver, which also knows methods registered from Python.");
}

}  // namespace

void register_settings_caster(const std::string& settings_type, SettingsCaster caster) {
    std::lock_guard<std::mutex> lock(casters_mutex);
    casters()[settings_type] = std::move(caster);
}

void bind_methods(py::module_& m) {
    bind_gi_solver(m);
    bind_registry(m);
}

}  // namespace shgi::python
