#pragma once
// The editable MJCF document: a tree of elements whose kinds, attributes and references come
// from the grammar table (grammar.h). Every attribute is optional: an unset attribute lets
// MuJoCo's default chain decide, a set one is written explicitly. Attribute values are kept as
// the exact text that was read, so an element nobody edited is written back exactly as it was
// imported; typed accessors parse on demand and typed setters format with round-trip precision.
//
// Thread: a document is a plain value owned by one thread at a time; no internal locking.
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/core/error.h"
#include "urlab/document/grammar.h"

namespace urlab::document {

// Folders that relative file attributes of an element resolve against (set at import, carried
// along when elements move between documents, e.g. when a scene composes articulations).
struct FileBases {
  std::string model_dir;    // folder of the main model file
  std::string mesh_dir;     // model_dir joined with <compiler meshdir>
  std::string texture_dir;  // model_dir joined with <compiler texturedir>
  bool strip_path = false;  // <compiler strippath="true">

  // Absolute path of `value` for an attribute resolved against `base`.
  std::string Resolve(std::string_view value, FileBase base) const;
};

struct Attribute {
  std::string name;
  std::string value;                    // exact text (XML entities decoded)
  const AttributeSpec* spec = nullptr;  // nullptr: not in the grammar, kept verbatim
};

class Element {
 public:
  // `spec` may be nullptr only for elements outside the grammar (never produced by the reader).
  Element(const ElementSpec* spec, std::string tag);
  ~Element();
  Element(const Element&) = delete;
  Element& operator=(const Element&) = delete;

  const std::string& tag() const { return tag_; }
  const ElementSpec* spec() const { return spec_; }
  // Grammar context id ("body", "default.geom", ...), or the tag when spec() is null.
  const std::string& kind() const;

  // ---- attributes (document order) ----
  const std::vector<Attribute>& attributes() const { return attributes_; }
  bool Has(std::string_view name) const { return Get(name) != nullptr; }
  // Exact text of the attribute, nullptr when unset.
  const std::string* Get(std::string_view name) const;
  std::string GetOr(std::string_view name, std::string_view fallback) const;
  // The element's name (`name`, or `class` for a default), "" when unnamed.
  std::string Name() const;

  // Typed reads; nullopt when unset; InputError (with the element's file:line) when the text
  // does not parse or, for an attribute of the grammar, has a value count or type the grammar
  // refuses (so callers may index up to the grammar's count). GetInt refuses fractions and
  // values outside int; the second GetReals also requires exactly `count` values.
  std::optional<double> GetReal(std::string_view name) const;
  std::optional<std::vector<double>> GetReals(std::string_view name) const;
  std::optional<std::vector<double>> GetReals(std::string_view name, size_t count) const;
  std::optional<int> GetInt(std::string_view name) const;

  // Writes set the attribute (appending it when new) and mark the element edited. Set() checks
  // the value against the grammar when the attribute is known and throws InputError when it is
  // not valid (bad number, too many values, keyword not in the set).
  void Set(std::string_view name, std::string value);
  void SetReal(std::string_view name, double value);
  void SetReals(std::string_view name, std::span<const double> values);
  void SetInt(std::string_view name, int value);
  // Removes the attribute; returns whether it was set.
  bool Unset(std::string_view name);
  // Appends an attribute exactly as read (reader use; no validation, not an edit).
  void AddRawAttribute(std::string name, std::string value);

  // True when any attribute was changed after import (or the element was built in code).
  bool edited() const { return edited_; }
  void set_edited(bool e) { edited_ = e; }

  // ---- tree ----
  Element* parent() { return parent_; }
  const Element* parent() const { return parent_; }
  const std::vector<std::unique_ptr<Element>>& children() const { return children_; }
  // Appends a child of kind `tag` allowed here by the grammar; throws Error otherwise.
  Element& AddChild(std::string_view tag);
  // Inserts an existing element at `index` (clamped); takes ownership.
  Element& InsertChild(size_t index, std::unique_ptr<Element> child);
  // Detaches `child`; returns ownership (nullptr when not a child).
  std::unique_ptr<Element> RemoveChild(const Element* child);
  // Index of `child` among children(), or -1.
  int IndexOf(const Element* child) const;
  // First direct child with `tag`, or nullptr.
  Element* FirstChild(std::string_view tag);
  const Element* FirstChild(std::string_view tag) const;
  // Deep copy (locations and file bases included, parent unset).
  std::unique_ptr<Element> Clone() const;

  // Calls f(element) for this element and every descendant, depth first, document order.
  template <typename F>
  void Visit(F&& f) {
    f(*this);
    for (auto& c : children_) c->Visit(f);
  }
  template <typename F>
  void Visit(F&& f) const {
    f(*this);
    for (const auto& c : children_) static_cast<const Element&>(*c).Visit(f);
  }

  // ---- provenance ----
  const SourceLocation& location() const { return location_; }
  void set_location(SourceLocation loc) { location_ = std::move(loc); }
  const std::shared_ptr<const FileBases>& file_bases() const { return file_bases_; }
  void set_file_bases(std::shared_ptr<const FileBases> b) { file_bases_ = std::move(b); }
  // Absolute path of a file attribute (nullopt when unset or not a file attribute).
  std::optional<std::string> ResolvedFile(std::string_view name) const;
  // "<tag name='x'> at file:line" for messages.
  std::string Describe() const;

 private:
  Attribute* FindAttr(std::string_view name);
  const Attribute* FindAttr(std::string_view name) const;

  const ElementSpec* spec_;
  std::string tag_;
  std::vector<Attribute> attributes_;
  std::vector<std::unique_ptr<Element>> children_;
  Element* parent_ = nullptr;
  SourceLocation location_;
  std::shared_ptr<const FileBases> file_bases_;
  bool edited_ = false;
};

// The namespace attribute `a` of `e` names: the grammar's fixed one, or the one chosen by the
// selector attribute (objtype/reftype). kNone when `a` is not a reference (a default's own
// `class` defines a name rather than naming one) or the selector is missing or unknown.
Namespace ReferencedNamespace(const Element& e, const Attribute& a);

// Formats a real with the shortest text that reads back to the same double.
std::string FormatReal(double v);
// Formats reals separated by single spaces.
std::string FormatReals(std::span<const double> v);
// Parses whitespace-separated reals; nullopt when any token is not a number.
std::optional<std::vector<double>> ParseReals(std::string_view text);
// Checks `value` against `spec` (number syntax, no NaN, int range, value count from the grammar,
// keyword set); returns an error message, or "" when valid.
std::string CheckValue(const AttributeSpec& spec, std::string_view value);

}  // namespace urlab::document
