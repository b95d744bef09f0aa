#include "model.hpp"

#include <kdl/segment.hpp>
#include <urdf_model/model.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <thread>

#include "angles.hpp"
#include "constants.hpp"
#include "errors.hpp"
#include "urdf_loader.hpp"

namespace rrosfuzz {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

bool is_movable(const urdf::Joint& j) {
  return j.type == urdf::Joint::REVOLUTE || j.type == urdf::Joint::CONTINUOUS ||
         j.type == urdf::Joint::PRISMATIC || j.type == urdf::Joint::FLOATING ||
         j.type == urdf::Joint::PLANAR;
}

const char* type_name(int type) {
  switch (type) {
    case urdf::Joint::REVOLUTE: return "revolute";
    case urdf::Joint::CONTINUOUS: return "continuous";
    case urdf::Joint::PRISMATIC: return "prismatic";
    case urdf::Joint::FLOATING: return "floating";
    case urdf::Joint::PLANAR: return "planar";
    case urdf::Joint::FIXED: return "fixed";
    default: return "unknown";
  }
}

bool finite3(const urdf::Vector3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Movable joints below each link (the link's whole subtree), without recursion.
std::map<std::string, int> subtree_movable_counts(const urdf::ModelInterface& model) {
  std::vector<urdf::LinkConstSharedPtr> order;  // parents before children
  std::vector<urdf::LinkConstSharedPtr> stack{model.getRoot()};
  while (!stack.empty()) {
    auto link = stack.back();
    stack.pop_back();
    order.push_back(link);
    for (const auto& child : link->child_links) stack.push_back(child);
  }
  std::map<std::string, int> count;
  for (auto it = order.rbegin(); it != order.rend(); ++it) {
    int n = 0;
    for (const auto& joint : (*it)->child_joints) {
      n += (is_movable(*joint) ? 1 : 0) + count[joint->child_link_name];
    }
    count[(*it)->name] = n;
  }
  return count;
}

// The contract's default tip: from the root, follow the only child, or the child
// whose subtree has strictly the most movable joints; stop at a leaf or a tie.
std::string default_tip(const urdf::ModelInterface& model) {
  const auto count = subtree_movable_counts(model);
  urdf::LinkConstSharedPtr link = model.getRoot();
  while (!link->child_joints.empty()) {
    if (link->child_joints.size() == 1) {
      link = model.getLink(link->child_joints.front()->child_link_name);
      continue;
    }
    int best = -1;
    int best_count = 0;
    for (const auto& joint : link->child_joints) {
      const int score = (is_movable(*joint) ? 1 : 0) + count.at(joint->child_link_name);
      if (score > best) {
        best = score;
        best_count = 1;
      } else if (score == best) {
        ++best_count;
      }
    }
    if (best_count != 1) break;
    for (const auto& joint : link->child_joints) {
      if ((is_movable(*joint) ? 1 : 0) + count.at(joint->child_link_name) == best) {
        link = model.getLink(joint->child_link_name);
        break;
      }
    }
  }
  return link->name;
}

void check_joint(const urdf::Joint& j) {
  const std::string who = "joint '" + j.name + "'";
  if (j.type == urdf::Joint::FLOATING || j.type == urdf::Joint::PLANAR) {
    fail(ErrorCode::kUrdfUnsupported, who + " is " + type_name(j.type) + ": only revolute, continuous, "
                                      "prismatic and fixed joints are supported on the chain");
  }
  const auto& o = j.parent_to_joint_origin_transform;
  if (!finite3(o.position) || !std::isfinite(o.rotation.x) || !std::isfinite(o.rotation.y) ||
      !std::isfinite(o.rotation.z) || !std::isfinite(o.rotation.w)) {
    fail(ErrorCode::kUrdfInvalid, who + " has a non-finite origin");
  }
  if (j.type == urdf::Joint::FIXED) return;
  if (!finite3(j.axis)) fail(ErrorCode::kUrdfInvalid, who + " has a non-finite axis");
  if (j.axis.x == 0.0 && j.axis.y == 0.0 && j.axis.z == 0.0) {
    fail(ErrorCode::kUrdfInvalid, who + " has a zero axis");
  }
  if (j.type == urdf::Joint::REVOLUTE || j.type == urdf::Joint::PRISMATIC) {
    if (!j.limits) fail(ErrorCode::kUrdfInvalid, who + " has no limits");
    if (!std::isfinite(j.limits->lower) || !std::isfinite(j.limits->upper)) {
      fail(ErrorCode::kUrdfInvalid, who + " has non-finite position limits");
    }
    if (j.limits->lower > j.limits->upper) {
      fail(ErrorCode::kUrdfInvalid, who + " has lower limit " + std::to_string(j.limits->lower) +
                                        " above upper limit " + std::to_string(j.limits->upper));
    }
  }
  if (j.limits && std::isnan(j.limits->velocity)) {
    fail(ErrorCode::kUrdfInvalid, who + " has a NaN velocity limit");
  }
  if (j.mimic && (!std::isfinite(j.mimic->multiplier) || !std::isfinite(j.mimic->offset))) {
    fail(ErrorCode::kUrdfInvalid, who + " has a non-finite mimic multiplier or offset");
  }
}

Variable make_variable(const urdf::Joint& j) {
  Variable v;
  v.name = j.name;
  if (j.type == urdf::Joint::CONTINUOUS) {
    v.kind = JointKind::kContinuous;
    v.lower = -kInf;
    v.upper = kInf;
  } else {
    v.kind = j.type == urdf::Joint::PRISMATIC ? JointKind::kPrismatic : JointKind::kRevolute;
    v.lower = j.limits->lower;
    v.upper = j.limits->upper;
  }
  const double vel = j.limits ? j.limits->velocity : 0.0;
  v.velocity = (vel > 0.0) ? vel : kDefaultVelocityLimit;
  return v;
}

void frame_to_matrix(const KDL::Frame& f, double* m) {
  for (int r = 0; r < 3; ++r) {
    m[4 * r + 0] = f.M(r, 0);
    m[4 * r + 1] = f.M(r, 1);
    m[4 * r + 2] = f.M(r, 2);
    m[4 * r + 3] = f.p(r);
  }
  m[12] = 0.0;
  m[13] = 0.0;
  m[14] = 0.0;
  m[15] = 1.0;
}

double rotation_angle(const KDL::Rotation& r) {
  double q[4];
  canonical_quaternion(r, q);
  return 2.0 * std::atan2(std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]), q[3]);
}

// The contract's graph rules, which urdfdom does not enforce: every link is the
// child of at most one joint, and every link is reachable from the root.
void check_tree(const urdf::ModelInterface& model) {
  std::map<std::string, std::string> parent_joint_of;
  for (const auto& [name, joint] : model.joints_) {  // std::map: joints in name order
    auto [it, fresh] = parent_joint_of.emplace(joint->child_link_name, name);
    if (!fresh) {
      fail(ErrorCode::kUrdfInvalid, "link '" + joint->child_link_name + "' is the child of two joints, '" +
                                        it->second + "' and '" + name + "'");
    }
  }
  std::set<std::string> reached{model.getRoot()->name};
  std::vector<urdf::LinkConstSharedPtr> stack{model.getRoot()};
  while (!stack.empty()) {
    auto link = stack.back();
    stack.pop_back();
    for (const auto& child : link->child_links) {
      if (reached.insert(child->name).second) stack.push_back(child);
    }
  }
  for (const auto& [name, link] : model.links_) {  // name order
    if (!reached.count(name)) {
      fail(ErrorCode::kUrdfInvalid, "link '" + name + "' is not connected to the root link '" +
                                        model.getRoot()->name + "'");
    }
  }
}

}  // namespace

