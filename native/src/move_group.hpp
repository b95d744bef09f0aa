// moveit_commander's MoveGroupCommander semantics over a simulated arm.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "model.hpp"
#include "trajectory.hpp"

namespace rrosfuzz {

class MoveGroup {
 public:
  explicit MoveGroup(std::shared_ptr<const Model> model);

  const Model& model() const { return *model_; }
  const std::vector<double>& current() const { return current_; }
  const std::vector<double>& target() const { return target_; }

  // All checks run before anything changes: on error the target is unchanged.
  void set_target(const std::vector<double>& values);
  void set_target(const std::vector<std::string>& names, const std::vector<double>& values);
  void set_named_target(const std::string& name);
  std::vector<std::string> named_targets() const;
  const std::vector<double>& named_target(const std::string& name) const;
  void remember(const std::string& name, const std::optional<std::vector<double>>& values);

  double goal_tolerance() const { return tolerance_; }
  void set_goal_tolerance(double value);
  void set_velocity_scaling(double value);
  void set_acceleration_scaling(double value);

  Trajectory plan() const;
  // names: the trajectory's joint names. Throws kInvalidTrajectory / kOutOfBounds.
  void execute(const std::vector<std::string>& names, const Trajectory& trajectory);
  bool go();

 private:
  // Bounds check and normalization of one target value (already finite).
  double accept(std::size_t variable, double value) const;

  std::shared_ptr<const Model> model_;
  std::vector<double> current_;
  std::vector<double> target_;
  std::map<std::string, std::vector<double>> named_;
  double tolerance_;
  double velocity_scaling_ = 1.0;
  double acceleration_scaling_ = 1.0;
};

}  // namespace rrosfuzz
