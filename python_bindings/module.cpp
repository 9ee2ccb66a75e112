// The shgi._shgi extension module: one bind_<area>.cpp per native module (STYLE.md habit 8).
#include <pybind11/pybind11.h>

namespace py = pybind11;

namespace {

// pybind11's tp_new, which every class of the module inherits from pybind11_object.
newfunc pybind11_new = nullptr;

// The same allocation under a function of the module's own. Calling a class (shgi.Mesh(...))
// reaches it through the type's tp_new slot and __init__ follows; a bare Mesh.__new__(Mesh)
// finds pybind11_object's __new__ instead, whose safety check (CPython's tp_new_wrapper) refuses
// a type whose tp_new is not pybind11_object's with a TypeError. Without this the bare __new__
// returned an object that __init__ never filled, and pybind11 ran the next method call on
// uninitialised memory (a segfault that took the Python process, Blender included, down).
PyObject* new_constructed_by_call(PyTypeObject* type, PyObject* args, PyObject* kwargs) {
    return pybind11_new(type, args, kwargs);
}

// Gives every class the module defines new_constructed_by_call as its tp_new.
void refuse_bare_new(py::module_& m) {
    pybind11_new = reinterpret_cast<PyTypeObject*>(py::detail::get_internals().instance_base)
                       ->tp_new;
    for (const auto item : m.attr("__dict__").cast<py::dict>()) {
        if (!PyType_Check(item.second.ptr())) continue;
        auto* type = reinterpret_cast<PyTypeObject*>(item.second.ptr());
        if (!py::detail::get_type_info(type)) continue;  // not a pybind11 class (exceptions)
        if (type->tp_new != pybind11_new) continue;
        type->tp_new = new_constructed_by_call;
        PyType_Modified(type);
    }
}

}  // namespace

namespace shgi::python {
void bind_util(py::module_& m);
void bind_sh(py::module_& m);
void bind_scene(py::module_& m);
void bind_io(py::module_& m);
void bind_loaders(py::module_& m);
void bind_render(py::module_& m);
void bind_methods(py::module_& m);
void bind_lattice(py::module_& m);
void bind_probes(py::module_& m);
void bind_radiance(py::module_& m);
void bind_propagation(py::module_& m);
void bind_instant(py::module_& m);
void bind_bake(py::module_& m);
}  // namespace shgi::python

PYBIND11_MODULE(_shgi, m) {
    m.doc() = "SHGI native core: SH maths, scenes on Embree, EXR/PNG I/O, glTF/OBJ loading (see the shgi package).";
    // Order matters: util registers the exception types and Progress the others use.
    shgi::python::bind_util(m);
    shgi::python::bind_sh(m);
    shgi::python::bind_scene(m);
    shgi::python::bind_io(m);
    shgi::python::bind_loaders(m);  // needs Scene from bind_scene
    shgi::python::bind_render(m);
    shgi::python::bind_methods(m);  // GiSolver, the base of every solver below
    shgi::python::bind_lattice(m);  // PhotonLattice derives from IndirectField (bind_render)
    shgi::python::bind_probes(m);   // so do ProbeGrid and ProbeField
    shgi::python::bind_radiance(m);  // and RadianceField
    shgi::python::bind_propagation(m);  // PropagationField too; PropagationVolume is a GiSolver
    shgi::python::bind_instant(m);  // InstantGiField too; InstantGi is a GiSolver
    shgi::python::bind_bake(m);     // takes any IndirectField
    refuse_bare_new(m);             // after every class exists
}
