#include "py_api.hpp"

#include <algorithm>
#include <cmath>

#include "../constants.hpp"
#include "../errors.hpp"

namespace rrosfuzz::py_api {
namespace {

// Handles into robot_api, created once and deliberately never freed (they must
// outlive module teardown at interpreter exit).
struct Handles {
  py::object pose, ik_result, ik_success, ik_no_solution, joint_limit, mimic_joint, trajectory, make_error;
  py::object plan_result, moveit_error_code, robot_state, joint_state;
  py::object joint_type_revolute, joint_type_continuous, joint_type_prismatic;
  py::object ndarray, masked_array, is_masked, generic;
};
Handles* handles = nullptr;

[[noreturn]] void bad(const char* what, const std::string& why) {
  fail(ErrorCode::kInvalidArgument, std::string(what) + ": " + why);
}

std::string type_of(py::handle h) { return Py_TYPE(h.ptr())->tp_name; }

// The Python error set now, when it is an Exception (the argument's fault: cleared, and the caller
// raises ApiError); a BaseException that is not one (KeyboardInterrupt, SystemExit) propagates.
void clear_or_propagate() {
  if (!PyErr_ExceptionMatches(PyExc_Exception)) throw py::error_already_set();
  PyErr_Clear();
}

}  // namespace

void init() {
  if (handles) return;
  auto records = py::module_::import("robot_api.records");
  auto errors = py::module_::import("robot_api.errors");
  handles = new Handles();
  handles->pose = records.attr("Pose");
  handles->ik_result = records.attr("IKResult");
  handles->ik_success = records.attr("IKStatus").attr("SUCCESS");
  handles->ik_no_solution = records.attr("IKStatus").attr("NO_SOLUTION");
  handles->joint_limit = records.attr("JointLimit");
  handles->mimic_joint = records.attr("MimicJoint");
  handles->trajectory = records.attr("RobotTrajectory");
  handles->joint_type_revolute = records.attr("JointType").attr("REVOLUTE");
  handles->joint_type_continuous = records.attr("JointType").attr("CONTINUOUS");
  handles->joint_type_prismatic = records.attr("JointType").attr("PRISMATIC");
  handles->make_error = errors.attr("make_error");
  handles->plan_result = records.attr("PlanResult");
  handles->moveit_error_code = records.attr("MoveItErrorCode");
  handles->robot_state = records.attr("RobotState");
  handles->joint_state = records.attr("JointState");
  handles->ndarray = py::module_::import("numpy").attr("ndarray");
  handles->generic = py::module_::import("numpy").attr("generic");
  auto ma = py::module_::import("numpy.ma");
  handles->masked_array = ma.attr("MaskedArray");
  handles->is_masked = ma.attr("is_masked");
}

bool is_string(py::handle h) { return PyUnicode_Check(h.ptr()); }

bool is_real(py::handle h) {
  PyObject* o = h.ptr();
  if (PyFloat_CheckExact(o) || PyLong_CheckExact(o)) return true;
  if (PyBool_Check(o) || PyUnicode_Check(o) || PyBytes_Check(o) || PyByteArray_Check(o)) return false;
  const bool scalar = py::isinstance(h, handles->generic);
  if (scalar || py::isinstance(h, handles->ndarray)) {  // a numpy scalar or 0-d array: by its dtype
    if (!scalar && h.attr("ndim").cast<long>() != 0) return false;  // an array is no number
    const char kind = h.attr("dtype").attr("kind").cast<std::string>().at(0);
    return kind == 'f' || kind == 'i' || kind == 'u';
  }
  if (PyFloat_Check(o) || PyLong_Check(o)) return true;
  return Py_TYPE(o)->tp_as_number != nullptr && Py_TYPE(o)->tp_as_number->nb_float != nullptr;
}

double to_real(py::handle h, const char* what) {
  if (!is_real(h)) bad(what, "expected a real number, got " + type_of(h));
  if (PyFloat_Check(h.ptr()) && !PyFloat_CheckExact(h.ptr())) {
    // a float subclass: its own __float__, as float() (the twin) calls it; PyFloat_AsDouble
    // read the stored value and skipped it
    PyObject* f = PyNumber_Float(h.ptr());
    if (f == nullptr) {
      clear_or_propagate();
      bad(what, "cannot convert " + type_of(h) + " to a float");
    }
    const double v = PyFloat_AS_DOUBLE(f);
    Py_DECREF(f);
    return v;
  }
  const double v = PyFloat_AsDouble(h.ptr());
  if (v == -1.0 && PyErr_Occurred()) {
    clear_or_propagate();
    bad(what, "cannot convert " + type_of(h) + " to a float");
  }
  return v;
}

bool is_sequence(py::handle h) {
  return PyList_Check(h.ptr()) || PyTuple_Check(h.ptr()) || py::isinstance(h, handles->ndarray);
}

py::tuple items(py::handle h, const char* what) {
  PyObject* t = PySequence_Tuple(h.ptr());
  if (!t) {
    clear_or_propagate();
    bad(what, "cannot read the " + type_of(h));
  }
  return py::reinterpret_steal<py::tuple>(t);
}

void refuse_masked(py::handle array, const char* what, ErrorCode code) {
  if (Py_TYPE(array.ptr()) == reinterpret_cast<PyTypeObject*>(handles->ndarray.ptr())) return;  // not a subclass
  if (py::isinstance(array, handles->masked_array) && handles->is_masked(array).cast<bool>()) {
    fail(code, std::string(what) + ": a masked array with masked entries (they have no value)");
  }
}

std::vector<double> to_vector(py::handle h, const char* what) {
  if (PyList_Check(h.ptr()) || PyTuple_Check(h.ptr())) {
    const py::tuple seq = items(h, what);
    const std::size_t n = seq.size();
    std::vector<double> out(n);
    for (std::size_t i = 0; i < n; ++i) out[i] = to_real(seq[i], what);
    return out;
  }
  if (py::isinstance(h, handles->ndarray)) {
    py::array a = py::reinterpret_borrow<py::array>(h);
    const char kind = a.dtype().kind();
    if (a.ndim() != 1) bad(what, "expected a 1-D array, got " + std::to_string(a.ndim()) + "-D");
    if (kind != 'f' && kind != 'i' && kind != 'u') bad(what, std::string("array of kind '") + kind + "' is not real");
    refuse_masked(h, what);
    auto d = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
    // ensure() clears the error it met (no memory for the copy), so there is none to propagate:
    // clear_or_propagate() threw pybind11's "error_already_set called while Python error
    // indicator not set" here
    if (!d) bad(what, "cannot convert the array to float64");
    return std::vector<double>(d.data(), d.data() + d.size());
  }
  bad(what, "expected a list, tuple or 1-D array of numbers, got " + type_of(h));
}

std::vector<std::string> to_strings(py::handle h, const char* what) {
  if (!PyList_Check(h.ptr()) && !PyTuple_Check(h.ptr())) bad(what, "expected a list or tuple of names, got " + type_of(h));
  std::vector<std::string> out;
  for (py::handle item : items(h, what)) out.push_back(to_string(item, what));
  return out;
}

std::string to_string(py::handle h, const char* what) {
  if (!PyUnicode_Check(h.ptr())) bad(what, "expected a str, got " + type_of(h));
  Py_ssize_t size = 0;
  const char* data = PyUnicode_AsUTF8AndSize(h.ptr(), &size);
  if (!data) {
    PyErr_Clear();
    bad(what, "string is not valid UTF-8");
  }
  return std::string(data, static_cast<std::size_t>(size));
}

std::optional<std::string> to_optional_string(py::handle h, const char* what) {
  if (h.is_none()) return std::nullopt;
  return to_string(h, what);
}

KDL::Frame to_frame(py::handle pose) {
  const PoseParts parts = to_pose_parts(pose);
  return KDL::Frame(KDL::Rotation::Quaternion(parts.q[0], parts.q[1], parts.q[2], parts.q[3]),
                    KDL::Vector(parts.p[0], parts.p[1], parts.p[2]));
}

PoseParts to_pose_parts(py::handle pose) {
  if (!PyTuple_Check(pose.ptr()) && !PyList_Check(pose.ptr())) {
    bad("pose", "expected a robot_api.Pose or a (position, orientation) pair, got " + type_of(pose));
  }
  const py::tuple pair = items(pose, "pose");
  if (pair.size() != 2) bad("pose", "expected a (position, orientation) pair");
  const auto p = to_vector(pair[0], "pose position");
  const auto q = to_vector(pair[1], "pose orientation");
  if (p.size() != 3) bad("pose position", "expected 3 values, got " + std::to_string(p.size()));
  if (q.size() != 4) bad("pose orientation", "expected 4 values (x, y, z, w), got " + std::to_string(q.size()));
  for (double v : p) {
    if (!std::isfinite(v)) fail(ErrorCode::kNonFinite, "pose position is not finite");
  }
  for (double v : q) {
    if (!std::isfinite(v)) fail(ErrorCode::kNonFinite, "pose orientation is not finite");
  }
  // Scaled by the largest component first: squaring 1e154 would overflow the norm to inf.
  const double scale = std::max({std::fabs(q[0]), std::fabs(q[1]), std::fabs(q[2]), std::fabs(q[3])});
  const double x = scale > 0.0 ? q[0] / scale : 0.0, y = scale > 0.0 ? q[1] / scale : 0.0;
  const double z = scale > 0.0 ? q[2] / scale : 0.0, w = scale > 0.0 ? q[3] / scale : 0.0;
  const double unit = std::sqrt(x * x + y * y + z * z + w * w);
  if (!(scale * unit >= kQuaternionNormEps)) bad("pose orientation", "quaternion has (near) zero norm");
  return PoseParts{{p[0], p[1], p[2]}, {x / unit, y / unit, z / unit, w / unit}};
}

py::object pose(const KDL::Frame& f) {
  double q[4];
  canonical_quaternion(f.M, q);
  return handles->pose(py::make_tuple(f.p.x(), f.p.y(), f.p.z()), py::make_tuple(q[0], q[1], q[2], q[3]));
}

py::object ik_result(const IkAnswer& a) {
  return handles->ik_result(a.status == IkStatus::kSuccess ? handles->ik_success : handles->ik_no_solution,
                            to_tuple(a.joint_values), a.position_error, a.orientation_error);
}

py::object joint_limits(const Model& m) {
  py::list out;
  for (const auto& v : m.variables()) {
    py::object type = v.kind == JointKind::kRevolute     ? handles->joint_type_revolute
                      : v.kind == JointKind::kContinuous ? handles->joint_type_continuous
                                                         : handles->joint_type_prismatic;
    out.append(handles->joint_limit(v.name, type, v.lower, v.upper, v.velocity));
  }
  return py::tuple(out);
}

py::object mimic_joints(const Model& m) {
  py::list out;
  for (const auto& mi : m.mimics()) out.append(handles->mimic_joint(mi.name, mi.master, mi.multiplier, mi.offset));
  return py::tuple(out);
}

py::object trajectory(const Model& m, const Trajectory& t) {
  const py::ssize_t rows = static_cast<py::ssize_t>(t.size());
  const py::ssize_t cols = static_cast<py::ssize_t>(t.dof);
  auto matrix = [&](const std::vector<double>& v) {
    py::array_t<double> a({rows, cols});
    std::copy(v.begin(), v.end(), a.mutable_data());
    return a;
  };
  py::array_t<double> times(rows);
  std::copy(t.time.begin(), t.time.end(), times.mutable_data());
  std::vector<std::string> names;
  for (const auto& v : m.variables()) names.push_back(v.name);
  return handles->trajectory(to_tuple(names), times, matrix(t.positions), matrix(t.velocities),
                             matrix(t.accelerations));
}

bool is_trajectory(py::handle h) { return py::isinstance(h, handles->trajectory); }

py::object plan_result(const Model& m, const PlanOutcome& outcome) {
  return handles->plan_result(outcome.code == PlanCode::kSuccess, trajectory(m, outcome.trajectory), 0.0,
                              handles->moveit_error_code(static_cast<int>(outcome.code)));
}

py::object robot_state(const Model& m, const std::vector<double>& positions) {
  std::vector<std::string> names;
  for (const auto& v : m.variables()) names.push_back(v.name);
  return handles->robot_state(handles->joint_state(to_tuple(names), to_tuple(positions)));
}

py::list to_list(const std::vector<double>& v) {
  py::list out(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) out[i] = py::float_(v[i]);
  return out;
}

py::tuple to_tuple(const std::vector<double>& v) {
  py::tuple out(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) out[i] = py::float_(v[i]);
  return out;
}

py::tuple to_tuple(const std::vector<std::string>& v) {
  py::tuple out(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) out[i] = py::str(v[i]);
  return out;
}

py::object make_error(int code, const std::string& message) { return handles->make_error(code, message); }

}  // namespace rrosfuzz::py_api
