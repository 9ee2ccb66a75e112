// Scaffolding: replaced by the render bindings.
#include <pybind11/pybind11.h>
namespace shgi::python {
void bind_render(pybind11::module_&) {}
}  // namespace shgi::python
