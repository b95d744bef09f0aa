// Python binding of Model (wrapped by native.RobotModel).
#include <pybind11/pybind11.h>

#include <cmath>
#include <memory>

#include "../errors.hpp"
#include "../model.hpp"
#include "py_api.hpp"

namespace rrosfuzz {
namespace py = pybind11;

namespace {

std::vector<double> batch_input(const Model& m, py::handle h, std::size_t& rows) {
  const std::size_t n = m.dof();
  std::vector<double> data;
  if (PyList_Check(h.ptr()) || PyTuple_Check(h.ptr())) {
    const py::tuple seq = py_api::items(h, "joint value rows");
    rows = seq.size();
    data.reserve(rows * n);
    for (std::size_t i = 0; i < rows; ++i) {
      auto row = py_api::to_vector(seq[i], "joint value rows");
      if (row.size() != n) {
        fail(ErrorCode::kWrongLength, "row " + std::to_string(i) + " has " + std::to_string(row.size()) +
                                          " joint values, expected " + std::to_string(n));
      }
      data.insert(data.end(), row.begin(), row.end());
    }
  } else if (py::isinstance<py::array>(h)) {
    py::array a = py::reinterpret_borrow<py::array>(h);
    const char kind = a.dtype().kind();
    if (a.ndim() != 2) fail(ErrorCode::kInvalidArgument, "joint value rows: expected a 2-D array (N, dof)");
    if (kind != 'f' && kind != 'i' && kind != 'u') {
      fail(ErrorCode::kInvalidArgument, std::string("joint value rows: array of kind '") + kind + "' is not real");
    }
    if (static_cast<std::size_t>(a.shape(1)) != n) {
      fail(ErrorCode::kWrongLength, "joint value rows: expected " + std::to_string(n) + " columns, got " +
                                        std::to_string(a.shape(1)));
    }
    py_api::refuse_masked(h, "joint value rows");
    auto d = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
    // ensure() clears the error it met: no memory for the float64 copy (a broadcast view of
    // 10**9 rows), which segfaulted here
    if (!d) fail(ErrorCode::kInvalidArgument, "joint value rows: cannot convert the array to float64");
    rows = static_cast<std::size_t>(a.shape(0));
    data.assign(d.data(), d.data() + d.size());
  } else {
    fail(ErrorCode::kInvalidArgument, std::string("joint value rows: expected a 2-D array or a list of rows, got ") +
                                          Py_TYPE(h.ptr())->tp_name);
  }
  for (std::size_t k = 0; k < data.size(); ++k) {
    if (!std::isfinite(data[k])) {
      fail(ErrorCode::kNonFinite, "joint value rows: row " + std::to_string(k / (n ? n : 1)) + " is not finite");
    }
  }
  return data;
}

}  // namespace

void bind_model(py::module_& m) {
  py::class_<Model, std::shared_ptr<Model>>(m, "Model")
      .def(py::init([](py::handle source, bool is_path, py::handle tip) {
             return std::make_shared<Model>(py_api::to_string(source, "urdf"), is_path,
                                            py_api::to_optional_string(tip, "tip_link"));
           }),
           py::arg("source"), py::arg("is_path"), py::arg("tip_link"))
      .def_property_readonly("name", &Model::name)
      .def_property_readonly("root_link", &Model::root_link)
      .def_property_readonly("tip_link", &Model::tip_link)
      .def_property_readonly("dof", &Model::dof)
      .def_property_readonly("link_names", [](const Model& self) { return py_api::to_tuple(self.link_names()); })
      .def_property_readonly("joint_names",
                             [](const Model& self) {
                               std::vector<std::string> names;
                               for (const auto& v : self.variables()) names.push_back(v.name);
                               return py_api::to_tuple(names);
                             })
      .def_property_readonly("joint_limits", [](const Model& self) { return py_api::joint_limits(self); })
      .def_property_readonly("mimic_joints", [](const Model& self) { return py_api::mimic_joints(self); })
      .def_property_readonly("home_values", [](const Model& self) { return py_api::to_tuple(self.home()); })
      .def("forward_kinematics",
           [](const Model& self, py::handle q, py::handle link) {
             const auto values = py_api::to_vector(q, "joint values");
             self.check_joint_vector(values, "joint values");
             const int index = self.link_index(py_api::to_optional_string(link, "link"));
             return py_api::pose(self.fk(values, index));
           })
      .def("forward_kinematics_batch",
           [](const Model& self, py::handle q, py::handle link) {
             std::size_t rows = 0;
             const auto data = batch_input(self, q, rows);
             const int index = self.link_index(py_api::to_optional_string(link, "link"));
             py::array_t<double> out({static_cast<py::ssize_t>(rows), py::ssize_t{4}, py::ssize_t{4}});
             double* dst = out.mutable_data();
             const KDL::Chain chain = self.chain_snapshot();  // under the GIL: no fk() runs now
             {
               py::gil_scoped_release release;
               self.fk_batch(chain, data.data(), rows, index, dst);
             }
             return out;
           })
      .def("inverse_kinematics", [](const Model& self, py::handle pose, py::handle seed, py::handle link) {
        const KDL::Frame target = py_api::to_frame(pose);
        std::vector<double> q = self.home();
        if (!seed.is_none()) {
          q = py_api::to_vector(seed, "seed");
          self.check_joint_vector(q, "seed");
        }
        const int index = self.link_index(py_api::to_optional_string(link, "link"));
        return py_api::ik_result(self.ik(target, q, index));
      });
}

}  // namespace rrosfuzz
