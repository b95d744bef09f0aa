// Straight-line joint-space trajectories with a synchronized trapezoidal
// velocity profile, sampled at a fixed period (docs/api.md, "plan()"), and the
// same trapezoid on the path coordinate of a joint-space polyline
// (docs/api.md, "compute_cartesian_path").
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

// Times the polyline through `points` (at least one, within limits): exact repeats
// are dropped, the path coordinate grows by max_j |delta_j| / vmax_j per segment
// and follows plan()'s trapezoid with du/dt <= 1. Throws kPlanningFailed.
Trajectory time_parameterize(const Model& model, const std::vector<std::vector<double>>& points,
                             double velocity_scaling, double acceleration_scaling);

}  // namespace rrosfuzz
