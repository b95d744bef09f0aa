#include "move_group.hpp"

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

Trajectory MoveGroup::plan() const {
  return plan_trajectory(*model_, current_, target_, velocity_scaling_, acceleration_scaling_);
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