void canonical_quaternion(const KDL::Rotation& r, double out[4]) {
  r.GetQuaternion(out[0], out[1], out[2], out[3]);
  const double n = std::sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2] + out[3] * out[3]);
  for (int i = 0; i < 4; ++i) out[i] /= n;
  bool flip = out[3] < 0.0;
  if (out[3] == 0.0) {
    for (int i = 0; i < 3; ++i) {
      if (out[i] != 0.0) {
        flip = out[i] < 0.0;
        break;
      }
    }
  }
  if (flip) {
    for (int i = 0; i < 4; ++i) out[i] = -out[i];
  }
  if (out[3] == 0.0) out[3] = 0.0;  // no negative zero
}

struct Model::IkSolver {
  KDL::Chain chain;
  KDL::JntArray q_min, q_max;
  std::unique_ptr<KDL::ChainFkSolverPos_recursive> fk;
  std::unique_ptr<KDL::ChainIkSolverVel_pinv> vel;
  std::unique_ptr<KDL::ChainIkSolverPos_NR_JL> pos;
  unsigned nvars = 0;
};

Model::Model(const std::string& source, bool is_path, const std::optional<std::string>& tip_link) {
  const urdf::ModelInterfaceSharedPtr loaded = load_urdf(source, is_path);
  const urdf::ModelInterface& model = *loaded;
  check_tree(model);
  name_ = model.getName();

  std::string tip;
  if (tip_link) {
    if (!model.getLink(*tip_link)) fail(ErrorCode::kUnknownLink, "tip link '" + *tip_link + "' is not in the URDF");
    tip = *tip_link;
  } else {
    tip = default_tip(model);
  }

  // Joints from the root to the tip.
  std::vector<urdf::JointConstSharedPtr> path;
  for (auto link = model.getLink(tip); link->parent_joint; link = model.getLink(link->parent_joint->parent_link_name)) {
    path.push_back(link->parent_joint);
  }
  std::reverse(path.begin(), path.end());

  link_names_.push_back(model.getRoot()->name);
  std::set<std::string> on_chain;
  for (const auto& joint : path) {
    check_joint(*joint);
    link_names_.push_back(joint->child_link_name);
    on_chain.insert(joint->name);
  }
  for (const auto& joint : path) {
    if (is_movable(*joint) && !joint->mimic) variables_.push_back(make_variable(*joint));
  }
  for (const auto& joint : path) {
    if (!joint->mimic) continue;
    const std::string who = "mimic joint '" + joint->name + "'";
    auto master = model.getJoint(joint->mimic->joint_name);
    if (!master) fail(ErrorCode::kUrdfInvalid, who + " follows unknown joint '" + joint->mimic->joint_name + "'");
    if (master->mimic) fail(ErrorCode::kUrdfUnsupported, who + " follows '" + master->name + "', itself a mimic joint");
    if (master->type != urdf::Joint::REVOLUTE && master->type != urdf::Joint::CONTINUOUS &&
        master->type != urdf::Joint::PRISMATIC) {
      fail(ErrorCode::kUrdfUnsupported, who + " follows '" + master->name + "', a " + type_name(master->type) + " joint");
    }
    if (!on_chain.count(master->name) && variable_index(master->name) < 0) {
      check_joint(*master);
      variables_.push_back(make_variable(*master));
    }
    mimics_.push_back({joint->name, master->name, joint->mimic->multiplier, joint->mimic->offset});
  }

  for (const auto& uj : path) {
    chain_.addSegment(segment_of(*uj));
    if (uj->type == urdf::Joint::FIXED) continue;
    if (uj->mimic) {
      chain_joints_.push_back({variable_index(uj->mimic->joint_name), uj->mimic->multiplier, uj->mimic->offset, true});
    } else {
      chain_joints_.push_back({variable_index(uj->name), 1.0, 0.0, false});
    }
  }
  q_kdl_.resize(chain_.getNrOfJoints());
  fk_solver_ = std::make_unique<KDL::ChainFkSolverPos_recursive>(chain_);
}

