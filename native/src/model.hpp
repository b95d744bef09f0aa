// A kinematic chain read from URDF (urdfdom + kdl_parser), with forward and
// inverse kinematics on Orocos KDL. See docs/api.md for the contract.
#pragma once

#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolverpos_nr_jl.hpp>
#include <kdl/chainiksolvervel_pinv.hpp>
#include <kdl/frames.hpp>
#include <kdl/jntarray.hpp>

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace rrosfuzz {

enum class JointKind { kRevolute, kContinuous, kPrismatic };

// One joint variable of the model (a column of every joint vector).
struct Variable {
  std::string name;
  JointKind kind;
  double lower;     // -inf for continuous joints
  double upper;     // +inf for continuous joints
  double velocity;  // planning velocity limit before scaling
};

struct MimicInfo {
  std::string name;
  std::string master;
  double multiplier;
  double offset;
};

// How one KDL chain joint gets its value from the variables.
struct ChainJoint {
  int variable;
  double multiplier;
  double offset;
  bool mimic;
};

enum class IkStatus { kSuccess, kNoSolution };

struct IkAnswer {
  IkStatus status;
  std::vector<double> joint_values;
  double position_error;
  double orientation_error;
};

class Model {
 public:
  // Loads a URDF from a file (is_path) or from XML text. Throws ApiError.
  Model(const std::string& source, bool is_path, const std::optional<std::string>& tip_link);
  ~Model();
  Model(const Model&) = delete;
  Model& operator=(const Model&) = delete;

  const std::string& name() const { return name_; }
  const std::string& root_link() const { return link_names_.front(); }
  const std::string& tip_link() const { return link_names_.back(); }
  const std::vector<std::string>& link_names() const { return link_names_; }
  const std::vector<Variable>& variables() const { return variables_; }
  const std::vector<MimicInfo>& mimics() const { return mimics_; }
  std::size_t dof() const { return variables_.size(); }
  std::vector<double> home() const;

  // Index into link_names(); nullopt means the tip. Throws kUnknownLink.
  int link_index(const std::optional<std::string>& link) const;
  // Index of a variable by name, or -1.
  int variable_index(const std::string& name) const;

  // Throws kWrongLength / kNonFinite.
  void check_joint_vector(const std::vector<double>& q, const char* what) const;

  // q has dof() entries, already checked.
  KDL::Frame fk(const std::vector<double>& q, int link) const;
  // The chain, copied: the argument fk_batch takes. Take it while no fk() runs (the binding
  // holds the GIL): fk() rewrites the cached poses of KDL::Joint in chain_, and a copy taken
  // during it could pair a new joint value with the old pose (wrong batch rows, no error).
  KDL::Chain chain_snapshot() const { return chain_; }
  // chain: chain_snapshot(); q: n rows of dof() values; out: n row-major 4x4 matrices.
  // Touches nothing of the model's own, so it runs without the GIL beside other calls;
  // batches of 8192 rows or more run on several threads.
  void fk_batch(const KDL::Chain& chain, const double* q, std::size_t n, int link, double* out) const;

  IkAnswer ik(const KDL::Frame& target, const std::vector<double>& seed, int link) const;

 private:
  struct IkSolver;

  void to_kdl(const double* q, KDL::JntArray& out) const;
  void fk_rows(const KDL::Chain& snapshot, const double* q, std::size_t begin, std::size_t end, int link,
               double* out) const;
  const IkSolver& ik_solver(int link) const;

  std::string name_;
  std::vector<std::string> link_names_;
  std::vector<Variable> variables_;
  std::vector<MimicInfo> mimics_;
  KDL::Chain chain_;
  std::vector<ChainJoint> chain_joints_;
  std::unique_ptr<KDL::ChainFkSolverPos_recursive> fk_solver_;
  mutable KDL::JntArray q_kdl_;
  mutable std::map<int, std::unique_ptr<IkSolver>> ik_solvers_;
};

// Canonical quaternion of a rotation: unit, w >= 0 (if w == 0, the first
// non-zero of x, y, z is positive). Order x, y, z, w.
void canonical_quaternion(const KDL::Rotation& r, double out[4]);

}  // namespace rrosfuzz
