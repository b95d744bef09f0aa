// moveit_commander's MoveGroupCommander semantics over a simulated arm.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "errors.hpp"
#include "model.hpp"
#include "trajectory.hpp"

namespace rrosfuzz {

// A position and a unit quaternion (x, y, z, w), as the contract's pose rule gives them.
struct PoseParts {
  double p[3];
  double q[4];
};

// Outcome of plan(): moveit_msgs/MoveItErrorCodes values.
enum class PlanCode : int { kSuccess = 1, kPlanningFailed = -1, kNoIkSolution = -31 };

struct PlanOutcome {
  PlanCode code;
  Trajectory trajectory;  // no points unless code == kSuccess
};

struct CartesianPath {
  Trajectory trajectory;
  double fraction;
};

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

  // A pose (or, position_only, a position keeping the link's orientation at planning
  // time) of chain link `link` becomes the goal; set_target / set_named_target end it.
  void set_pose_target(const PoseParts& pose, int link, bool position_only);
  void clear_pose_targets() { pose_goal_.reset(); }

  // Throws kPlanningFailed (or kUnsupportedOperation from IK); pose goals with
  // no IK solution throw NoIkSolution.
  Trajectory plan() const;
  // plan() with planning failures as codes; other errors still throw.
  PlanOutcome plan_outcome() const;
  // names: the trajectory's joint names. Throws kInvalidTrajectory / kOutOfBounds.
  void execute(const std::vector<std::string>& names, const Trajectory& trajectory);
  bool go();
  // Arguments already checked (waypoints non-empty, eef_step > 0, jump_threshold >= 0).
  CartesianPath compute_cartesian_path(const std::vector<PoseParts>& waypoints, double eef_step,
                                       double jump_threshold) const;

 private:
  // Bounds check and normalization of one target value (already finite).
  double accept(std::size_t variable, double value) const;
  std::vector<double> goal() const;

  struct PoseGoal {
    PoseParts pose;
    int link;
    bool position_only;
  };

  std::shared_ptr<const Model> model_;
  std::vector<double> current_;
  std::vector<double> target_;
  std::map<std::string, std::vector<double>> named_;
  double tolerance_;
  double velocity_scaling_ = 1.0;
  double acceleration_scaling_ = 1.0;
  std::optional<PoseGoal> pose_goal_;
};

// plan() of a pose goal without IK solution (a PLANNING_FAILED error, reported
// by plan_outcome() as kNoIkSolution).
class NoIkSolution : public ApiError {
 public:
  explicit NoIkSolution(const std::string& message) : ApiError(ErrorCode::kPlanningFailed, message) {}
};

}  // namespace rrosfuzz