Model::~Model() = default;

std::vector<double> Model::home() const {
  std::vector<double> q(variables_.size());
  for (std::size_t i = 0; i < q.size(); ++i) q[i] = std::clamp(0.0, variables_[i].lower, variables_[i].upper);
  return q;
}

int Model::link_index(const std::optional<std::string>& link) const {
  if (!link) return static_cast<int>(link_names_.size()) - 1;
  for (std::size_t i = 0; i < link_names_.size(); ++i) {
    if (link_names_[i] == *link) return static_cast<int>(i);
  }
  fail(ErrorCode::kUnknownLink, "link '" + *link + "' is not on the chain from '" + root_link() + "' to '" +
                                    tip_link() + "'");
}

int Model::variable_index(const std::string& name) const {
  for (std::size_t i = 0; i < variables_.size(); ++i) {
    if (variables_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

void Model::check_joint_vector(const std::vector<double>& q, const char* what) const {
  if (q.size() != variables_.size()) {
    fail(ErrorCode::kWrongLength, std::string(what) + ": expected " + std::to_string(variables_.size()) +
                                      " joint values, got " + std::to_string(q.size()));
  }
  for (std::size_t i = 0; i < q.size(); ++i) {
    if (!std::isfinite(q[i])) {
      fail(ErrorCode::kNonFinite, std::string(what) + ": value of joint '" + variables_[i].name + "' is not finite");
    }
  }
}

void Model::to_kdl(const double* q, KDL::JntArray& out) const {
  for (std::size_t j = 0; j < chain_joints_.size(); ++j) {
    const ChainJoint& cj = chain_joints_[j];
    out(j) = cj.mimic ? cj.multiplier * q[cj.variable] + cj.offset : q[cj.variable];
  }
}

KDL::Frame Model::fk(const std::vector<double>& q, int link) const {
  to_kdl(q.data(), q_kdl_);
  KDL::Frame f;
  fk_solver_->JntToCart(q_kdl_, f, link);
  return f;
}

void Model::fk_rows(const KDL::Chain& snapshot, const double* q, std::size_t begin, std::size_t end, int link,
                    double* out) const {
  // A private copy per thread: KDL::Joint::pose() caches into mutable members, so segments
  // shared with other threads would race. Copied from the caller's snapshot, never from
  // chain_, which fk() rewrites meanwhile (the batch runs without the GIL).
  const KDL::Chain chain = snapshot;
  KDL::ChainFkSolverPos_recursive solver(chain);
  KDL::JntArray qk(chain.getNrOfJoints());
  KDL::Frame f;
  const std::size_t nv = variables_.size();
  for (std::size_t i = begin; i < end; ++i) {
    to_kdl(q + i * nv, qk);
    solver.JntToCart(qk, f, link);
    frame_to_matrix(f, out + 16 * i);
  }
}

void Model::fk_batch(const KDL::Chain& chain, const double* q, std::size_t n, int link, double* out) const {
  // Large batches are split over the machine's cores (rows are independent).
  constexpr std::size_t kRowsPerThread = 4096;
  const std::size_t cores = std::max(1u, std::thread::hardware_concurrency());
  const std::size_t workers = std::min({cores, std::size_t{16}, std::max<std::size_t>(1, n / kRowsPerThread)});
  if (workers <= 1) {
    fk_rows(chain, q, 0, n, link, out);
    return;
  }
  std::vector<std::thread> threads;
  const std::size_t chunk = (n + workers - 1) / workers;
  for (std::size_t w = 1; w < workers; ++w) {
    const std::size_t begin = std::min(n, w * chunk), end = std::min(n, (w + 1) * chunk);
    threads.emplace_back([=, &chain] { fk_rows(chain, q, begin, end, link, out); });
  }
  fk_rows(chain, q, 0, std::min(n, chunk), link, out);
  for (auto& t : threads) t.join();
}

const Model::IkSolver& Model::ik_solver(int link) const {
  auto found = ik_solvers_.find(link);
  if (found != ik_solvers_.end()) return *found->second;
  auto s = std::make_unique<IkSolver>();
  for (int i = 0; i < link; ++i) s->chain.addSegment(chain_.getSegment(i));
  s->nvars = s->chain.getNrOfJoints();
  for (unsigned j = 0; j < s->nvars; ++j) {
    if (chain_joints_[j].mimic) {
      fail(ErrorCode::kUnsupportedOperation, "inverse kinematics to '" + link_names_[link] +
                                                 "' passes through a mimic joint, which is not supported");
    }
  }
  s->q_min.resize(s->nvars);
  s->q_max.resize(s->nvars);
  for (unsigned j = 0; j < s->nvars; ++j) {
    s->q_min(j) = variables_[j].lower;
    s->q_max(j) = variables_[j].upper;
  }
  s->fk = std::make_unique<KDL::ChainFkSolverPos_recursive>(s->chain);
  s->vel = std::make_unique<KDL::ChainIkSolverVel_pinv>(s->chain, kIkPinvEps, kIkSvdIterations);
  s->pos = std::make_unique<KDL::ChainIkSolverPos_NR_JL>(s->chain, s->q_min, s->q_max, *s->fk, *s->vel,
                                                         kIkMaxIterations, kIkEps);
  return *ik_solvers_.emplace(link, std::move(s)).first->second;
}

IkAnswer Model::ik(const KDL::Frame& target, const std::vector<double>& seed, int link) const {
  const IkSolver& s = ik_solver(link);
  std::vector<double> q = seed;
  for (std::size_t i = 0; i < q.size(); ++i) {
    q[i] = variables_[i].kind == JointKind::kContinuous ? normalize_angle(q[i])
                                                         : std::clamp(q[i], variables_[i].lower, variables_[i].upper);
  }
  IkStatus status;
  if (s.nvars == 0) {
    const KDL::Frame here = fk(q, link);
    status = KDL::Equal(KDL::diff(here, target), KDL::Twist::Zero(), kIkEps) ? IkStatus::kSuccess
                                                                              : IkStatus::kNoSolution;
  } else {
    KDL::JntArray q_init(s.nvars), q_out(s.nvars);
    for (unsigned j = 0; j < s.nvars; ++j) q_init(j) = q[j];
    const int rc = s.pos->CartToJnt(q_init, target, q_out);
    status = rc == KDL::SolverI::E_NOERROR ? IkStatus::kSuccess : IkStatus::kNoSolution;
    bool finite = true;
    for (unsigned j = 0; j < s.nvars; ++j) finite = finite && std::isfinite(q_out(j));
    if (!finite) {
      status = IkStatus::kNoSolution;  // a non-finite iterate (absurd target): keep the clamped seed
    } else {
      for (unsigned j = 0; j < s.nvars; ++j) {
        q[j] = variables_[j].kind == JointKind::kContinuous ? normalize_angle(q_out(j)) : q_out(j);
      }
    }
  }
  const KDL::Frame reached = fk(q, link);
  IkAnswer answer;
  answer.status = status;
  const KDL::Vector d = reached.p - target.p;  // not KDL's Norm(): it returns 0 below 1e-6
  answer.position_error = std::sqrt(d.x() * d.x() + d.y() * d.y() + d.z() * d.z());
  answer.orientation_error = rotation_angle(reached.M.Inverse() * target.M);
  answer.joint_values = std::move(q);
  return answer;
}

}  // namespace rrosfuzz
