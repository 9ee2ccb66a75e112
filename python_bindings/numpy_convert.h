// Checked conversions between numpy arrays and SHGI types, shared by every bind_<area>.cpp.
//
// The boundary rules (docs/architecture.md, "Bindings"): explicit shapes and dtypes, checks done
// with the GIL held, and a ValueError that names the argument, the expected shape/dtype and what
// came in. Floating input accepts float32 or float64 (converted to float32); integer input accepts
// any integer dtype whose values fit (negative or too-large indices are errors, not wrap-arounds).
// Non-finite floats are rejected unless allow_non_finite is set.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "util/math.h"

namespace shgi::python {

namespace py = pybind11;

// An (N, columns) float array, or (N,) when columns == 0. Returns the data row-major as float32.
// Integer dtypes are rejected unless accept_integers (meant for small literals like colours).
std::vector<float> to_float_rows(const py::handle& obj, const char* arg_name, int columns,
                                 bool allow_non_finite = false, bool accept_integers = false);

std::vector<vec2> to_vec2_array(const py::handle& obj, const char* arg_name);
std::vector<vec3> to_vec3_array(const py::handle& obj, const char* arg_name);
// (N, 4) rows; NaN and infinities pass through when allow_non_finite (the native side then
// decides, e.g. Mesh tangents, which validate_mesh drops with a warning).
std::vector<vec4> to_vec4_array(const py::handle& obj, const char* arg_name,
                                bool allow_non_finite = false);
std::vector<uvec3> to_uvec3_array(const py::handle& obj, const char* arg_name);
std::vector<uint32_t> to_uint_array(const py::handle& obj, const char* arg_name);

// A length-3 sequence or array of finite floats (a colour or a point).
vec3 to_vec3(const py::handle& obj, const char* arg_name);
// A 4x4 float matrix given row-major as numpy/Blender write it (m[row][col]); returned as GLM's
// column-major mat4 so that world_from_object * p works as written.
mat4 to_mat4(const py::handle& obj, const char* arg_name);
py::array_t<float> from_mat4(const mat4& m);

// (N, k) float32 arrays out.
py::array_t<float> to_numpy(const std::vector<vec2>& values);
py::array_t<float> to_numpy(const std::vector<vec3>& values);
py::array_t<float> to_numpy(const std::vector<vec4>& values);
py::array_t<uint32_t> to_numpy(const std::vector<uvec3>& values);

// "(H, W, 3)", "float64" and "(H, W, 3) float64", for error messages.
std::string shape_string(const py::array& array);
std::string dtype_string(const py::array& array);
std::string describe_array(const py::array& array);

// Raises ValueError "<arg_name>: <message>".
[[noreturn]] void throw_value_error(const char* arg_name, const std::string& message);
// `value`, or ValueError "<arg_name>: is nan; it must be finite" for NaN or ±inf.
float checked_finite(float value, const char* arg_name);

// Raises MemoryError "<arg_name>: a contiguous <dtype> copy of the <shape> array does not fit in
// memory; ...": what ensure() leaves when it cannot allocate the copy.
[[noreturn]] void throw_copy_failed(const py::array& array, const char* arg_name,
                                   const py::dtype& dtype);

// `array` as a C-contiguous Array (a py::array_t), copied when needed. ensure() gives a null
// array when the copy cannot be allocated (a broadcast view of a few bytes may stand for
// terabytes); that is a MemoryError naming the argument, never a null pointer to read through.
template <typename Array>
Array contiguous_copy(const py::array& array, const char* arg_name) {
    Array contiguous = Array::ensure(array);
    if (!contiguous)
        throw_copy_failed(array, arg_name, py::dtype::of<typename Array::value_type>());
    return contiguous;
}

}  // namespace shgi::python
