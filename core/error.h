#pragma once
// The project's error type: every library folder throws proctex::Error with a message that says
// what is wrong and a hint that says what to do. cli/ prints "proctex: error: <message> (<hint>)"
// and exits 1; UsageError exits 2.
#include <stdexcept>
#include <string>

namespace proctex {

class Error : public std::runtime_error {
 public:
  explicit Error(std::string message, std::string hint = {})
      : std::runtime_error(message), message_(std::move(message)), hint_(std::move(hint)) {}
  const std::string& message() const { return message_; }
  const std::string& hint() const { return hint_; }

 private:
  std::string message_;
  std::string hint_;
};

// Bad command-line usage or a malformed argument the user typed (exit code 2).
class UsageError : public Error {
 public:
  using Error::Error;
};

}  // namespace proctex
