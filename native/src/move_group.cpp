#include "move_group.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

#include "angles.hpp"
#include "constants.hpp"
#include "errors.hpp"

namespace rrosfuzz {
namespace {

std::string num(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

// The pose rule's normalization (docs/api.md, "Arguments"), then KDL's rotation.
KDL::Frame make_frame(const double p[3], const double q[4]) {
  const double scale = std::max({std::fabs(q[0]), std::fabs(q[1]), std::fabs(q[2]), std::fabs(q[3])});
  const double x = q[0] / scale, y = q[1] / scale, z = q[2] / scale, w = q[3] / scale;
  const double unit = std::sqrt(x * x + y * y + z * z + w * w);
  return KDL::Frame(KDL::Rotation::Quaternion(x / unit, y / unit, z / unit, w / unit), KDL::Vector(p[0], p[1], p[2]));
}

// MoveIt's RobotState::distance: per-joint distances summed, continuous joints the short way.
double joint_distance(const std::vector<Variable>& vars, const std::vector<double>& a, const std::vector<double>& b) {
  double total = 0.0;
  for (std::size_t j = 0; j < vars.size(); ++j) {
    const double d = a[j] - b[j];
    total += vars[j].kind == JointKind::kContinuous ? std::fabs(normalize_angle(d)) : std::fabs(d);
  }
  return total;
}

// MoveIt's relative jump test: truncates `points` and returns the share kept.
double jump_test(const std::vector<Variable>& vars, std::vector<std::vector<double>>& points, double factor) {
  if (points.size() < 2) return 1.0;
  std::vector<double> steps;
  for (std::size_t i = 1; i < points.size(); ++i) steps.push_back(joint_distance(vars, points[i], points[i - 1]));
  double total = 0.0;
  for (double d : steps) total += d;
  const double threshold = factor * (total / static_cast<double>(steps.size()));
  for (std::size_t i = 0; i < steps.size(); ++i) {
    if (steps[i] > threshold) {
      const double share = static_cast<double>(i + 1) / static_cast<double>(points.size());
      points.resize(i + 1);
      return share;
    }
  }
  return 1.0;
}

void check_scaling(double value, const char* what) {
  if (!std::isfinite(value) || value <= 0.0 || value > 1.0) {
    fail(ErrorCode::kInvalidArgument, std::string(what) + " must be in (0, 1], got " + num(value));
  }
}

}  // namespace

MoveGroup::MoveGroup(std::shared_ptr<const Model> model)
    : model_(std::move(model)), tolerance_(kGoalJointTolerance) {
  current_ = model_->home();
  target_ = current_;
  named_["home"] = current_;
}

double MoveGroup::accept(std::size_t i, double value) const {
  const Variable& v = model_->variables()[i];
  if (v.kind == JointKind::kContinuous) return normalize_angle(value);
  if (value < v.lower - tolerance_ || value > v.upper + tolerance_) {
    fail(ErrorCode::kOutOfBounds, "target " + num(value) + " of joint '" + v.name + "' is outside its limits [" +
                                      num(v.lower) + ", " + num(v.upper) + "]");
  }
  return std::clamp(value, v.lower, v.upper);
}

void MoveGroup::set_target(const std::vector<double>& values) {
  model_->check_joint_vector(values, "joint value target");
  std::vector<double> next(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) next[i] = accept(i, values[i]);
  target_ = std::move(next);
  pose_goal_.reset();
}

void MoveGroup::set_target(const std::vector<std::string>& names, const std::vector<double>& values) {
  if (names.size() != values.size()) {
    fail(ErrorCode::kWrongLength, "joint value target: " + std::to_string(names.size()) + " names but " +
                                      std::to_string(values.size()) + " values");
  }
  std::vector<int> index(names.size());
  for (std::size_t k = 0; k < names.size(); ++k) {
    index[k] = model_->variable_index(names[k]);
    if (index[k] < 0) fail(ErrorCode::kUnknownJoint, "joint '" + names[k] + "' is not an active joint of the group");
  }
  std::set<int> seen;
  for (std::size_t k = 0; k < names.size(); ++k) {
    if (!seen.insert(index[k]).second) fail(ErrorCode::kDuplicateName, "joint '" + names[k] + "' is given twice");
  }
  for (std::size_t k = 0; k < names.size(); ++k) {
    if (!std::isfinite(values[k])) fail(ErrorCode::kNonFinite, "value of joint '" + names[k] + "' is not finite");
  }
  std::vector<double> next = target_;
  for (std::size_t k = 0; k < names.size(); ++k) next[index[k]] = accept(index[k], values[k]);
  target_ = std::move(next);
  pose_goal_.reset();
}

void MoveGroup::set_named_target(const std::string& name) { set_target(named_target(name)); }

std::vector<std::string> MoveGroup::named_targets() const {
  std::vector<std::string> out;
  for (const auto& kv : named_) out.push_back(kv.first);
  return out;  // std::map keeps them sorted
}

const std::vector<double>& MoveGroup::named_target(const std::string& name) const {
  auto it = named_.find(name);
  if (it == named_.end()) fail(ErrorCode::kUnknownNamedTarget, "no named target '" + name + "'");
  return it->second;
}

void MoveGroup::remember(const std::string& name, const std::optional<std::vector<double>>& values) {
  if (values) {
    model_->check_joint_vector(*values, "remembered joint values");
    named_[name] = *values;
  } else {
    named_[name] = current_;
  }
}

void MoveGroup::set_goal_tolerance(double value) {
  if (!std::isfinite(value) || value < 0.0) {
    fail(ErrorCode::kInvalidArgument, "goal joint tolerance must be finite and >= 0, got " + num(value));
  }
  tolerance_ = value;
}

void MoveGroup::set_velocity_scaling(double value) {
  check_scaling(value, "max velocity scaling factor");
  velocity_scaling_ = value;
}

void MoveGroup::set_acceleration_scaling(double value) {
  check_scaling(value, "max acceleration scaling factor");
  acceleration_scaling_ = value;
}

void MoveGroup::set_pose_target(const PoseParts& pose, int link, bool position_only) {
  pose_goal_ = PoseGoal{pose, link, position_only};
}

std::vector<double> MoveGroup::goal() const {
  if (!pose_goal_) return target_;
  const PoseGoal& g = *pose_goal_;
  KDL::Frame target;
  if (g.position_only) {
    target = KDL::Frame(model_->fk(current_, g.link).M, KDL::Vector(g.pose.p[0], g.pose.p[1], g.pose.p[2]));
  } else {
    target = make_frame(g.pose.p, g.pose.q);
  }
  IkAnswer answer = model_->ik(target, current_, g.link);
  if (answer.status != IkStatus::kSuccess) throw NoIkSolution("no IK solution for the pose target from the current state");
  return std::move(answer.joint_values);
}

Trajectory MoveGroup::plan() const {
  return plan_trajectory(*model_, current_, goal(), velocity_scaling_, acceleration_scaling_);
}

PlanOutcome MoveGroup::plan_outcome() const {
  PlanOutcome out;
  out.code = PlanCode::kSuccess;
  try {
    out.trajectory = plan();
  } catch (const NoIkSolution&) {
    out.code = PlanCode::kNoIkSolution;
  } catch (const ApiError& e) {
    if (e.code() != ErrorCode::kPlanningFailed) throw;
    out.code = PlanCode::kPlanningFailed;
  }
  if (out.code != PlanCode::kSuccess) {
    out.trajectory = Trajectory();
    out.trajectory.dof = model_->dof();
  }
  return out;
}

CartesianPath MoveGroup::compute_cartesian_path(const std::vector<PoseParts>& waypoints, double eef_step,
                                                double jump_threshold) const {
  const int tip = static_cast<int>(model_->link_names().size()) - 1;
  const KDL::Frame here = model_->fk(current_, tip);
  PoseParts start{{here.p.x(), here.p.y(), here.p.z()}, {0.0, 0.0, 0.0, 1.0}};
  canonical_quaternion(here.M, start.q);

  // Steps per segment, all checked before any IK.
  const std::string too_many = "the path needs more than " + std::to_string(kCartesianMaxPoints) + " points at this eef_step";
  std::vector<std::size_t> counts;
  std::size_t total = 1;  // the start point
  const double* prev_p = start.p;
  for (const PoseParts& w : waypoints) {
    const double dx = w.p[0] - prev_p[0], dy = w.p[1] - prev_p[1], dz = w.p[2] - prev_p[2];
    const double ratio = std::sqrt(dx * dx + dy * dy + dz * dz) / eef_step;
    if (!(ratio < static_cast<double>(kCartesianMaxPoints))) fail(ErrorCode::kPlanningFailed, too_many);
    const std::size_t steps = static_cast<std::size_t>(std::floor(ratio)) + 1;
    total += steps;
    if (total > kCartesianMaxPoints) fail(ErrorCode::kPlanningFailed, too_many);
    counts.push_back(steps);
    prev_p = w.p;
  }

  std::vector<std::vector<double>> points{current_};
  std::vector<double> q = current_;
  double fraction = 0.0;
  const double n_waypoints = static_cast<double>(waypoints.size());
  const PoseParts* prev = &start;
  for (std::size_t i = 0; i < waypoints.size(); ++i) {
    const PoseParts& w = waypoints[i];
    const std::size_t steps = counts[i];
    const Eigen::Quaterniond qa(prev->q[3], prev->q[0], prev->q[1], prev->q[2]);
    const Eigen::Quaterniond qb(w.q[3], w.q[0], w.q[1], w.q[2]);
    std::size_t reached = 0;
    for (std::size_t k = 1; k <= steps; ++k) {
      const double t = static_cast<double>(k) / static_cast<double>(steps);
      double p[3];
      for (int c = 0; c < 3; ++c) p[c] = t * w.p[c] + (1.0 - t) * prev->p[c];
      const Eigen::Quaterniond qs = qa.slerp(t, qb);
      const double qv[4] = {qs.x(), qs.y(), qs.z(), qs.w()};
      IkAnswer answer = model_->ik(make_frame(p, qv), q, tip);
      if (answer.status != IkStatus::kSuccess) break;
      q = std::move(answer.joint_values);
      points.push_back(q);
      reached = k;
    }
    if (reached == steps) {
      fraction = static_cast<double>(i + 1) / n_waypoints;
    } else {
      fraction += (static_cast<double>(reached) / static_cast<double>(steps)) / n_waypoints;
      break;
    }
    prev = &w;
  }
  if (jump_threshold > 0.0) fraction *= jump_test(model_->variables(), points, jump_threshold);
  return CartesianPath{time_parameterize(*model_, points, velocity_scaling_, acceleration_scaling_), fraction};
}

void MoveGroup::execute(const std::vector<std::string>& names, const Trajectory& t) {
  const auto& vars = model_->variables();
  const std::size_t n = vars.size();
  if (names.size() != n) fail(ErrorCode::kInvalidTrajectory, "trajectory joints do not match the group's joints");
  for (std::size_t j = 0; j < n; ++j) {
    if (names[j] != vars[j].name) {
      fail(ErrorCode::kInvalidTrajectory, "trajectory joint #" + std::to_string(j) + " is '" + names[j] +
                                              "', the group's is '" + vars[j].name + "'");
    }
  }
  const std::size_t m = t.size();
  if (m == 0) fail(ErrorCode::kInvalidTrajectory, "trajectory has no points");
  for (std::size_t i = 0; i < m; ++i) {
    if (!std::isfinite(t.time[i]) || (i == 0 ? t.time[i] < 0.0 : !(t.time[i] > t.time[i - 1]))) {
      fail(ErrorCode::kInvalidTrajectory, "trajectory times must be finite, >= 0 and strictly increasing");
    }
  }
  for (double p : t.positions) {
    if (!std::isfinite(p)) fail(ErrorCode::kInvalidTrajectory, "trajectory has a non-finite position");
  }
  for (std::size_t j = 0; j < n; ++j) {
    double dev = t.positions[j] - current_[j];
    if (vars[j].kind == JointKind::kContinuous) dev = normalize_angle(dev);
    if (std::fabs(dev) > kExecuteStartTolerance) {
      fail(ErrorCode::kInvalidTrajectory, "trajectory starts " + num(std::fabs(dev)) + " away from the current "
                                          "value of joint '" + vars[j].name + "'");
    }
  }
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      const double p = t.positions[i * n + j];
      if (vars[j].kind != JointKind::kContinuous && (p < vars[j].lower - tolerance_ || p > vars[j].upper + tolerance_)) {
        fail(ErrorCode::kOutOfBounds, "trajectory point " + std::to_string(i) + " puts joint '" + vars[j].name +
                                          "' at " + num(p) + ", outside [" + num(vars[j].lower) + ", " +
                                          num(vars[j].upper) + "]");
      }
    }
  }
  for (std::size_t j = 0; j < n; ++j) {
    const double p = t.positions[(m - 1) * n + j];
    current_[j] = vars[j].kind == JointKind::kContinuous ? normalize_angle(p) : std::clamp(p, vars[j].lower, vars[j].upper);
  }
}

bool MoveGroup::go() {
  Trajectory t;
  try {
    t = plan();
  } catch (const ApiError& e) {
    if (e.code() == ErrorCode::kPlanningFailed) return false;  // moveit_commander's go() returns False
    throw;
  }
  std::vector<std::string> names;
  names.reserve(model_->dof());
  for (const auto& v : model_->variables()) names.push_back(v.name);
  execute(names, t);
  return true;
}

}  // namespace rrosfuzz
