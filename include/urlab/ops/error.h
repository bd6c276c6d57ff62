#pragma once
// An operation refused: the wire error code (docs/network.md, "Errors": unknown_articulation,
// dim_mismatch, bad_value, ...) and a message naming the field. Every operation of the ops layer
// checks its request whole before it changes anything and throws this; the step server answers
// it as {op: error, code, message}, the viewer shows the message, the CLI prints it.
//
// Thread: any (a value type).
#include <string>
#include <utility>

#include "urlab/core/error.h"

namespace urlab::ops {

struct OpError : Error {
  OpError(std::string code_, std::string message_)
      : Error(message_), code(std::move(code_)), message(std::move(message_)) {}
  std::string code, message;
};

[[noreturn]] inline void Fail(std::string code, std::string message) {
  throw OpError(std::move(code), std::move(message));
}

}  // namespace urlab::ops
