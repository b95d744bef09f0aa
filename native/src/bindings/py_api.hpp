// The Python side of the boundary: robot_api's records and errors, and the
// conversions between Python arguments and C++ values. Nothing else in the
// bindings touches Python types directly.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <kdl/frames.hpp>

#include <optional>
#include <string>
#include <vector>

#include "../model.hpp"
#include "../move_group.hpp"
#include "../trajectory.hpp"

namespace rrosfuzz::py_api {

namespace py = pybind11;

// Imports robot_api once, at module initialization.
void init();

// Python values -> C++ (each throws ApiError(kInvalidArgument) naming `what`).
std::vector<double> to_vector(py::handle h, const char* what);
std::vector<std::string> to_strings(py::handle h, const char* what);
std::string to_string(py::handle h, const char* what);
std::optional<std::string> to_optional_string(py::handle h, const char* what);
double to_real(py::handle h, const char* what);
bool is_real(py::handle h);
bool is_string(py::handle h);
bool is_sequence(py::handle h);  // list, tuple or ndarray
// A list's or tuple's items, read once as tuple() reads them (a subclass through its __iter__),
// so that converting them cannot change what is read.
py::tuple items(py::handle h, const char* what);
// A numpy.ma masked array with masked entries (they have no value): ApiError(code).
void refuse_masked(py::handle array, const char* what, ErrorCode code = ErrorCode::kInvalidArgument);
KDL::Frame to_frame(py::handle pose);  // robot_api.Pose or (position, orientation)
PoseParts to_pose_parts(py::handle pose);  // the same checks; unit quaternion (x, y, z, w)

// C++ -> Python (robot_api records).
py::object pose(const KDL::Frame& f);
py::object ik_result(const IkAnswer& a);
py::object joint_limits(const Model& m);
py::object mimic_joints(const Model& m);
py::object trajectory(const Model& m, const Trajectory& t);
bool is_trajectory(py::handle h);
py::object plan_result(const Model& m, const PlanOutcome& outcome);  // robot_api.PlanResult
py::object robot_state(const Model& m, const std::vector<double>& positions);  // robot_api.RobotState
py::list to_list(const std::vector<double>& v);
py::tuple to_tuple(const std::vector<double>& v);
py::tuple to_tuple(const std::vector<std::string>& v);

// robot_api.errors.make_error(code, message)
py::object make_error(int code, const std::string& message);

}  // namespace rrosfuzz::py_api
