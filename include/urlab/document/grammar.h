#pragma once
// The MJCF grammar of MuJoCo 2.2.2 as data: which element may contain which, which attributes
// each accepts, their value types and keyword sets, and which attributes name other elements.
//
// The whole grammar lives in one table (src/document/grammar_table.cc), one row per element
// context, written in a small attribute mini-language and parsed once at first use:
//
//   row:      { id, tag, name namespace, child ids, attribute specs }
//   id:       unique per context, e.g. "body", "default.geom", "composite.geom"
//   children: space separated ids; the reader picks the child whose tag matches
//   attribute spec (space separated): NAME ':' TYPE [COUNT] ['@' REF] ['{' kw '|' kw ... '}']
//     TYPE  s string | r real | i int | k keyword | f file (model dir) | m mesh-dir file |
//           t texture-dir file
//     COUNT absent = exactly 1; N = exactly N; N-M = N to M values; * = any number (0 or more)
//     REF   namespace the value names: body joint geom site camera light mesh skin hfield
//           texture material pair exclude equality tendon actuator sensor numeric text tuple key
//           class, or "obj:<attr>" when the namespace is chosen by sibling attribute <attr>
//           (objtype/reftype); see Namespace.
//   e.g. "name:s class:s@class type:k{plane|sphere|box} size:r1-3 pos:r3 material:s@material"
//
// A second table (grammar_dialect_table.cc) holds what MJCF written for MuJoCo 3.x adds and the
// reader accepts (the engine is MuJoCo 3): its rows are marked `dialect`, and a row whose id
// starts with '+' extends the 2.2.2 row of that id with more children and attributes (also
// marked `dialect`); naming an attribute the row already has adds keywords to it (listed in
// `dialect_keywords`) or widens its value count (`dialect_count`, the 2.2.2 counts kept). The
// writer never emits dialect elements or attributes that the bridge has not translated: compiling
// such a document fails with a clear message instead.
//
// Thread: immutable after first use; any thread may read.
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace urlab::document {

// A namespace of named elements (MuJoCo's mjtObj, plus default classes).
enum class Namespace : std::uint8_t {
  kNone,
  kBody,
  kJoint,
  kGeom,
  kSite,
  kCamera,
  kLight,
  kMesh,
  kSkin,
  kHField,
  kTexture,
  kMaterial,
  kPair,
  kExclude,
  kEquality,
  kTendon,
  kActuator,
  kSensor,
  kNumeric,
  kText,
  kTuple,
  kKey,
  kClass,
  kCount
};

// Name used in the grammar table and in messages ("body", "class", ...).
std::string_view NamespaceName(Namespace ns);
// Inverse of NamespaceName; kNone when unknown.
Namespace NamespaceFromName(std::string_view name);
// The namespace MJCF's objtype/reftype keyword selects ("body", "xbody", "geom", "site",
// "camera", "joint", "actuator", "tendon", ...); kNone when unknown.
Namespace NamespaceFromObjType(std::string_view objtype);

enum class ValueType : std::uint8_t { kString, kReal, kInt, kKeyword, kFile };

// Which folder a relative file attribute is resolved against.
enum class FileBase : std::uint8_t { kNone, kModelDir, kMeshDir, kTextureDir };

struct AttributeSpec {
  std::string name;
  ValueType type = ValueType::kString;
  int min_count = 1;  // number of values (for kReal / kInt); 1 for scalars
  int max_count = 1;  // -1: unbounded
  FileBase file_base = FileBase::kNone;
  Namespace ref = Namespace::kNone;  // namespace named by the value, when fixed
  std::string ref_selector;          // sibling attribute choosing the namespace (objtype, ...)
  std::vector<std::string> keywords;
  bool dialect = false;                       // MuJoCo 3.x only: the bridge must translate it
  std::vector<std::string> dialect_keywords;  // 3.x-only values of a 2.2.2 attribute
  // 3.x accepts more (or fewer) values than 2.2.2 (a dialect row naming the attribute with
  // another count widens it): the 2.2.2 counts, which a value outside makes a 3.x value.
  bool dialect_count = false;
  int legacy_min_count = 1;
  int legacy_max_count = 1;
  // Allowed values of a number attribute (every value), from the range table; unbounded unless
  // a row names the attribute.
  double min_value = -std::numeric_limits<double>::infinity();
  double max_value = std::numeric_limits<double>::infinity();
  bool min_exclusive = false;
  bool HasRange() const {
    return min_value != -std::numeric_limits<double>::infinity() ||
           max_value != std::numeric_limits<double>::infinity();
  }

  bool IsReference() const { return ref != Namespace::kNone || !ref_selector.empty(); }
};

struct ElementSpec {
  std::string id;
  std::string tag;
  Namespace name_space = Namespace::kNone;  // the namespace its `name` attribute enters
  std::vector<AttributeSpec> attributes;
  std::vector<const ElementSpec*> children;
  bool dialect = false;  // MuJoCo 3.x only element: the bridge must translate it

  // nullptr when the element has no such attribute / child.
  const AttributeSpec* FindAttribute(std::string_view name) const;
  const ElementSpec* FindChild(std::string_view tag) const;
};

// A range row: the values a number attribute of an element context may take (every value of
// the attribute). Rows are few and deliberate: they refuse input that MuJoCo 2.2.2 accepts but
// that cannot run (a timestep <= 0) or sizes that cannot be allocated.
struct RangeRow {
  const char* id;         // element context ("option", "size")
  const char* attribute;  // attribute name
  double min;
  bool min_exclusive;
  double max;
};

// Raw table row, see the file comment. Defined in grammar_table.cc.
struct GrammarRow {
  const char* id;
  const char* tag;
  const char* name_space;
  const char* children;
  const char* attributes;
};

// The parsed grammar. Get() parses the table on first use and throws urlab::Error if the table
// is inconsistent (a child id with no row, a malformed attribute spec): a programming error.
class Grammar {
 public:
  static const Grammar& Get();

  const ElementSpec& Root() const;  // <mujoco>
  const ElementSpec* Find(std::string_view id) const;
  std::span<const ElementSpec> Elements() const { return elements_; }

  // Parses `rows`, then `dialect_rows`, then applies `ranges` (used by Get() and by tests of the
  // mini-language).
  explicit Grammar(std::span<const GrammarRow> rows, std::span<const GrammarRow> dialect_rows = {},
                   std::span<const RangeRow> ranges = {});

 private:
  std::vector<ElementSpec> elements_;
};

// The actuator elements of MuJoCo 2.2.2 (general, motor, position, ...): the children of the
// grammar table's <actuator> row that have a default template of their own, in table order. The
// one list every module uses (the bridge, the composer, default-class resolution).
std::span<const std::string> ActuatorTags();
bool IsActuatorTag(std::string_view tag);

// The table itself (src/document/grammar_table.cc).
std::span<const GrammarRow> GrammarTable();
// MuJoCo 3.x additions (src/document/grammar_dialect_table.cc).
std::span<const GrammarRow> DialectGrammarTable();
// Value ranges of number attributes (src/document/grammar_table.cc).
std::span<const RangeRow> ValueRangeTable();

}  // namespace urlab::document
