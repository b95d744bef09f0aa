// Checks a URDF document with expat before urdfdom sees it.
//
// urdfdom 3.0.1 (TinyXML 1) crashes on some inputs. It builds log messages out
// of attribute values and hands them to printf as the *format* (link.cpp: material
// name and rgba, sphere radius, box size, cylinder length/radius, inertial mass
// and inertia; pose.cpp: origin xyz/rpy), so a '%' there
// kills the process; nesting tens of thousands of elements deep overflows the
// stack, and a model of ~200k links overflows it again when freed. TinyXML also
// reads markup differently from expat in places (a DOCTYPE or a processing
// instruction ends at its first '>' for TinyXML), which would let it see
// elements that expat never checked. This guard rejects all of those documents
// with a URDFError instead, and enforces the contract's XML rules (docs/api.md,
// "URDF rules"): UTF-8 only, well-formed, no DOCTYPE, no processing
// instructions, no '%' in any attribute value.
#pragma once

#include <cstddef>
#include <string>

namespace rrosfuzz {

constexpr int kMaxXmlDepth = 1000;
constexpr int kMaxLinks = 10000;
// Attributes on one element: TinyXML 2.6 (urdfdom's parser) looks each one up in a list, so
// 80,000 on one element took 21 s to parse (a 2.3 MB file).
constexpr int kMaxAttributes = 256;
// Largest URDF accepted, in bytes (file or UTF-8 text): 16 MiB.
constexpr std::size_t kMaxUrdfBytes = std::size_t{16} << 20;

// Throws ApiError(kUrdfInvalid or kUrdfUnsupported) naming the problem.
void check_urdf_xml(const std::string& xml);

// urdfdom's vector grammar: pieces split on ' ' (empty pieces skipped), each a
// decimal number (optional leading whitespace, no trailing junk, no overflow),
// exactly 3 of them.
bool is_urdf_vector3(const std::string& text);

// `text` with every byte that is not part of a valid UTF-8 sequence (strict, as
// Python decodes) replaced by U+FFFD, so that it can become a Python str.
std::string valid_utf8(const std::string& text);

}  // namespace rrosfuzz
