// PathArg: the file path argument of every binding that reads or writes a file. It takes what
// open() takes: str, bytes or an os.PathLike (os.fspath), str encoded as os.fsencode does.
// pybind11's std::filesystem::path caster made a path holding a NUL byte an "incompatible function
// arguments" TypeError that named neither the argument nor the byte, and its std::string caster
// refused pathlib.Path; with this one the NUL reaches the native checks, whose ValueError names its
// position (io/image.h, require_readable_file and the writers).
#pragma once

#include <string>

#include <pybind11/pybind11.h>

namespace shgi::python {

struct PathArg {
    std::string value;
    operator const std::string&() const { return value; }
};

}  // namespace shgi::python

namespace pybind11::detail {

template <>
struct type_caster<shgi::python::PathArg> {
    PYBIND11_TYPE_CASTER(shgi::python::PathArg, const_name("str | bytes | os.PathLike"));

    bool load(handle source, bool /*convert*/) {
        object path = reinterpret_steal<object>(PyOS_FSPath(source.ptr()));
        if (!path) {  // not str, bytes or os.PathLike: pybind's TypeError lists the types
            PyErr_Clear();
            return false;
        }
        if (PyUnicode_Check(path.ptr())) {
            path = reinterpret_steal<object>(PyUnicode_EncodeFSDefault(path.ptr()));
            if (!path) throw error_already_set();  // not encodable: Python's own error
        }
        char* data = nullptr;
        Py_ssize_t size = 0;
        if (PyBytes_AsStringAndSize(path.ptr(), &data, &size) != 0) throw error_already_set();
        value.value.assign(data, size_t(size));
        return true;
    }
    static handle cast(const shgi::python::PathArg& source, return_value_policy, handle) {
        const std::string& path = source.value;
        return PyUnicode_DecodeFSDefaultAndSize(path.data(), Py_ssize_t(path.size()));
    }
};

}  // namespace pybind11::detail
