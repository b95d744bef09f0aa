// Python binding of MoveGroup (wrapped by native.MoveGroup).
#include <pybind11/pybind11.h>

#include <cmath>
#include <memory>

#include "../errors.hpp"
#include "../move_group.hpp"
#include "py_api.hpp"

namespace rrosfuzz {
namespace py = pybind11;

namespace {

// moveit_commander's accepted forms of set_joint_value_target (docs/api.md).
void set_joint_value_target(MoveGroup& g, py::handle arg1, py::handle arg2) {
  const char* what = "joint value target";
  if (arg2.is_none()) {
    if (PyDict_Check(arg1.ptr())) {
      std::vector<std::string> names;
      std::vector<double> values;
      // read once (PyDict_Items copies the pairs), so that converting a value cannot change the dict read
      const py::list pairs = py::reinterpret_steal<py::list>(PyDict_Items(arg1.ptr()));
      for (py::handle pair : pairs) {
        names.push_back(py_api::to_string(PyTuple_GET_ITEM(pair.ptr(), 0), what));
        values.push_back(py_api::to_real(PyTuple_GET_ITEM(pair.ptr(), 1), what));
      }
      g.set_target(names, values);
    } else if (py_api::is_sequence(arg1)) {
      g.set_target(py_api::to_vector(arg1, what));
    } else if (py_api::is_string(arg1)) {
      fail(ErrorCode::kInvalidArgument, "joint value target: joint name '" + py_api::to_string(arg1, what) +
                                            "' given without a value");
    } else {
      fail(ErrorCode::kInvalidArgument, std::string("joint value target: unsupported argument of type ") +
                                            Py_TYPE(arg1.ptr())->tp_name);
    }
  } else if (py_api::is_string(arg1)) {
    const std::string name = py_api::to_string(arg1, what);
    g.set_target(std::vector<std::string>{name}, std::vector<double>{py_api::to_real(arg2, what)});
  } else if (PyList_Check(arg1.ptr()) || PyTuple_Check(arg1.ptr())) {
    const auto names = py_api::to_strings(arg1, what);
    g.set_target(names, py_api::to_vector(arg2, what));
  } else {
    fail(ErrorCode::kInvalidArgument, std::string("joint value target: unsupported argument of type ") +
                                          Py_TYPE(arg1.ptr())->tp_name);
  }
}

void check_wait(py::handle wait) {
  if (!PyBool_Check(wait.ptr())) fail(ErrorCode::kInvalidArgument, "wait: expected a bool");
}

Trajectory to_trajectory(const MoveGroup& g, py::handle plan, std::vector<std::string>& names) {
  if (!py_api::is_trajectory(plan)) {
    fail(ErrorCode::kInvalidArgument, std::string("plan: expected a robot_api.RobotTrajectory, got ") +
                                          Py_TYPE(plan.ptr())->tp_name);
  }
  Trajectory t;
  t.dof = g.model().dof();
  try {
    names = py_api::to_strings(plan.attr("joint_names"), "trajectory joint names");
    t.time = py_api::to_vector(plan.attr("time_from_start"), "trajectory times");
  } catch (const ApiError& e) {
    fail(ErrorCode::kInvalidTrajectory, e.what());
  }
  py::object positions = plan.attr("positions");
  if (!py::isinstance<py::array>(positions)) fail(ErrorCode::kInvalidTrajectory, "trajectory positions: not an array");
  py::array a = py::reinterpret_borrow<py::array>(positions);
  const char kind = a.dtype().kind();
  if (a.ndim() != 2 || static_cast<std::size_t>(a.shape(0)) != t.time.size() ||
      static_cast<std::size_t>(a.shape(1)) != t.dof || (kind != 'f' && kind != 'i' && kind != 'u')) {
    fail(ErrorCode::kInvalidTrajectory, "trajectory positions: expected a real array of shape (M, dof) matching "
                                        "the times");
  }
  py_api::refuse_masked(positions, "trajectory positions", ErrorCode::kInvalidTrajectory);
  auto d = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!d) fail(ErrorCode::kInvalidTrajectory, "trajectory positions: cannot convert the array to float64");
  t.positions.assign(d.data(), d.data() + d.size());
  return t;
}

void set_position_target(MoveGroup& g, py::handle xyz, py::handle link) {
  const char* what = "position target";
  const std::vector<double> v = py_api::to_vector(xyz, what);
  if (v.size() != 3) fail(ErrorCode::kWrongLength, std::string(what) + ": expected 3 values, got " + std::to_string(v.size()));
  for (double x : v) {
    if (!std::isfinite(x)) fail(ErrorCode::kNonFinite, std::string(what) + " is not finite");
  }
  const int index = g.model().link_index(py_api::to_optional_string(link, "link"));
  g.set_pose_target(PoseParts{{v[0], v[1], v[2]}, {0.0, 0.0, 0.0, 1.0}}, index, true);
}

py::tuple compute_cartesian_path(const MoveGroup& g, py::handle waypoints, py::handle eef_step, py::handle jump) {
  if (!PyList_Check(waypoints.ptr()) && !PyTuple_Check(waypoints.ptr())) {
    fail(ErrorCode::kInvalidArgument, std::string("waypoints: expected a list or tuple of poses, got ") +
                                          Py_TYPE(waypoints.ptr())->tp_name);
  }
  std::vector<PoseParts> poses;
  for (py::handle w : py::reinterpret_borrow<py::sequence>(waypoints)) poses.push_back(py_api::to_pose_parts(w));
  if (poses.empty()) fail(ErrorCode::kInvalidArgument, "waypoints: no waypoints");
  const double step = py_api::to_real(eef_step, "eef_step");
  if (!std::isfinite(step) || !(step > 0.0)) fail(ErrorCode::kInvalidArgument, "eef_step: must be finite and > 0");
  const double factor = py_api::to_real(jump, "jump_threshold");
  if (!std::isfinite(factor) || !(factor >= 0.0)) {
    fail(ErrorCode::kInvalidArgument, "jump_threshold: must be finite and >= 0");
  }
  const CartesianPath path = g.compute_cartesian_path(poses, step, factor);
  return py::make_tuple(py_api::trajectory(g.model(), path.trajectory), path.fraction);
}

}  // namespace

