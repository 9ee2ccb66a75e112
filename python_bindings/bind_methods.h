// Shared by the bindings of every GI method (bind_methods.cpp): how a method's Python settings
// object becomes the std::any its registry row's factory reads (methods/method_registry.h).
#pragma once

#include <pybind11/pybind11.h>

#include <any>
#include <functional>
#include <string>
#include <vector>

#include "render/gi_solver.h"

namespace shgi::python {

using SettingsCaster = std::function<std::any(pybind11::handle)>;

// Registers the caster of a settings struct under its name (the row's settings_type).
void register_settings_caster(const std::string& settings_type, SettingsCaster caster);

// The caster of the bound settings struct S, named as its Python class.
template <class S>
void register_settings_type(const std::string& settings_type) {
    register_settings_caster(settings_type,
                             [](pybind11::handle settings) { return std::any(settings.cast<S>()); });
}

// GiSolver::stage_seconds() as a list of (stage, seconds) tuples.
inline pybind11::list stage_list(const std::vector<StageSeconds>& stages) {
    pybind11::list out;
    for (const StageSeconds& stage : stages) out.append(pybind11::make_tuple(stage.stage, stage.seconds));
    return out;
}

}  // namespace shgi::python
