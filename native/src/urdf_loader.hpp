// Reading URDF with urdfdom, and turning joints into KDL segments.
//
// Debian's kdl_parser is not used: it is the catkin build and links roscpp,
// log4cxx and the system libpython into the process. The conversion it would do
// for a chain is segment_of() below.
#pragma once

#include <kdl/segment.hpp>
#include <urdf_model/model.h>
#include <urdf_world/types.h>

#include <string>

namespace rrosfuzz {

// Parses a URDF file (is_path) or XML text. Throws ApiError(kUrdfInvalid) with
// urdfdom's own messages when urdfdom rejects the document.
urdf::ModelInterfaceSharedPtr load_urdf(const std::string& source, bool is_path);

// The KDL segment of a URDF joint: the child link, moved by the joint about (or
// along) its normalized axis at the joint origin. Fixed joints give fixed segments.
KDL::Segment segment_of(const urdf::Joint& joint);

}  // namespace rrosfuzz