void bind_move_group(py::module_& m) {
  py::class_<MoveGroup>(m, "MoveGroup")
      .def(py::init([](std::shared_ptr<Model> model) { return std::make_unique<MoveGroup>(std::move(model)); }))
      .def("get_active_joints",
           [](const MoveGroup& g) {
             py::list out;
             for (const auto& v : g.model().variables()) out.append(v.name);
             return out;
           })
      .def("get_end_effector_link", [](const MoveGroup& g) { return g.model().tip_link(); })
      .def("get_planning_frame", [](const MoveGroup& g) { return g.model().root_link(); })
      .def("get_current_joint_values", [](const MoveGroup& g) { return py_api::to_list(g.current()); })
      .def("get_joint_value_target", [](const MoveGroup& g) { return py_api::to_list(g.target()); })
      .def("get_current_state", [](const MoveGroup& g) { return py_api::robot_state(g.model(), g.current()); })
      .def("get_current_pose",
           [](const MoveGroup& g, py::handle link) {
             const int index = g.model().link_index(py_api::to_optional_string(link, "link"));
             return py_api::pose(g.model().fk(g.current(), index));
           })
      .def("set_joint_value_target", &set_joint_value_target)
      .def("set_named_target",
           [](MoveGroup& g, py::handle name) { g.set_named_target(py_api::to_string(name, "named target")); })
      .def("get_named_targets",
           [](const MoveGroup& g) {
             py::list out;
             for (const auto& name : g.named_targets()) out.append(py::str(name));
             return out;
           })
      .def("get_named_target_values",
           [](const MoveGroup& g, py::handle name) {
             const auto& values = g.named_target(py_api::to_string(name, "named target"));
             py::dict out;
             const auto& vars = g.model().variables();
             for (std::size_t i = 0; i < vars.size(); ++i) out[py::str(vars[i].name)] = py::float_(values[i]);
             return out;
           })
      .def("remember_joint_values",
           [](MoveGroup& g, py::handle name, py::handle values) {
             const std::string key = py_api::to_string(name, "named target");
             if (values.is_none()) {
               g.remember(key, std::nullopt);
             } else {
               g.remember(key, py_api::to_vector(values, "remembered joint values"));
             }
           })
      .def("set_goal_joint_tolerance",
           [](MoveGroup& g, py::handle v) { g.set_goal_tolerance(py_api::to_real(v, "goal joint tolerance")); })
      .def("get_goal_joint_tolerance", &MoveGroup::goal_tolerance)
      .def("set_max_velocity_scaling_factor",
           [](MoveGroup& g, py::handle v) { g.set_velocity_scaling(py_api::to_real(v, "max velocity scaling factor")); })
      .def("set_max_acceleration_scaling_factor",
           [](MoveGroup& g, py::handle v) {
             g.set_acceleration_scaling(py_api::to_real(v, "max acceleration scaling factor"));
           })
      .def("set_pose_target",
           [](MoveGroup& g, py::handle pose, py::handle link) {
             const PoseParts parts = py_api::to_pose_parts(pose);
             g.set_pose_target(parts, g.model().link_index(py_api::to_optional_string(link, "link")), false);
           })
      .def("set_position_target", &set_position_target)
      .def("clear_pose_targets", &MoveGroup::clear_pose_targets)
      .def("plan",
           [](MoveGroup& g, py::handle joints) {
             if (!joints.is_none()) set_joint_value_target(g, joints, py::none());
             return py_api::plan_result(g.model(), g.plan_outcome());
           })
      .def("stop", [](const MoveGroup&) {})
      .def("compute_cartesian_path", &compute_cartesian_path)
      .def("execute",
           [](MoveGroup& g, py::handle plan, py::handle wait) {
             std::vector<std::string> names;
             Trajectory t = to_trajectory(g, plan, names);
             check_wait(wait);
             g.execute(names, t);
             return true;
           })
      .def("go", [](MoveGroup& g, py::handle joints, py::handle wait) {
        check_wait(wait);  // first: a refused go() changes nothing
        if (!joints.is_none()) set_joint_value_target(g, joints, py::none());
        return g.go();
      });
}

}  // namespace rrosfuzz
