#include "trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "angles.hpp"
#include "constants.hpp"
#include "errors.hpp"

namespace rrosfuzz {
namespace {

// Position, velocity and acceleration of the normalized path s in [0, 1].
struct Profile {
  double ta, total, peak, accel;

  void at(double t, double& s, double& sd, double& sdd) const {
    if (t < ta) {
      s = 0.5 * accel * t * t;
      sd = accel * t;
      sdd = accel;
    } else if (t < total - ta) {
      s = 0.5 * accel * ta * ta + peak * (t - ta);
      sd = peak;
      sdd = 0.0;
    } else {
      const double r = total - t;
      s = 1.0 - 0.5 * accel * r * r;
      sd = accel * r;
      sdd = -accel;
    }
  }
};

}  // namespace

Trajectory plan_trajectory(const Model& model, const std::vector<double>& start, const std::vector<double>& goal,
                           double velocity_scaling, double acceleration_scaling) {
  const auto& vars = model.variables();
  const std::size_t n = vars.size();
  Trajectory traj;
  traj.dof = n;

  std::vector<double> delta(n);
  double vs = std::numeric_limits<double>::infinity();
  double as = std::numeric_limits<double>::infinity();
  bool moving = false;
  for (std::size_t j = 0; j < n; ++j) {
    delta[j] = goal[j] - start[j];
    if (vars[j].kind == JointKind::kContinuous) delta[j] = normalize_angle(delta[j]);
    const double d = std::fabs(delta[j]);
    if (d > 0.0) {
      moving = true;
      vs = std::min(vs, vars[j].velocity * velocity_scaling / d);
      as = std::min(as, kAccelerationLimit * acceleration_scaling / d);
    }
  }

  auto push_row = [&](double t, const double* p, double sd, double sdd) {
    traj.time.push_back(t);
    for (std::size_t j = 0; j < n; ++j) {
      traj.positions.push_back(p[j]);
      traj.velocities.push_back(delta[j] * sd);
      traj.accelerations.push_back(delta[j] * sdd);
    }
  };

  if (!moving) {
    push_row(0.0, goal.data(), 0.0, 0.0);
    return traj;
  }

  Profile prof;
  prof.accel = as;
  if (vs * vs < as) {  // reaches cruise speed
    prof.ta = vs / as;
    prof.total = 1.0 / vs + prof.ta;
    prof.peak = vs;
  } else {  // triangular
    prof.ta = std::sqrt(1.0 / as);
    prof.total = 2.0 * prof.ta;
    prof.peak = as * prof.ta;
  }

  if (!(prof.total <= kMaxTrajectoryDuration)) {
    std::ostringstream msg;
    msg.precision(17);
    msg << "the move would last " << prof.total << " s, more than " << kMaxTrajectoryDuration << " s";
    fail(ErrorCode::kPlanningFailed, msg.str());
  }
  const std::size_t k = static_cast<std::size_t>(std::ceil(prof.total / kTrajectoryDt));
  std::vector<double> row(n);
  for (std::size_t i = 0; i < k; ++i) {
    const double t = static_cast<double>(i) * kTrajectoryDt;
    if (!(t < prof.total)) break;
    double s, sd, sdd;
    prof.at(t, s, sd, sdd);
    for (std::size_t j = 0; j < n; ++j) {
      row[j] = start[j] + delta[j] * s;
      row[j] = vars[j].kind == JointKind::kContinuous ? normalize_angle(row[j])
                                                      : std::clamp(row[j], vars[j].lower, vars[j].upper);
    }
    push_row(t, row.data(), sd, sdd);
  }
  push_row(prof.total, goal.data(), 0.0, 0.0);
  return traj;
}

}  // namespace rrosfuzz
