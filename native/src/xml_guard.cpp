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

// At most `limit` bytes of `text`, cut at a UTF-8 character boundary, for messages.
std::string clip(const std::string& text, std::size_t limit = 60) {
  if (text.size() <= limit) return text;
  std::size_t cut = limit;
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
  return text.substr(0, cut) + "...";
}

// Length of the valid UTF-8 sequence at s[0..n), or 0. Strict like Python's
// decoder: no overlong forms, no surrogates, nothing above U+10FFFF.
std::size_t utf8_length(const unsigned char* s, std::size_t n) {
  const unsigned char c = s[0];
  if (c < 0x80) return 1;
  std::size_t len = 0;
  unsigned char lo = 0x80, hi = 0xBF;
  if (c >= 0xC2 && c <= 0xDF) {
    len = 2;
  } else if (c >= 0xE0 && c <= 0xEF) {
    len = 3;
    if (c == 0xE0) lo = 0xA0;
    if (c == 0xED) hi = 0x9F;
  } else if (c >= 0xF0 && c <= 0xF4) {
    len = 4;
    if (c == 0xF0) lo = 0x90;
    if (c == 0xF4) hi = 0x8F;
  } else {
    return 0;
  }
  if (n < len || s[1] < lo || s[1] > hi) return 0;
  for (std::size_t k = 2; k < len; ++k) {
    if (s[k] < 0x80 || s[k] > 0xBF) return 0;
  }
  return len;
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

// Checks run in this order for every element, as the twin's (python_impl/urdf_text.py):
// depth, link count, attribute count, '%' in any attribute but a file name, <origin> vectors.
void XMLCALL on_start(void* data, const XML_Char* name, const XML_Char** attrs) {
  auto* st = static_cast<GuardState*>(data);
  if (!st->error.empty()) return;
  ++st->depth;
  if (st->depth > kMaxXmlDepth) {
    st->stop(ErrorCode::kUrdfUnsupported, "XML is nested deeper than " + std::to_string(kMaxXmlDepth) + " elements");
    return;
  }
  if (st->depth == 1) st->root_is_robot = std::strcmp(name, "robot") == 0;
  if (st->depth == 2 && st->root_is_robot && std::strcmp(name, "link") == 0 && ++st->links > kMaxLinks) {
    st->stop(ErrorCode::kUrdfUnsupported, "has more than " + std::to_string(kMaxLinks) + " links");
    return;
  }
  int count = 0;
  while (attrs[2 * count]) ++count;
  if (count > kMaxAttributes) {
    st->stop(ErrorCode::kUrdfUnsupported,
             std::string("<") + clip(name) + "> has more than " + std::to_string(kMaxAttributes) + " attributes");
    return;
  }
  for (int i = 0; attrs[i]; i += 2) {
    // A file name (<mesh filename>, <texture filename>) is never part of a format string in
    // urdfdom 3.0.1, and URL-encoded names ("my%20arm.stl") are common in real URDFs.
    if (std::strcmp(attrs[i], "filename") == 0) continue;
    if (std::strchr(attrs[i + 1], '%')) {
      st->stop(ErrorCode::kUrdfInvalid, std::string("<") + clip(name) + " " + clip(attrs[i]) + "=\"" +
                                            clip(attrs[i + 1]) +
                                            "\">: '%' is not allowed in attribute values (urdfdom would "
                                            "pass it to printf as a format directive)");
      return;
    }
  }
  if (std::strcmp(name, "origin") == 0) {
    for (int i = 0; attrs[i]; i += 2) {
      if ((std::strcmp(attrs[i], "xyz") == 0 || std::strcmp(attrs[i], "rpy") == 0) && !is_urdf_vector3(attrs[i + 1])) {
        st->stop(ErrorCode::kUrdfInvalid, std::string("origin ") + attrs[i] + "=\"" + clip(attrs[i + 1]) +
                                              "\" is not a vector of 3 numbers");
        return;
      }
    }
  }
}

void XMLCALL on_end(void* data, const XML_Char*) { --static_cast<GuardState*>(data)->depth; }

void XMLCALL on_xml_decl(void* data, const XML_Char*, const XML_Char* encoding, int) {
  if (encoding == nullptr) return;
  std::string lower(encoding);
  for (char& ch : lower) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  if (lower != "utf-8") {
    static_cast<GuardState*>(data)->stop(ErrorCode::kUrdfInvalid, "declares encoding '" + clip(encoding) +
                                                                      "'; only UTF-8 is supported");
  }
}

void XMLCALL on_doctype(void* data, const XML_Char* name, const XML_Char*, const XML_Char*, int) {
  static_cast<GuardState*>(data)->stop(ErrorCode::kUrdfInvalid,
                                       "DOCTYPE declarations are not allowed (<!DOCTYPE " + clip(name) + ">)");
}

void XMLCALL on_processing_instruction(void* data, const XML_Char* target, const XML_Char*) {
  static_cast<GuardState*>(data)->stop(ErrorCode::kUrdfInvalid,
                                       "processing instructions are not allowed (<?" + clip(target) + " ...?>)");
}

void XMLCALL on_entity_decl(void* data, const XML_Char* name, int, const XML_Char*, int, const XML_Char*,
                            const XML_Char*, const XML_Char*, const XML_Char*) {
  static_cast<GuardState*>(data)->stop(ErrorCode::kUrdfInvalid,
                                       std::string("entity declarations are not allowed (entity '") + clip(name) + "')");
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

std::string valid_utf8(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  const auto* s = reinterpret_cast<const unsigned char*>(text.data());
  std::size_t i = 0;
  while (i < text.size()) {
    const std::size_t len = utf8_length(s + i, text.size() - i);
    if (len == 0) {
      out += "\xEF\xBF\xBD";
      ++i;
    } else {
      out.append(text, i, len);
      i += len;
    }
  }
  return out;
}

void check_urdf_xml(const std::string& xml) {
  if (xml.size() > kMaxUrdfBytes) {
    fail(ErrorCode::kUrdfUnsupported, "URDF is larger than " + std::to_string(kMaxUrdfBytes >> 20) + " MiB");
  }
  if (xml.size() >= 2 && ((xml[0] == '\xFF' && xml[1] == '\xFE') || (xml[0] == '\xFE' && xml[1] == '\xFF'))) {
    fail(ErrorCode::kUrdfInvalid, "URDF must be UTF-8 (it starts with a UTF-16/UTF-32 byte order mark)");
  }
  // expat takes a document starting "<\0" or "\0<" for UTF-16 whatever it is told,
  // and TinyXML stops at the first NUL: no NUL byte at all (XML has no such character).
  const std::size_t nul = xml.find('\0');
  if (nul != std::string::npos) {
    fail(ErrorCode::kUrdfInvalid, "URDF must be UTF-8 text (NUL byte at offset " + std::to_string(nul) + ")");
  }
  // "UTF-8" overrides whatever the document declares: bytes are read as UTF-8,
  // and on_xml_decl rejects any other declared encoding.
  std::unique_ptr<std::remove_pointer_t<XML_Parser>, void (*)(XML_Parser)> parser(XML_ParserCreate("UTF-8"),
                                                                                 XML_ParserFree);
  if (!parser) fail(ErrorCode::kUrdfInvalid, "cannot create an XML parser");
  GuardState st;
  st.parser = parser.get();
  XML_SetUserData(parser.get(), &st);
  XML_SetElementHandler(parser.get(), on_start, on_end);
  XML_SetXmlDeclHandler(parser.get(), on_xml_decl);
  XML_SetStartDoctypeDeclHandler(parser.get(), on_doctype);
  XML_SetProcessingInstructionHandler(parser.get(), on_processing_instruction);
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
