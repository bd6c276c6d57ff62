#pragma once
// A whole MJCF model as an editable document: the <mujoco> root element plus what the reader
// learned while importing (source file, compiler settings, diagnostics).
//
// Thread: plain value, one owning thread at a time.
#include <memory>
#include <string>
#include <vector>

#include "urlab/core/diagnostics.h"
#include "urlab/document/element.h"

namespace urlab::document {

// Compiler settings that change how attributes are interpreted (merged over every <compiler>).
struct CompilerSettings {
  bool degree = true;  // angle="degree" (MJCF's default)
  std::string eulerseq = "xyz";
  bool autolimits = false;  // 2.2.2 default
};

// A non-fatal finding of the reader or a later pass (unknown attribute kept, etc.): the core
// diagnostic type (urlab/core/diagnostics.h), so findings move into a Diagnostics sink as they are.
using Diagnostic = urlab::Diagnostic;

class Document {
 public:
  // An empty model: <mujoco model="name"/>.
  Document() : Document(std::string()) {}
  explicit Document(std::string model_name);
  Document(Document&&) noexcept;
  Document& operator=(Document&&) noexcept;
  ~Document();

  Element& root() { return *root_; }
  const Element& root() const { return *root_; }

  // Main file the document was read from ("" for documents built in code).
  const std::string& source_path() const { return source_path_; }
  void set_source_path(std::string p) { source_path_ = std::move(p); }

  // Settings merged from every <compiler> element, in document order.
  CompilerSettings Compiler() const;

  // The first top-level section with `tag` (e.g. "worldbody", "asset"); created (appended)
  // when missing.
  Element& Section(std::string_view tag);
  // Same, but nullptr when missing.
  const Element* FindSection(std::string_view tag) const;

  // Finds a named element in namespace `ns` (by `name`, or `class` for defaults, or the implicit
  // file-stem name of assets). nullptr when none.
  const Element* FindNamed(Namespace ns, std::string_view name) const;
  Element* FindNamed(Namespace ns, std::string_view name);

  std::vector<Diagnostic>& diagnostics() { return diagnostics_; }
  const std::vector<Diagnostic>& diagnostics() const { return diagnostics_; }

  Document Clone() const;

 private:
  std::unique_ptr<Element> root_;
  std::string source_path_;
  std::vector<Diagnostic> diagnostics_;
};

// The name an element defines in its namespace: `name`, `class` for defaults, or for assets read
// from a file without a name, the file name without folder and extension. "" when unnamed.
std::string DefinedName(const Element& e);

}  // namespace urlab::document
