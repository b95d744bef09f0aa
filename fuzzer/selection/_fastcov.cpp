// The engine's edge callback: Atheris' own counter increment, called without pybind11.
//
// Atheris gives every edge of an instrumented Python module a call to
// `atheris._trace_branch(index)`. Once fuzzing starts, that is a pybind11 wrapper
// of `atheris::_trace_branch(uint64_t)` in Atheris' core module, and the wrapper's
// argument dispatch costs about 150 ns a call where the increment itself costs a
// few (BENCHMARKS.md, "Instrumentation's cost, split"). This module finds that
// same C++ function in the core module already loaded (dlopen with RTLD_NOLOAD,
// dlsym of its mangled name) and calls it from a METH_O builtin: the same counters
// bumped, by Atheris' own code (nothing before its counters are allocated, an index
// past them wrapped), without the dispatch.
// `fuzzer.selection.fastcov` is its Python facade.
//
// Plain CPython API, no pybind11: its dispatch is what this saves.

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <dlfcn.h>

#include <cstdint>

namespace {

using TraceBranch = void (*)(uint64_t);

// atheris::_trace_branch(unsigned long) in Atheris 3.0.0's core modules.
constexpr const char kSymbol[] = "_ZN7atheris13_trace_branchEm";

TraceBranch target = nullptr;

PyObject* bind(PyObject*, PyObject* path) {
  const char* file = PyUnicode_AsUTF8(path);
  if (file == nullptr) {
    return nullptr;
  }
  // RTLD_NOLOAD: only a library this process has loaded already (Atheris' core
  // module, imported by atheris.Fuzz); never loads one from the path given.
  void* handle = dlopen(file, RTLD_NOW | RTLD_NOLOAD);
  if (handle == nullptr) {
    PyErr_Format(PyExc_LookupError, "%s is not a library this process has loaded", file);
    return nullptr;
  }
  void* symbol = dlsym(handle, kSymbol);
  dlclose(handle);  // the core module stays loaded: Python holds it
  if (symbol == nullptr) {
    PyErr_Format(PyExc_LookupError, "%s has no %s (another Atheris version?)", file, kSymbol);
    return nullptr;
  }
  target = reinterpret_cast<TraceBranch>(symbol);
  Py_RETURN_NONE;
}

PyObject* trace_branch(PyObject*, PyObject* index) {
  const unsigned long long i = PyLong_AsUnsignedLongLong(index);
  if (i == static_cast<unsigned long long>(-1) && PyErr_Occurred()) {
    return nullptr;
  }
  if (target == nullptr) {
    PyErr_SetString(PyExc_RuntimeError, "_fastcov.trace_branch called before bind()");
    return nullptr;
  }
  target(static_cast<uint64_t>(i));
  Py_RETURN_NONE;
}

PyMethodDef methods[] = {
    {"bind", bind, METH_O,
     "bind(path): call atheris::_trace_branch of the loaded library at path (Atheris' core module)"},
    {"trace_branch", trace_branch, METH_O,
     "trace_branch(index): bump Atheris' coverage counter index, as atheris._trace_branch does"},
    {nullptr, nullptr, 0, nullptr},
};

PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_fastcov", "Atheris' edge callback without pybind11's dispatch.", -1,
    methods,
};

}  // namespace

extern "C" PyMODINIT_FUNC PyInit__fastcov() { return PyModule_Create(&module); }
