// Helpers that expose plain native structs (settings, materials, lights) field by field, so a
// Python object mirrors its C++ struct with the same names and defaults (docs/architecture.md).
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include <pybind11/pybind11.h>

#include "numpy_convert.h"
#include "util/math.h"

namespace shgi::python {

// Makes Enum(value) accept only the named values: pybind11's enum_ converts any integer, and
// an unnamed one (DiffuseModel(7)) reached native switches that have no case for it. Call after
// the last .value().
template <typename Enum>
void named_values_only(pybind11::enum_<Enum> cls) {
    using Scalar = std::underlying_type_t<Enum>;
    std::vector<Scalar> named;
    std::string names;
    for (const auto& [name, value] : pybind11::dict(cls.attr("__members__"))) {
        named.push_back(static_cast<Scalar>(value.template cast<Enum>()));
        names += (names.empty() ? "" : ", ") + name.template cast<std::string>() + " (" +
                 std::to_string(named.back()) + ")";
    }
    const std::string type = cls.attr("__name__").template cast<std::string>();
    cls.attr("__init__") = pybind11::none();  // replaced, not overloaded: one signature
    cls.def(pybind11::init([named, names, type](Scalar value) {
                if (std::find(named.begin(), named.end(), value) == named.end())
                    throw pybind11::value_error(type + "(" + std::to_string(value) +
                                                "): not a member; use one of " + names);
                return static_cast<Enum>(value);
            }),
            pybind11::arg("value"));
}

// The clamp_indirect field of every settings struct that has one (render/shading.h,
// clamp_contribution).
inline constexpr const char* kClampIndirectDoc =
    "Light Paths > Clamp Indirect as Cycles': an indirect contribution whose components average "
    "more than this is scaled down to it; 0 = off (0).";

// The filter_glossy field of every settings struct that has one (PrincipledBsdf::blur).
inline constexpr const char* kFilterGlossyDoc =
    "Light Paths > Filter Glossy as Cycles': after a bounce whose BSDF pdf was below this value, "
    "glossy and glass lobes widen to GGX alpha sqrt(1 - pdf / value) / 2, against the caustic "
    "fireflies of mirrors seen through diffuse bounces; 0 = off (0).";

// The pixel_filter and filter_width fields of the renderers' settings (render/pixel_filter.h).
inline constexpr const char* kPixelFilterDoc =
    "Film > Pixel Filter as Cycles': PixelFilter BOX, GAUSSIAN or BLACKMAN_HARRIS, drawn per "
    "sample around its pixel (BOX; Cycles' default is BLACKMAN_HARRIS).";
inline constexpr const char* kFilterWidthDoc =
    "Film > Pixel Filter's width in pixels as Cycles' Filter Size, [0.01, 10] (1.0; Cycles' "
    "default 1.5): a box of width w spans w pixels, a Gaussian of width w has sigma w / 4, a "
    "Blackman-Harris of width w spans 2 w.";

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

// A Python int, or any object with __index__ (numpy's integers), kept at full size so that
// def_integer can range-check it and name the field.
struct IndexInt {
    pybind11::int_ value;
};

// operator.index(value), or a null object when value is not an integer (1.5, "3").
inline pybind11::object as_index(const pybind11::handle& value) {
    PyObject* index = PyNumber_Index(value.ptr());
    if (index == nullptr) PyErr_Clear();
    return pybind11::reinterpret_steal<pybind11::object>(index);
}

// Spells a bound parameter's type without deducing it from the argument (C++20's
// std::type_identity_t): def_integer(..., 1) for a uint64_t field must not deduce int.
template <typename U>
struct Exactly {
    using type = U;
};

// `number` as a U if it is in [minimum, maximum]; else a ValueError naming `name` and the range.
template <typename U>
U range_checked(const pybind11::int_& number, const char* name, U minimum, U maximum) {
    static_assert(std::is_integral_v<U> && !std::is_same_v<U, bool>,
                  "range_checked is for integer types");
    if (number < pybind11::int_(minimum) || number > pybind11::int_(maximum))
        throw_value_error(name, "must be in [" + std::to_string(minimum) + ", " +
                                    std::to_string(maximum) + "], got " +
                                    std::string(pybind11::str(number)));
    return number.cast<U>();
}

// `value` (an int, or any object with __index__) as a U in [minimum, maximum], by default the
// type's range: outside it, a ValueError naming `name` and the range; not an integer at all, a
// TypeError naming `name`. For arguments and sequence elements; fields use def_integer.
template <typename U>
U checked_integer(const pybind11::handle& value, const char* name,
                  typename Exactly<U>::type minimum = std::numeric_limits<U>::min(),
                  typename Exactly<U>::type maximum = std::numeric_limits<U>::max()) {
    const pybind11::object index = as_index(value);
    if (!index)
        throw pybind11::type_error(std::string(name) + ": expected an integer, got " +
                                   Py_TYPE(value.ptr())->tp_name);
    return range_checked<U>(pybind11::reinterpret_borrow<pybind11::int_>(index), name, minimum,
                            maximum);
}

// An integer argument bound as IndexInt, as a U in [minimum, maximum] (by default the type's
// range): outside it, a ValueError naming the argument. pybind's own int caster turned 2**64 into
// a TypeError about incompatible arguments that named none.
template <typename U>
U int_arg(const IndexInt& value, const char* name,
          typename Exactly<U>::type minimum = std::numeric_limits<U>::min(),
          typename Exactly<U>::type maximum = std::numeric_limits<U>::max()) {
    return range_checked<U>(value.value, name, minimum, maximum);
}

// An integer field (int, uint32_t, uint64_t) exposed as an int in [minimum, maximum], by default
// the type's range. It takes any int or __index__ object (numpy's integers); outside the range
// (2**40 for an int, -1 for an unsigned) it is a ValueError naming the field and the range,
// where def_readwrite let pybind raise a TypeError about incompatible arguments that named
// neither. The settings' own validation still checks what the solver accepts.
template <typename T, typename U>
void def_integer(pybind11::class_<T>& cls, const char* name, U T::*field, const char* doc,
                 typename Exactly<U>::type minimum = std::numeric_limits<U>::min(),
                 typename Exactly<U>::type maximum = std::numeric_limits<U>::max()) {
    cls.def_property(
        name, [field](const T& self) { return self.*field; },
        [field, name, minimum, maximum](T& self, const IndexInt& value) {
            self.*field = int_arg<U>(value, name, minimum, maximum);
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

namespace pybind11::detail {

template <>
struct type_caster<shgi::python::IndexInt> {
    PYBIND11_TYPE_CASTER(shgi::python::IndexInt, const_name("typing.SupportsIndex"));

    bool load(handle source, bool /*convert*/) {
        const object index = shgi::python::as_index(source);
        if (!index) return false;  // pybind's TypeError listing the accepted types
        value.value = reinterpret_borrow<int_>(index);
        return true;
    }
    static handle cast(const shgi::python::IndexInt& source, return_value_policy, handle) {
        return source.value.inc_ref();
    }
};

}  // namespace pybind11::detail
