#include "xml_guard.hpp"

#include <expat.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <memory>

#include "errors.hpp"

namespace rrosfuzz {
namespace {

bool is_urdf_number(const std::string& s) {
  std::size_t i = 0;
  while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
  const std::size_t begin = i;
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
  std::size_t int_digits = 0, frac_digits = 0;
  while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i, ++int_digits;
  if (i < s.size() && s[i] == '.') {
    ++i;
    while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i, ++frac_digits;
  }
  if (int_digits + frac_digits == 0) return false;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    std::size_t exp_digits = 0;
    while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i, ++exp_digits;
    if (exp_digits == 0) return false;
  }
  if (i != s.size()) return false;
  const double v = std::strtod(s.c_str() + begin, nullptr);
  return std::isfinite(v);
}

struct GuardState {
  XML_Parser parser = nullptr;
  int depth = 0;
  int links = 0;
  bool root_is_robot = false;
  std::string error;
  ErrorCode code = ErrorCode::kUrdfInvalid;

  void stop(ErrorCode c, const std::string& message) {
    if (!error.empty()) return;
    code = c;
    error = message + " (line " + std::to_string(XML_GetCurrentLineNumber(parser)) + ")";
    XML_StopParser(parser, XML_FALSE);
  }
};

void XMLCALL on_start(void* data, const XML_Char* name, const XML_Char** attrs) {
  auto* st = static_cast<GuardState*>(data);
  ++st->depth;
  if (st->depth > kMaxXmlDepth) {
    st->stop(ErrorCode::kUrdfUnsupported, "XML is nested deeper than " + std::to_string(kMaxXmlDepth) + " elements");
    return;
  }
  if (st->depth == 1) st->root_is_robot = std::strcmp(name, "robot") == 0;
  if (st->depth == 2 && st->root_is_robot && std::strcmp(name, "link") == 0 && ++st->links > kMaxLinks) {
    st->stop(ErrorCode::kUrdfUnsupported, "more than " + std::to_string(kMaxLinks) + " links");
    return;
  }
  if (std::strcmp(name, "origin") == 0) {
    for (int i = 0; attrs[i]; i += 2) {
      if ((std::strcmp(attrs[i], "xyz") == 0 || std::strcmp(attrs[i], "rpy") == 0) && !is_urdf_vector3(attrs[i + 1])) {
        st->stop(ErrorCode::kUrdfInvalid, std::string("origin ") + attrs[i] + "=\"" + attrs[i + 1] +
                                              "\" is not a vector of 3 numbers");
        return;
      }
    }
  }
}

void XMLCALL on_end(void* data, const XML_Char*) { --static_cast<GuardState*>(data)->depth; }

void XMLCALL on_entity_decl(void* data, const XML_Char* name, int, const XML_Char*, int, const XML_Char*,
                            const XML_Char*, const XML_Char*, const XML_Char*) {
  static_cast<GuardState*>(data)->stop(ErrorCode::kUrdfInvalid,
                                       std::string("entity declarations are not allowed (entity '") + name + "')");
}

int XMLCALL on_external_entity(XML_Parser parser, const XML_Char*, const XML_Char*, const XML_Char*,
                               const XML_Char*) {
  auto* st = static_cast<GuardState*>(XML_GetUserData(parser));
  st->stop(ErrorCode::kUrdfInvalid, "external entities are not allowed");
  return XML_STATUS_ERROR;
}

}  // namespace

bool is_urdf_vector3(const std::string& text) {
  std::size_t count = 0;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find(' ', start);
    if (end == std::string::npos) end = text.size();
    if (end > start) {
      if (!is_urdf_number(text.substr(start, end - start))) return false;
      ++count;
    }
    start = end + 1;
  }
  return count == 3;
}

void check_urdf_xml(const std::string& xml) {
  std::unique_ptr<std::remove_pointer_t<XML_Parser>, void (*)(XML_Parser)> parser(XML_ParserCreate(nullptr),
                                                                                 XML_ParserFree);
  if (!parser) fail(ErrorCode::kUrdfInvalid, "cannot create an XML parser");
  GuardState st;
  st.parser = parser.get();
  XML_SetUserData(parser.get(), &st);
  XML_SetElementHandler(parser.get(), on_start, on_end);
  XML_SetEntityDeclHandler(parser.get(), on_entity_decl);
  XML_SetExternalEntityRefHandler(parser.get(), on_external_entity);
  XML_SetParamEntityParsing(parser.get(), XML_PARAM_ENTITY_PARSING_NEVER);
  const auto status = XML_Parse(parser.get(), xml.data(), static_cast<int>(xml.size()), XML_TRUE);
  if (!st.error.empty()) fail(st.code, "URDF " + st.error);
  if (status != XML_STATUS_OK) {
    fail(ErrorCode::kUrdfInvalid, std::string("URDF is not well-formed XML: ") +
                                      XML_ErrorString(XML_GetErrorCode(parser.get())) + " (line " +
                                      std::to_string(XML_GetCurrentLineNumber(parser.get())) + ")");
  }
}

}  // namespace rrosfuzz
