#include "urlab/document/grammar.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <unordered_map>

#include "urlab/core/error.h"

namespace urlab::document {

namespace {

constexpr std::array<std::string_view, static_cast<size_t>(Namespace::kCount)> kNamespaceNames = {
    "",         "body",   "joint",   "geom",     "site",  "camera",  "light",    "mesh",
    "skin",     "hfield", "texture", "material", "pair",  "exclude", "equality", "tendon",
    "actuator", "sensor", "numeric", "text",     "tuple", "key",     "class"};

std::vector<std::string_view> SplitSpaces(std::string_view s) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && s[i] == ' ') ++i;
    size_t j = i;
    // Keyword lists in braces never contain spaces, so a plain split is enough.
    while (j < s.size() && s[j] != ' ') ++j;
    if (j > i) out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

[[noreturn]] void Bad(std::string_view row, std::string_view spec, std::string_view why) {
  throw Error("MJCF grammar table, row '" + std::string(row) + "', attribute '" +
              std::string(spec) + "': " + std::string(why));
}

int ParseCount(std::string_view row, std::string_view spec, std::string_view s) {
  int v = 0;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || p != s.data() + s.size()) Bad(row, spec, "bad count");
  return v;
}

AttributeSpec ParseAttribute(std::string_view row, std::string_view spec) {
  AttributeSpec a;
  const size_t colon = spec.find(':');
  if (colon == std::string_view::npos || colon == 0) Bad(row, spec, "missing ':'");
  a.name = std::string(spec.substr(0, colon));
  std::string_view rest = spec.substr(colon + 1);
  if (rest.empty()) Bad(row, spec, "missing type");
  switch (rest[0]) {
    case 's':
      a.type = ValueType::kString;
      break;
    case 'r':
      a.type = ValueType::kReal;
      break;
    case 'i':
      a.type = ValueType::kInt;
      break;
    case 'k':
      a.type = ValueType::kKeyword;
      break;
    case 'f':
      a.type = ValueType::kFile;
      a.file_base = FileBase::kModelDir;
      break;
    case 'm':
      a.type = ValueType::kFile;
      a.file_base = FileBase::kMeshDir;
      break;
    case 't':
      a.type = ValueType::kFile;
      a.file_base = FileBase::kTextureDir;
      break;
    default:
      Bad(row, spec, "unknown type letter");
  }
  rest.remove_prefix(1);
  // Keyword list.
  if (const size_t brace = rest.find('{'); brace != std::string_view::npos) {
    if (rest.back() != '}') Bad(row, spec, "unterminated keyword list");
    std::string_view kws = rest.substr(brace + 1, rest.size() - brace - 2);
    size_t i = 0;
    while (i <= kws.size()) {
      size_t j = kws.find('|', i);
      if (j == std::string_view::npos) j = kws.size();
      a.keywords.emplace_back(kws.substr(i, j - i));
      i = j + 1;
    }
    rest = rest.substr(0, brace);
  }
  if (a.type == ValueType::kKeyword && a.keywords.empty()) Bad(row, spec, "keyword without list");
  // Reference.
  if (const size_t at = rest.find('@'); at != std::string_view::npos) {
    std::string_view ref = rest.substr(at + 1);
    if (ref.starts_with("obj:")) {
      a.ref_selector = std::string(ref.substr(4));
    } else {
      a.ref = NamespaceFromName(ref);
      if (a.ref == Namespace::kNone) Bad(row, spec, "unknown namespace");
    }
    rest = rest.substr(0, at);
  }
  // Count.
  if (rest.empty()) {
    a.min_count = a.max_count = 1;
  } else if (rest == "*") {
    a.min_count = 0;
    a.max_count = -1;
  } else if (const size_t dash = rest.find('-'); dash != std::string_view::npos) {
    a.min_count = ParseCount(row, spec, rest.substr(0, dash));
    a.max_count = ParseCount(row, spec, rest.substr(dash + 1));
  } else {
    a.min_count = a.max_count = ParseCount(row, spec, rest);
  }
  return a;
}

AttributeSpec* FindMutable(ElementSpec& e, std::string_view name) {
  for (AttributeSpec& a : e.attributes) {
    if (a.name == name) return &a;
  }
  return nullptr;
}

}  // namespace

std::string_view NamespaceName(Namespace ns) { return kNamespaceNames[static_cast<size_t>(ns)]; }

Namespace NamespaceFromName(std::string_view name) {
  for (size_t i = 1; i < kNamespaceNames.size(); ++i) {
    if (kNamespaceNames[i] == name) return static_cast<Namespace>(i);
  }
  return Namespace::kNone;
}

Namespace NamespaceFromObjType(std::string_view objtype) {
  if (objtype == "xbody") return Namespace::kBody;
  return NamespaceFromName(objtype);
}

const AttributeSpec* ElementSpec::FindAttribute(std::string_view n) const {
  for (const AttributeSpec& a : attributes) {
    if (a.name == n) return &a;
  }
  return nullptr;
}

