#include "numpy_convert.h"

#include <cmath>
#include <limits>
#include <sstream>

#include "util/error.h"

namespace shgi::python {

std::string shape_string(const py::array& array) {
    std::ostringstream out;
    out << '(';
    for (py::ssize_t i = 0; i < array.ndim(); ++i) out << (i ? ", " : "") << array.shape(i);
    out << (array.ndim() == 1 ? ",)" : ")");
    return out.str();
}

std::string dtype_string(const py::array& array) {
    return py::str(static_cast<py::object>(array.dtype())).cast<std::string>();
}

std::string describe_array(const py::array& array) {
    return shape_string(array) + " " + dtype_string(array);
}

void throw_copy_failed(const py::array& array, const char* arg_name, const py::dtype& dtype) {
    PyErr_Clear();
    throw OutOfMemory(std::string(arg_name) + ": a contiguous " + std::string(py::str(dtype)) +
                      " copy of the " +
                      shape_string(array) + " array does not fit in memory; pass a smaller "
                      "array");
}

namespace {

py::array as_array(const py::handle& obj, const char* arg_name) {
    if (obj.is_none()) throw_value_error(arg_name, "expected an array, got None");
    py::array array = py::array::ensure(obj);  // null (error cleared) when not convertible
    if (!array) throw_value_error(arg_name, "could not be converted to a numpy array");
    return array;
}

// Checks the array is (N, columns) (or (N,) when columns == 0) and returns it as a C-contiguous
// array of the requested element type. Bulk float arrays must have a float dtype; small values
// (colours, matrices typed as Python lists of ints) may pass integers with accept_integers.
template <typename T>
py::array_t<T, py::array::c_style | py::array::forcecast> checked_rows(
    const py::handle& obj, const char* arg_name, int columns, bool accept_integers = false) {
    py::array array = as_array(obj, arg_name);
    const bool want_float = std::is_floating_point_v<T>;
    const char kind = array.dtype().kind();
    const bool is_integer = kind == 'i' || kind == 'u';
    const bool ok_kind = want_float ? (kind == 'f' || (accept_integers && is_integer)) : is_integer;
    if (!ok_kind)
        throw_value_error(arg_name, "expected a " + std::string(want_float ? "float32/float64"
                                                                            : "integer") +
                                        " array, got dtype " + dtype_string(array));
    const bool shape_ok = columns == 0 ? array.ndim() == 1
                                       : (array.ndim() == 2 && array.shape(1) == columns);
    if (!shape_ok) {
        const std::string expected =
            columns == 0 ? "(N,)" : "(N, " + std::to_string(columns) + ")";
        throw_value_error(arg_name,
                          "expected shape " + expected + ", got " + shape_string(array));
    }
    return contiguous_copy<py::array_t<T, py::array::c_style | py::array::forcecast>>(
        array, arg_name);
}

}  // namespace

void throw_value_error(const char* arg_name, const std::string& message) {
    throw py::value_error(std::string(arg_name) + ": " + message);
}

float checked_finite(float value, const char* arg_name) {
    if (!std::isfinite(value))
        throw_value_error(arg_name, "is " + std::to_string(value) + "; it must be finite");
    return value;
}

std::vector<float> to_float_rows(const py::handle& obj, const char* arg_name, int columns,
                                 bool allow_non_finite, bool accept_integers) {
    auto array = checked_rows<float>(obj, arg_name, columns, accept_integers);
    const float* data = array.data();
    const size_t count = static_cast<size_t>(array.size());
    std::vector<float> out(data, data + count);
    if (!allow_non_finite) {
        const size_t stride = columns > 0 ? static_cast<size_t>(columns) : 1;
        for (size_t i = 0; i < count; ++i) {
            if (!std::isfinite(out[i])) {
                std::ostringstream message;
                message << "element [" << i / stride;
                if (columns > 0) message << ", " << i % stride;
                message << "] is " << out[i] << "; all values must be finite (no NaN or Inf)";
                throw_value_error(arg_name, message.str());
            }
        }
    }
    return out;
}

namespace {

// Row-major (N, Vec::length()) values into N vectors: the inverse of rows_to_numpy below.
template <typename Vec, typename Scalar>
std::vector<Vec> rows_to_vectors(const std::vector<Scalar>& rows) {
    constexpr int kColumns = Vec::length();
    std::vector<Vec> out(rows.size() / kColumns);
    for (size_t i = 0; i < out.size(); ++i)
        for (int k = 0; k < kColumns; ++k) out[i][k] = rows[kColumns * i + k];
    return out;
}

}  // namespace

std::vector<vec2> to_vec2_array(const py::handle& obj, const char* arg_name) {
    return rows_to_vectors<vec2>(to_float_rows(obj, arg_name, 2));
}

std::vector<vec3> to_vec3_array(const py::handle& obj, const char* arg_name) {
    return rows_to_vectors<vec3>(to_float_rows(obj, arg_name, 3));
}

std::vector<vec4> to_vec4_array(const py::handle& obj, const char* arg_name,
                                bool allow_non_finite) {
    return rows_to_vectors<vec4>(to_float_rows(obj, arg_name, 4, allow_non_finite));
}

namespace {

// Integer input of any width: values must lie in [0, 2^32 - 1).
std::vector<uint32_t> checked_indices(const py::handle& obj, const char* arg_name, int columns) {
    auto array = checked_rows<int64_t>(obj, arg_name, columns);
    const int64_t* data = array.data();
    const size_t count = static_cast<size_t>(array.size());
    std::vector<uint32_t> out(count);
    constexpr int64_t kMaxIndex = std::numeric_limits<uint32_t>::max() - 1;
    for (size_t i = 0; i < count; ++i) {
        if (data[i] < 0 || data[i] > kMaxIndex) {
            std::ostringstream message;
            message << "element " << i << " is " << data[i] << "; indices must be in [0, "
                    << kMaxIndex << "]";
            throw_value_error(arg_name, message.str());
        }
        out[i] = static_cast<uint32_t>(data[i]);
    }
    return out;
}

}  // namespace

std::vector<uvec3> to_uvec3_array(const py::handle& obj, const char* arg_name) {
    return rows_to_vectors<uvec3>(checked_indices(obj, arg_name, 3));
}

std::vector<uint32_t> to_uint_array(const py::handle& obj, const char* arg_name) {
    return checked_indices(obj, arg_name, 0);
}

vec3 to_vec3(const py::handle& obj, const char* arg_name) {
    py::array array = as_array(obj, arg_name);
    if (array.ndim() != 1 || array.shape(0) != 3)
        throw_value_error(arg_name, "expected 3 values, got shape " + shape_string(array));
    const std::vector<float> rows =
        to_float_rows(array.reshape({1, 3}), arg_name, 3, false, /*accept_integers=*/true);
    return vec3(rows[0], rows[1], rows[2]);
}

mat4 to_mat4(const py::handle& obj, const char* arg_name) {
    py::array array = as_array(obj, arg_name);
    if (array.ndim() != 2 || array.shape(0) != 4 || array.shape(1) != 4)
        throw_value_error(arg_name, "expected a 4x4 matrix, got shape " + shape_string(array));
    const std::vector<float> rows = to_float_rows(array, arg_name, 4, false, true);
    mat4 m(1.0f);
    for (int row = 0; row < 4; ++row)
        for (int col = 0; col < 4; ++col) m[col][row] = rows[4 * row + col];
    return m;
}

py::array_t<float> from_mat4(const mat4& m) {
    py::array_t<float> out({4, 4});
    auto view = out.mutable_unchecked<2>();
    for (int row = 0; row < 4; ++row)
        for (int col = 0; col < 4; ++col) view(row, col) = m[col][row];
    return out;
}

namespace {

template <typename Out, typename Vec, int N>
py::array_t<Out> rows_to_numpy(const std::vector<Vec>& values) {
    py::array_t<Out> out({static_cast<py::ssize_t>(values.size()), static_cast<py::ssize_t>(N)});
    Out* data = out.mutable_data();
    for (size_t i = 0; i < values.size(); ++i)
        for (int k = 0; k < N; ++k) data[N * i + k] = values[i][k];
    return out;
}

}  // namespace

py::array_t<float> to_numpy(const std::vector<vec2>& values) {
    return rows_to_numpy<float, vec2, 2>(values);
}
py::array_t<float> to_numpy(const std::vector<vec3>& values) {
    return rows_to_numpy<float, vec3, 3>(values);
}
py::array_t<float> to_numpy(const std::vector<vec4>& values) {
    return rows_to_numpy<float, vec4, 4>(values);
}
py::array_t<uint32_t> to_numpy(const std::vector<uvec3>& values) {
    return rows_to_numpy<uint32_t, uvec3, 3>(values);
}

}  // namespace shgi::python
