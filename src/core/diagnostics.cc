#include "urlab/core/diagnostics.h"

namespace urlab {

std::string Diagnostic::str() const {
  const std::string w = where.str();
  return w.empty() ? message : w + ": " + message;
}

const char* SeverityName(Diagnostic::Severity s) {
  switch (s) {
    case Diagnostic::Severity::kNote:
      return "note";
    case Diagnostic::Severity::kWarning:
      return "warning";
    case Diagnostic::Severity::kError:
      return "error";
  }
  return "error";
}

void Diagnostics::Add(Diagnostic d) { all_.push_back(std::move(d)); }

void Diagnostics::Add(Diagnostic::Severity severity, SourceLocation where, std::string message) {
  all_.push_back(Diagnostic{severity, std::move(where), std::move(message)});
}

void Diagnostics::Error(SourceLocation where, std::string message) {
  Add(Diagnostic::Severity::kError, std::move(where), std::move(message));
}

void Diagnostics::Warning(SourceLocation where, std::string message) {
  Add(Diagnostic::Severity::kWarning, std::move(where), std::move(message));
}

void Diagnostics::Add(const InputError& e, const std::string& label) {
  Error(e.where(), label + e.message());
}

void Diagnostics::Append(const std::vector<Diagnostic>& other, const std::string& label) {
  for (const Diagnostic& d : other) Add(d.severity, d.where, label + d.message);
}

std::vector<Diagnostic> Diagnostics::errors() const {
  std::vector<Diagnostic> out;
  for (const Diagnostic& d : all_) {
    if (d.severity == Diagnostic::Severity::kError) out.push_back(d);
  }
  return out;
}

std::vector<Diagnostic> Diagnostics::warnings() const {
  std::vector<Diagnostic> out;
  for (const Diagnostic& d : all_) {
    if (d.severity == Diagnostic::Severity::kWarning) out.push_back(d);
  }
  return out;
}

std::size_t Diagnostics::error_count() const {
  std::size_t n = 0;
  for (const Diagnostic& d : all_) n += d.severity == Diagnostic::Severity::kError;
  return n;
}

void Diagnostics::ThrowIfErrors() const {
  const Diagnostic* first = nullptr;
  for (const Diagnostic& d : all_) {
    if (d.severity == Diagnostic::Severity::kError) {
      first = &d;
      break;
    }
  }
  if (!first) return;
  const std::size_t more = error_count() - 1;
  if (more == 0) throw InputError(first->where, first->message);
  throw InputError(first->where,
                   first->message + " (and " + std::to_string(more) + " more problem(s))");
}

}  // namespace urlab
