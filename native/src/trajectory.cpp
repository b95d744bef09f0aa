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

Trajectory time_parameterize(const Model& model, const std::vector<std::vector<double>>& points,
                             double velocity_scaling, double acceleration_scaling) {
  const auto& vars = model.variables();
  const std::size_t n = vars.size();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Trajectory traj;
  traj.dof = n;

  // Exact repeats dropped; per segment the delta (continuous: short way) and its cost.
  std::vector<const std::vector<double>*> kept{&points.front()};
  std::vector<std::vector<double>> deltas;
  std::vector<double> costs;
  for (std::size_t k = 1; k < points.size(); ++k) {
    const std::vector<double>& prev = *kept.back();
    std::vector<double> delta(n);
    double cost = 0.0;
    for (std::size_t j = 0; j < n; ++j) {
      double d = points[k][j] - prev[j];
      if (vars[j].kind == JointKind::kContinuous) d = normalize_angle(d);
      delta[j] = d;
      if (d != 0.0) {
        const double vmax = vars[j].velocity * velocity_scaling;
        cost = std::max(cost, vmax > 0.0 ? std::fabs(d) / vmax : kInf);
      }
    }
    if (cost > 0.0) {
      kept.push_back(&points[k]);
      deltas.push_back(std::move(delta));
      costs.push_back(cost);
    }
  }

  auto push_row = [&](double t, const std::vector<double>& p, const std::vector<double>& v,
                      const std::vector<double>& a) {
    traj.time.push_back(t);
    traj.positions.insert(traj.positions.end(), p.begin(), p.end());
    traj.velocities.insert(traj.velocities.end(), v.begin(), v.end());
    traj.accelerations.insert(traj.accelerations.end(), a.begin(), a.end());
  };
  auto pop_row = [&] {
    traj.time.pop_back();
    traj.positions.resize(traj.positions.size() - n);
    traj.velocities.resize(traj.velocities.size() - n);
    traj.accelerations.resize(traj.accelerations.size() - n);
  };
  const std::vector<double> zero(n, 0.0);
  if (costs.empty()) {
    push_row(0.0, *kept.front(), zero, zero);
    return traj;
  }

  const double amax = kAccelerationLimit * acceleration_scaling;
  double total_u = 0.0;
  double accel = kInf;
  for (std::size_t k = 0; k < costs.size(); ++k) {
    total_u += costs[k];
    for (double d : deltas[k]) {
      if (d != 0.0) accel = std::min(accel, amax * costs[k] / std::fabs(d));
    }
  }
  std::ostringstream msg;
  msg.precision(17);
  if (!(accel > 0.0 && total_u < kInf)) {
    msg << "the path would never end (length " << total_u << ", acceleration bound " << accel << ")";
    fail(ErrorCode::kPlanningFailed, msg.str());
  }
  double ta, total, peak;
  if (accel * total_u > 1.0) {  // reaches the cruise speed du/dt = 1
    ta = 1.0 / accel;
    total = total_u + ta;
    peak = 1.0;
  } else {  // triangular
    ta = std::sqrt(total_u / accel);
    total = 2.0 * ta;
    peak = accel * ta;
  }
  if (!(total <= kMaxTrajectoryDuration)) {
    msg << "the path would last " << total << " s, more than " << kMaxTrajectoryDuration << " s";
    fail(ErrorCode::kPlanningFailed, msg.str());
  }
  const double ua = 0.5 * accel * ta * ta;
  std::vector<double> v(n), a(n);
  for (std::size_t j = 0; j < n; ++j) a[j] = deltas[0][j] * (accel / costs[0]);
  push_row(0.0, *kept.front(), zero, a);
  double u = 0.0;
  const std::size_t last = costs.size() - 1;
  for (std::size_t k = 0; k < costs.size(); ++k) {
    u += costs[k];  // the same sums as total_u: the last point has u == total_u exactly
    double t, ud, udd;
    if (u < ua) {
      t = std::sqrt(2.0 * u / accel);
      ud = accel * t;
      udd = accel;
    } else if (u <= total_u - ua) {
      t = ta + (u - ua) / peak;
      ud = peak;
      udd = 0.0;
    } else {
      const double r = std::sqrt(2.0 * (total_u - u) / accel);
      t = total - r;
      ud = accel * r;
      udd = -accel;
    }
    if (k == last) {
      if (!(t > traj.time.back())) {  // the end takes the place (and time) of the point before
        t = traj.time.back();
        pop_row();
      }
      push_row(t, *kept[k + 1], zero, zero);
    } else if (t > traj.time.back()) {
      for (std::size_t j = 0; j < n; ++j) {
        v[j] = deltas[k][j] * (ud / costs[k]);
        a[j] = deltas[k][j] * (udd / costs[k]);
      }
      push_row(t, *kept[k + 1], v, a);
    }
  }
  return traj;
}

}  // namespace rrosfuzz
