// Helpers that expose plain native structs (settings, materials, lights) field by field, so a
// Python object mirrors its C++ struct with the same names and defaults (DESIGN.md).
#pragma once

#include <memory>
#include <string>

#include <pybind11/pybind11.h>

#include "numpy_convert.h"
#include "util/math.h"

namespace shgi::python {

inline pybind11::tuple to_tuple(const vec3& v) { return pybind11::make_tuple(v.x, v.y, v.z); }

// A vec3 field exposed as a 3-tuple; assignment accepts any length-3 sequence of finite numbers.
template <typename T>
void def_vec3(pybind11::class_<T>& cls, const char* name, vec3 T::*field, const char* doc) {
    cls.def_property(
        name, [field](const T& self) { return to_tuple(self.*field); },
        [field, name](T& self, const pybind11::object& value) {
            self.*field = to_vec3(value, name);
        },
        doc);
}

// A uint64_t field exposed as an int that must be >= `minimum` (ValueError naming the field).
template <typename T>
void def_uint64(pybind11::class_<T>& cls, const char* name, uint64_t T::*field, int64_t minimum,
                const char* doc) {
    cls.def_property(
        name, [field](const T& self) { return self.*field; },
        [field, name, minimum](T& self, int64_t value) {
            if (value < minimum)
                throw_value_error(name, "must be >= " + std::to_string(minimum) + ", got " +
                                            std::to_string(value));
            self.*field = uint64_t(value);
        },
        doc);
}

// Constructor from keyword arguments naming fields: Material(roughness=0.2, name="Red"). An
// unknown field is a TypeError naming it.
template <typename T>
std::unique_ptr<T> from_kwargs(const pybind11::kwargs& kwargs) {
    auto value = std::make_unique<T>();
    pybind11::object self = pybind11::cast(value.get(), pybind11::return_value_policy::reference);
    for (const auto& item : kwargs) {
        const std::string field = pybind11::str(item.first);
        if (field.empty() || field[0] == '_' || !pybind11::hasattr(self, field.c_str()))
            throw pybind11::type_error(
                std::string(pybind11::str(pybind11::type::of<T>().attr("__name__"))) +
                " has no field '" + field + "'");
        self.attr(field.c_str()) = item.second;
    }
    return value;
}

}  // namespace shgi::python
