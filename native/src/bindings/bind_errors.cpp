// ApiError -> the robot_api exception class of its code.
#include <pybind11/pybind11.h>

#include "../errors.hpp"
#include "py_api.hpp"

namespace rrosfuzz {
namespace py = pybind11;

void bind_errors(py::module_&) {
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const ApiError& e) {
      py::object err = py_api::make_error(static_cast<int>(e.code()), e.what());
      PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(err.ptr())), err.ptr());
    }
  });
}

}  // namespace rrosfuzz
