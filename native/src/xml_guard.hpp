// Checks a URDF document with expat before urdfdom sees it.
//
// urdfdom 3.0.1 (TinyXML 1) crashes on some inputs: a '%' in an <origin> xyz/rpy
// value reaches printf as a format string, nesting tens of thousands of elements
// deep overflows the stack, and a model of ~200k links overflows it again when
// freed. This guard rejects those documents with a URDFError instead, and also
// enforces the contract's XML rules (well-formed XML, no entity declarations).
#pragma once

#include <string>

namespace rrosfuzz {

constexpr int kMaxXmlDepth = 1000;
constexpr int kMaxLinks = 10000;

// Throws ApiError(kUrdfInvalid or kUrdfUnsupported) naming the problem.
void check_urdf_xml(const std::string& xml);

// urdfdom's vector grammar: pieces split on ' ' (empty pieces skipped), each a
// decimal number (optional leading whitespace, no trailing junk, no overflow),
// exactly 3 of them.
bool is_urdf_vector3(const std::string& text);

}  // namespace rrosfuzz