const ElementSpec* ElementSpec::FindChild(std::string_view t) const {
  for (const ElementSpec* c : children) {
    if (c->tag == t) return c;
  }
  return nullptr;
}

Grammar::Grammar(std::span<const GrammarRow> rows, std::span<const GrammarRow> dialect_rows,
                 std::span<const RangeRow> ranges) {
  // Rows of the main table, then new dialect rows; '+id' dialect rows extend existing ones.
  struct Source {
    const GrammarRow* row;
    bool dialect;
  };
  std::vector<Source> fresh;
  std::vector<const GrammarRow*> extensions;
  for (const GrammarRow& r : rows) fresh.push_back({&r, false});
  for (const GrammarRow& r : dialect_rows) {
    if (r.id[0] == '+') {
      extensions.push_back(&r);
    } else {
      fresh.push_back({&r, true});
    }
  }
  elements_.resize(fresh.size());  // never resized again: children point into it
  std::unordered_map<std::string_view, size_t> index;
  for (size_t i = 0; i < fresh.size(); ++i) {
    const GrammarRow& r = *fresh[i].row;
    ElementSpec& e = elements_[i];
    e.id = r.id;
    e.tag = r.tag;
    e.dialect = fresh[i].dialect;
    if (r.name_space[0] != '\0') {
      e.name_space = NamespaceFromName(r.name_space);
      if (e.name_space == Namespace::kNone) Bad(r.id, r.name_space, "unknown name namespace");
    }
    for (std::string_view spec : SplitSpaces(r.attributes)) {
      e.attributes.push_back(ParseAttribute(r.id, spec));
      e.attributes.back().dialect = e.dialect;
    }
    if (!index.emplace(r.id, i).second) Bad(r.id, "", "duplicate row id");
  }
  auto link_children = [&](const GrammarRow& r, ElementSpec& e) {
    for (std::string_view child : SplitSpaces(r.children)) {
      auto it = index.find(child);
      if (it == index.end()) Bad(r.id, child, "unknown child id");
      e.children.push_back(&elements_[it->second]);
    }
  };
  for (size_t i = 0; i < fresh.size(); ++i) link_children(*fresh[i].row, elements_[i]);
  for (const GrammarRow* r : extensions) {
    auto it = index.find(std::string_view(r->id + 1));
    if (it == index.end()) Bad(r->id, "", "extends an unknown row");
    ElementSpec& e = elements_[it->second];
    for (std::string_view spec : SplitSpaces(r->attributes)) {
      AttributeSpec added = ParseAttribute(r->id, spec);
      // An attribute 2.2.2 already has gains the dialect's extra keywords (e.g. implicitfast).
      if (AttributeSpec* existing = FindMutable(e, added.name)) {
        for (const std::string& k : added.keywords) {
          if (std::find(existing->keywords.begin(), existing->keywords.end(), k) ==
              existing->keywords.end()) {
            existing->keywords.push_back(k);
            existing->dialect_keywords.push_back(k);
          }
        }
        if (added.min_count != existing->min_count || added.max_count != existing->max_count) {
          existing->dialect_count = true;
          existing->legacy_min_count = existing->min_count;
          existing->legacy_max_count = existing->max_count;
          existing->min_count = added.min_count;
          existing->max_count = added.max_count;
        }
        continue;
      }
      added.dialect = true;
      e.attributes.push_back(std::move(added));
    }
    link_children(*r, e);
  }
  if (elements_.empty() || elements_[0].tag != "mujoco") {
    throw Error("MJCF grammar table: the first row must be <mujoco>");
  }
  for (const RangeRow& r : ranges) {
    auto it = index.find(r.id);
    if (it == index.end()) Bad(r.id, r.attribute, "range row for an unknown row");
    AttributeSpec* a = FindMutable(elements_[it->second], r.attribute);
    if (!a || (a->type != ValueType::kReal && a->type != ValueType::kInt)) {
      Bad(r.id, r.attribute, "range row for an attribute that is not a number");
    }
    a->min_value = r.min;
    a->min_exclusive = r.min_exclusive;
    a->max_value = r.max;
  }
}

const Grammar& Grammar::Get() {
  static const Grammar grammar(GrammarTable(), DialectGrammarTable(), ValueRangeTable());
  return grammar;
}

const ElementSpec& Grammar::Root() const { return elements_[0]; }

const ElementSpec* Grammar::Find(std::string_view id) const {
  for (const ElementSpec& e : elements_) {
    if (e.id == id) return &e;
  }
  return nullptr;
}

std::span<const std::string> ActuatorTags() {
  static const std::vector<std::string> tags = [] {
    std::vector<std::string> out;
    const Grammar& g = Grammar::Get();
    for (const ElementSpec* c : g.Find("actuator")->children) {
      if (!c->dialect && g.Find("default." + c->tag)) out.push_back(c->tag);
    }
    return out;
  }();
  return tags;
}

bool IsActuatorTag(std::string_view tag) {
  const auto tags = ActuatorTags();
  return std::find(tags.begin(), tags.end(), tag) != tags.end();
}

}  // namespace urlab::document
