// The compiled module rrosfuzz's `native` package wraps. Wiring only.
#include <pybind11/pybind11.h>

#include "../constants.hpp"
#include "py_api.hpp"

namespace py = pybind11;

namespace rrosfuzz {
void bind_errors(py::module_& m);
void bind_model(py::module_& m);
void bind_move_group(py::module_& m);
}  // namespace rrosfuzz

PYBIND11_MODULE(_native, m) {
  m.doc() = "Orocos KDL kinematics and a simulated MoveGroup (private; use the `native` package)";
  rrosfuzz::py_api::init();
  rrosfuzz::bind_errors(m);
  rrosfuzz::bind_model(m);
  rrosfuzz::bind_move_group(m);

  py::dict constants;
  constants["GOAL_JOINT_TOLERANCE"] = rrosfuzz::kGoalJointTolerance;
  constants["DEFAULT_VELOCITY_LIMIT"] = rrosfuzz::kDefaultVelocityLimit;
  constants["ACCELERATION_LIMIT"] = rrosfuzz::kAccelerationLimit;
  constants["TRAJECTORY_DT"] = rrosfuzz::kTrajectoryDt;
  constants["MAX_TRAJECTORY_DURATION"] = rrosfuzz::kMaxTrajectoryDuration;
  constants["IK_MAX_ITERATIONS"] = rrosfuzz::kIkMaxIterations;
  constants["IK_EPS"] = rrosfuzz::kIkEps;
  constants["IK_PINV_EPS"] = rrosfuzz::kIkPinvEps;
  constants["EXECUTE_START_TOLERANCE"] = rrosfuzz::kExecuteStartTolerance;
  constants["QUATERNION_NORM_EPS"] = rrosfuzz::kQuaternionNormEps;
  constants["CARTESIAN_MAX_POINTS"] = rrosfuzz::kCartesianMaxPoints;
  m.attr("constants") = constants;
}
