// Numbers of the contract (docs/api.md); robot_api/constants.py holds the same
// values and tests/test_parity.py checks that both agree.
#pragma once

namespace rrosfuzz {

constexpr double kGoalJointTolerance = 1e-4;
constexpr double kDefaultVelocityLimit = 1.0;
constexpr double kAccelerationLimit = 1.0;
constexpr double kTrajectoryDt = 0.01;
constexpr double kMaxTrajectoryDuration = 600.0;
constexpr unsigned kIkMaxIterations = 100;
constexpr double kIkEps = 1e-6;
constexpr double kIkPinvEps = 1e-5;
constexpr int kIkSvdIterations = 150;
constexpr double kExecuteStartTolerance = 0.01;
constexpr double kQuaternionNormEps = 1e-9;
constexpr unsigned kCartesianMaxPoints = 1000;

}  // namespace rrosfuzz
