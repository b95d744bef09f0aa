#include "urdf_loader.hpp"

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <mutex>
#include <sstream>
#include <vector>

#include "errors.hpp"
#include "xml_guard.hpp"

namespace rrosfuzz {
namespace {

// Collects what urdfdom reports through console_bridge instead of letting it
// print to the terminal; the messages become the text of the URDFError.
class CaptureHandler : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) messages.push_back(text);
  }
  std::vector<std::string> messages;
};

std::mutex& console_mutex() {
  static std::mutex m;
  return m;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(ErrorCode::kUrdfInvalid, "cannot read URDF file '" + path + "'");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) fail(ErrorCode::kUrdfInvalid, "cannot read URDF file '" + path + "'");
  return buffer.str();
}

std::string join(const std::vector<std::string>& parts) {
  std::string out;
  for (const auto& p : parts) {
    if (!out.empty()) out += "; ";
    out += p;
  }
  return out;
}

}  // namespace

urdf::ModelInterfaceSharedPtr load_urdf(const std::string& source, bool is_path) {
  const std::string xml = is_path ? read_file(source) : source;
  const std::string where = is_path ? "URDF file '" + source + "'" : "URDF";
  if (xml.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    fail(ErrorCode::kUrdfUnsupported, where + " is larger than 2 GiB");
  }
  check_urdf_xml(xml);

  std::lock_guard<std::mutex> lock(console_mutex());
  CaptureHandler handler;
  console_bridge::useOutputHandler(&handler);
  console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_WARN);
  urdf::ModelInterfaceSharedPtr out;
  std::string error;
  try {
    out = urdf::parseURDF(xml);
    if (!out) error = handler.messages.empty() ? "urdfdom rejected it" : join(handler.messages);
  } catch (const std::exception& e) {
    error = std::string("urdfdom failed: ") + e.what();
  }
  console_bridge::restorePreviousOutputHandler();
  if (!error.empty()) fail(ErrorCode::kUrdfInvalid, where + " is invalid: " + error);
  return out;
}

KDL::Segment segment_of(const urdf::Joint& joint) {
  const urdf::Pose& o = joint.parent_to_joint_origin_transform;
  const KDL::Frame origin(KDL::Rotation::Quaternion(o.rotation.x, o.rotation.y, o.rotation.z, o.rotation.w),
                          KDL::Vector(o.position.x, o.position.y, o.position.z));
  // Unit axis (never zero here: Model rejects zero axes), scaled first so tiny
  // axes neither underflow nor reach KDL's Normalize(), which turns any axis
  // shorter than 1e-6 into (1, 0, 0).
  auto unit_axis = [&joint]() {
    const double scale = std::max({std::fabs(joint.axis.x), std::fabs(joint.axis.y), std::fabs(joint.axis.z)});
    const double ax = joint.axis.x / scale, ay = joint.axis.y / scale, az = joint.axis.z / scale;
    const double norm = std::sqrt(ax * ax + ay * ay + az * az);
    return KDL::Vector(ax / norm, ay / norm, az / norm);
  };
  switch (joint.type) {
    case urdf::Joint::REVOLUTE:
    case urdf::Joint::CONTINUOUS:
      return KDL::Segment(joint.child_link_name, KDL::Joint(joint.name, origin.p, origin.M * unit_axis(), KDL::Joint::RotAxis),
                          origin);
    case urdf::Joint::PRISMATIC:
      return KDL::Segment(joint.child_link_name,
                          KDL::Joint(joint.name, origin.p, origin.M * unit_axis(), KDL::Joint::TransAxis), origin);
    default:
      return KDL::Segment(joint.child_link_name, KDL::Joint(joint.name, KDL::Joint::Fixed), origin);
  }
}

}  // namespace rrosfuzz
