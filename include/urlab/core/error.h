#pragma once
// Error types raised at URLab's boundaries. Every error that comes from user input (a model
// file, a scene file, a network message) carries enough context to find the offending place.
#include <stdexcept>
#include <string>

namespace urlab {

// A place in a user file; line 0 means "whole file".
struct SourceLocation {
  std::string file;
  int line = 0;
  // "file:line" (or just "file" when the line is unknown, or "" when nothing is known).
  std::string str() const;
};

// Base of every URLab exception.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Bad user input with a location: what() is "file:line: message".
class InputError : public Error {
 public:
  InputError(SourceLocation where, const std::string& message);
  const SourceLocation& where() const { return where_; }
  const std::string& message() const { return message_; }

 private:
  SourceLocation where_;
  std::string message_;
};

// An error reported by MuJoCo through mju_user_error (see mujoco_handlers.h).
class MujocoError : public Error {
 public:
  using Error::Error;
};

}  // namespace urlab
