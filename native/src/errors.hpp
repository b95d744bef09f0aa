// The error vocabulary of the contract. Codes equal robot_api.errors.ErrorCode;
// the binding turns an ApiError into the Python class that robot_api assigns.
#pragma once

#include <stdexcept>
#include <string>

namespace rrosfuzz {

enum class ErrorCode : int {
  kUrdfInvalid = 1,
  kUrdfUnsupported = 2,
  kWrongLength = 10,
  kNonFinite = 11,
  kInvalidArgument = 12,
  kDuplicateName = 13,
  kInvalidTrajectory = 14,
  kUnsupportedOperation = 15,
  kUnknownJoint = 20,
  kUnknownLink = 21,
  kUnknownNamedTarget = 22,
  kOutOfBounds = 30,
  kPlanningFailed = 40,
};

class ApiError : public std::runtime_error {
 public:
  ApiError(ErrorCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
  ErrorCode code() const noexcept { return code_; }

 private:
  ErrorCode code_;
};

[[noreturn]] inline void fail(ErrorCode code, const std::string& message) { throw ApiError(code, message); }

}  // namespace rrosfuzz
