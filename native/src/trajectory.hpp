// Straight-line joint-space trajectories with a synchronized trapezoidal
// velocity profile, sampled at a fixed period (docs/api.md, "plan()").
#pragma once

#include <cstddef>
#include <vector>

#include "model.hpp"

namespace rrosfuzz {

struct Trajectory {
  std::size_t dof = 0;
  std::vector<double> time;          // M samples
  std::vector<double> positions;     // M x dof, row-major
  std::vector<double> velocities;    // M x dof
  std::vector<double> accelerations; // M x dof
  std::size_t size() const { return time.size(); }
};

// start and goal are within limits (continuous joints in (-pi, pi]).
Trajectory plan_trajectory(const Model& model, const std::vector<double>& start, const std::vector<double>& goal,
                           double velocity_scaling, double acceleration_scaling);

}  // namespace rrosfuzz
