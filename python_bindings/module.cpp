// The shgi._shgi extension module: one bind_<area>.cpp per native module (STYLE.md habit 8).
#include <pybind11/pybind11.h>

namespace py = pybind11;

namespace shgi::python {
void bind_util(py::module_& m);
void bind_sh(py::module_& m);
void bind_scene(py::module_& m);
void bind_io(py::module_& m);
void bind_loaders(py::module_& m);
void bind_render(py::module_& m);
void bind_lattice(py::module_& m);
void bind_probes(py::module_& m);
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
    shgi::python::bind_lattice(m);  // PhotonLattice derives from IndirectField (bind_render)
    shgi::python::bind_probes(m);   // so do ProbeGrid and ProbeField
    shgi::python::bind_bake(m);     // takes any IndirectField
}
