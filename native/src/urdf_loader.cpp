#include "urdf_loader.hpp"

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <mutex>
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

// Reads at most kMaxUrdfBytes + 1 bytes of a regular file. Opened non-blocking,
// so that a FIFO without a writer cannot hang the open; anything but a regular
// file (FIFO, device, directory, socket) is refused before a byte is read.
std::string read_file(const std::string& path) {
  const std::string where = "cannot read URDF file '" + valid_utf8(path) + "'";
  if (path.find('\0') != std::string::npos) fail(ErrorCode::kUrdfInvalid, where + ": the path contains a NUL character");
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) fail(ErrorCode::kUrdfInvalid, where + ": " + std::strerror(errno));
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat info {};
  if (::fstat(fd, &info) != 0) fail(ErrorCode::kUrdfInvalid, where + ": " + std::strerror(errno));
  if (!S_ISREG(info.st_mode)) fail(ErrorCode::kUrdfInvalid, where + ": not a regular file");
  std::string out;
  char buffer[65536];
  while (out.size() <= kMaxUrdfBytes) {
    const std::size_t want = std::min(sizeof buffer, kMaxUrdfBytes + 1 - out.size());
    const ssize_t got = ::read(fd, buffer, want);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) fail(ErrorCode::kUrdfInvalid, where + ": " + std::strerror(errno));
    if (got == 0) break;
    out.append(buffer, static_cast<std::size_t>(got));
  }
  return out;
}

std::string join(const std::vector<std::string>& parts) {
  std::string out;
  for (const auto& p : parts) {
    if (!out.empty()) out += "; ";
    out += valid_utf8(p);  // console_bridge cuts messages at 1023 bytes, maybe inside a character
  }
  return out;
}

}  // namespace

urdf::ModelInterfaceSharedPtr load_urdf(const std::string& source, bool is_path) {
  const std::string xml = is_path ? read_file(source) : source;
  const std::string where = is_path ? "URDF file '" + valid_utf8(source) + "'" : "URDF";
  check_urdf_xml(xml);
  // A leading UTF-8 byte order mark puts TinyXML in UTF-8 mode; without it, a
  // document with no encoding declaration is read as "legacy" bytes, and a
  // character reference such as &#xE9; becomes the lone byte 0xE9 in a name.
  static const std::string kBom = "\xEF\xBB\xBF";
  const std::string for_urdfdom = xml.compare(0, kBom.size(), kBom) == 0 ? xml : kBom + xml;

  std::lock_guard<std::mutex> lock(console_mutex());
  CaptureHandler handler;
  console_bridge::useOutputHandler(&handler);
  console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_WARN);
  urdf::ModelInterfaceSharedPtr out;
  std::string error;
  try {
    out = urdf::parseURDF(for_urdfdom);
    if (!out) error = handler.messages.empty() ? "urdfdom rejected it" : join(handler.messages);
  } catch (const std::exception& e) {
    error = std::string("urdfdom failed: ") + valid_utf8(e.what());
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
