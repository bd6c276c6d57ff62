#pragma once
// One error style for untrusted input: checks add located findings to a Diagnostics sink instead
// of throwing at the first problem. `urlab validate` prints everything a sink collected; loading
// calls ThrowIfErrors(), which throws the first error as an InputError with "(and N more)".
//
// Thread: a sink is a plain value owned by one thread at a time; no internal locking.
#include <cstddef>
#include <string>
#include <vector>

#include "urlab/core/error.h"

namespace urlab {

// One located finding about user input.
struct Diagnostic {
  enum class Severity { kNote, kWarning, kError };
  Severity severity = Severity::kWarning;
  SourceLocation where;
  std::string message;

  // "file:line: message" (just the message when the location is unknown).
  std::string str() const;
};

// "note", "warning" or "error".
const char* SeverityName(Diagnostic::Severity s);

class Diagnostics {
 public:
  void Add(Diagnostic d);
  void Add(Diagnostic::Severity severity, SourceLocation where, std::string message);
  void Error(SourceLocation where, std::string message);
  void Warning(SourceLocation where, std::string message);
  // An InputError caught from code that throws, as an error; `label` prefixes the message
  // (e.g. the articulation: "left: ").
  void Add(const InputError& e, const std::string& label = {});
  // Every finding of `other`, with `label` prefixed to each message.
  void Append(const std::vector<Diagnostic>& other, const std::string& label = {});

  // Every finding, in the order added.
  const std::vector<Diagnostic>& all() const { return all_; }
  std::vector<Diagnostic> errors() const;
  std::vector<Diagnostic> warnings() const;
  std::size_t error_count() const;
  bool has_errors() const { return error_count() > 0; }
  bool empty() const { return all_.empty(); }

  // Throws the first error as an InputError (its location; "(and N more)" appended when there
  // are more errors). Does nothing when there is no error.
  void ThrowIfErrors() const;

 private:
  std::vector<Diagnostic> all_;
};

}  // namespace urlab
