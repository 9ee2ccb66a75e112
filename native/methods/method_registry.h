// The registry of GI methods: one row per method (identifier, label, description, the enum number
// .blend files store, its settings struct, how many passes a final solve runs, and how to build
// its solver). The bindings, shgi.bake, `python -m shgi` and the add-on all read it, so adding a
// method is: its folder under native/, its binding file, one row in method_registry.cpp, its
// tests (docs/solvers.md). pbrt-v4's Integrator::Create is the model: one small hierarchy
// (render/gi_solver.h) and one table.
//
// PATH_TRACE, the reference, is a row without a solver: it renders with the path tracer and
// bakes by path tracing every texel. Rows added at run time (register_method) serve tests and
// plugins; the built-in rows come first, in menu order.
#pragma once

#include <any>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "render/gi_solver.h"
#include "scene/scene.h"
#include "util/error.h"
#include "util/progress.h"

namespace shgi {

// Builds a method's solver on a committed scene from its settings struct held in a std::any
// (an empty any: the struct's defaults). Throws InvalidArgument for settings of another type.
using SolverFactory =
    std::function<std::unique_ptr<GiSolver>(const Scene&, const std::any&, Progress*)>;

struct MethodInfo {
    std::string identifier;            // "PHOTON_LATTICE": the one name every front end uses
    std::string label;                 // "Photon Lattice"
    std::string description;           // what an artist gets from it (a tooltip)
    int number = -1;                   // the enum value .blend files store; never reused
    std::vector<std::string> aliases;  // older names still accepted ("PATH_TRACER")
    std::string settings_type;         // the settings struct's name, C++ and Python alike
    uint32_t final_passes = 1;         // refinement passes of a final solve (F12, bake, CLI)
    SolverFactory make;                // empty: the method solves no field (PATH_TRACE)

    bool solves_field() const { return static_cast<bool>(make); }
};

// Every method: the built-in rows in menu order, then those registered at run time.
std::vector<MethodInfo> registered_methods();
// Numbers reserved for methods still to come, by identifier: a file saved by a later version
// keeps its value here.
std::vector<std::pair<std::string, int>> reserved_method_numbers();
// The row named by `name` (an identifier or an alias); InvalidArgument listing the choices.
MethodInfo find_method(std::string_view name);
// Adds a row; InvalidArgument when its identifier, an alias or its number is taken or reserved
// for another method, or the row is incomplete.
void register_method(MethodInfo row);
// Removes a row registered at run time (tests); false when there was none by that name.
bool unregister_method(std::string_view identifier);

// The method's solver; InvalidArgument for a method that solves no field.
std::unique_ptr<GiSolver> make_solver(std::string_view method, const Scene& scene,
                                      const std::any& settings = {},
                                      Progress* progress = nullptr);

// The factory of a solver type constructed as Solver(scene, settings, progress).
template <class Solver, class Settings>
SolverFactory solver_factory(const char* settings_type) {
    return [settings_type](const Scene& scene, const std::any& settings,
                           Progress* progress) -> std::unique_ptr<GiSolver> {
        if (!settings.has_value()) return std::make_unique<Solver>(scene, Settings{}, progress);
        const Settings* typed = std::any_cast<Settings>(&settings);
        if (typed == nullptr)
            throw InvalidArgument(format_message("settings: expected ", settings_type,
                                                 ", got another type"));
        return std::make_unique<Solver>(scene, *typed, progress);
    };
}

}  // namespace shgi
