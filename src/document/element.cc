#include "urlab/document/element.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>

#include "core/gcc_workarounds.h"

namespace urlab::document {

namespace fs = std::filesystem;

std::string FileBases::Resolve(std::string_view value, FileBase base) const {
  std::string text(value);
  if (strip_path) {
    // MuJoCo strips both separators, so Windows-style paths work on any host.
    const size_t cut = text.find_last_of("/\\");
    if (cut != std::string::npos) text = text.substr(cut + 1);
  }
  fs::path file(text);
  if (file.is_absolute()) return file.lexically_normal().string();
  const std::string* dir = &model_dir;
  if (base == FileBase::kMeshDir) dir = &mesh_dir;
  if (base == FileBase::kTextureDir) dir = &texture_dir;
  return (fs::path(*dir) / file).lexically_normal().string();
}

Element::Element(const ElementSpec* spec, std::string tag) : spec_(spec), tag_(std::move(tag)) {}

Element::~Element() = default;

const std::string& Element::kind() const { return spec_ ? spec_->id : tag_; }

Attribute* Element::FindAttr(std::string_view name) {
  for (Attribute& a : attributes_) {
    if (a.name == name) return &a;
  }
  return nullptr;
}

const Attribute* Element::FindAttr(std::string_view name) const {
  for (const Attribute& a : attributes_) {
    if (a.name == name) return &a;
  }
  return nullptr;
}

const std::string* Element::Get(std::string_view name) const {
  const Attribute* a = FindAttr(name);
  return a ? &a->value : nullptr;
}

std::string Element::GetOr(std::string_view name, std::string_view fallback) const {
  const std::string* v = Get(name);
  return v ? *v : std::string(fallback);
}

std::string Element::Name() const {
  const std::string* v = Get(spec_ && spec_->name_space == Namespace::kClass ? "class" : "name");
  return v ? *v : std::string();
}

std::optional<double> Element::GetReal(std::string_view name) const {
  auto v = GetReals(name);
  if (!v) return std::nullopt;
  if (v->size() != 1) {
    throw InputError(location_,
                     tag_ + " attribute '" + std::string(name) + "': expected one number");
  }
  return (*v)[0];
}

std::optional<std::vector<double>> Element::GetReals(std::string_view name) const {
  const Attribute* a = FindAttr(name);
  if (!a) return std::nullopt;
  // The grammar's value count and type are authoritative: nothing indexes a value that the
  // grammar would refuse, whichever path built the element.
  if (a->spec && (a->spec->type == ValueType::kReal || a->spec->type == ValueType::kInt)) {
    const std::string problem = CheckValue(*a->spec, a->value);
    if (!problem.empty()) {
      throw InputError(location_,
                       "<" + tag_ + "> attribute '" + std::string(name) + "': " + problem);
    }
  }
  auto v = ParseReals(a->value);
  if (!v) {
    throw InputError(location_, "<" + tag_ + "> attribute '" + std::string(name) + "': '" +
                                    a->value + "' is not a list of numbers");
  }
  return v;
}

std::optional<std::vector<double>> Element::GetReals(std::string_view name, size_t count) const {
  auto v = GetReals(name);
  if (v && v->size() != count) {
    throw InputError(location_, "<" + tag_ + "> attribute '" + std::string(name) + "': expected " +
                                    std::to_string(count) + " number(s), got " +
                                    std::to_string(v->size()));
  }
  return v;
}

std::optional<int> Element::GetInt(std::string_view name) const {
  auto v = GetReal(name);
  if (!v) return std::nullopt;
  if (!(*v >= std::numeric_limits<int>::min() && *v <= std::numeric_limits<int>::max()) ||
      *v != std::floor(*v)) {
    throw InputError(location_, "<" + tag_ + "> attribute '" + std::string(name) +
                                    "': " + FormatReal(*v) + " is not an integer in range");
  }
  return static_cast<int>(*v);
}

void Element::Set(std::string_view name, std::string value) {
  const AttributeSpec* spec = spec_ ? spec_->FindAttribute(name) : nullptr;
  if (spec) {
    const std::string problem = CheckValue(*spec, value);
    if (!problem.empty()) {
      throw InputError(location_,
                       "<" + tag_ + "> attribute '" + std::string(name) + "': " + problem);
    }
  }
  edited_ = true;
  if (Attribute* a = FindAttr(name)) {
    a->value = std::move(value);
    a->spec = spec;
    return;
  }
  attributes_.push_back(Attribute{std::string(name), std::move(value), spec});
}

void Element::SetReal(std::string_view name, double value) { Set(name, FormatReal(value)); }

void Element::SetReals(std::string_view name, std::span<const double> values) {
  Set(name, FormatReals(values));
}

void Element::SetInt(std::string_view name, int value) { Set(name, std::to_string(value)); }

bool Element::Unset(std::string_view name) {
  auto it = std::find_if(attributes_.begin(), attributes_.end(),
                         [&](const Attribute& a) { return a.name == name; });
  if (it == attributes_.end()) return false;
  attributes_.erase(it);
  edited_ = true;
  return true;
}

void Element::AddRawAttribute(std::string name, std::string value) {
  const AttributeSpec* spec = spec_ ? spec_->FindAttribute(name) : nullptr;
  attributes_.push_back(Attribute{std::move(name), std::move(value), spec});
}

Element& Element::AddChild(std::string_view tag) {
  const ElementSpec* child_spec = spec_ ? spec_->FindChild(tag) : nullptr;
  if (!child_spec) {
    throw Error("<" + std::string(tag) + "> is not allowed inside <" + tag_ + ">");
  }
  auto child = std::make_unique<Element>(child_spec, std::string(tag));
  child->file_bases_ = file_bases_;
  child->edited_ = true;
  return InsertChild(children_.size(), std::move(child));
}

Element& Element::InsertChild(size_t index, std::unique_ptr<Element> child) {
  child->parent_ = this;
  index = std::min(index, children_.size());
  children_.insert(children_.begin() + static_cast<std::ptrdiff_t>(index), std::move(child));
  return *children_[index];
}

std::unique_ptr<Element> Element::RemoveChild(const Element* child) {
  const int i = IndexOf(child);
  if (i < 0) return nullptr;
  std::unique_ptr<Element> out = std::move(children_[static_cast<size_t>(i)]);
  children_.erase(children_.begin() + i);
  out->parent_ = nullptr;
  return out;
}

int Element::IndexOf(const Element* child) const {
  for (size_t i = 0; i < children_.size(); ++i) {
    if (children_[i].get() == child) return static_cast<int>(i);
  }
  return -1;
}

Element* Element::FirstChild(std::string_view tag) {
  for (auto& c : children_) {
    if (c->tag_ == tag) return c.get();
  }
  return nullptr;
}

const Element* Element::FirstChild(std::string_view tag) const {
  for (const auto& c : children_) {
    if (c->tag_ == tag) return c.get();
  }
  return nullptr;
}

std::unique_ptr<Element> Element::Clone() const {
  auto copy = std::make_unique<Element>(spec_, tag_);
  copy->attributes_ = attributes_;
  copy->location_ = location_;
  copy->file_bases_ = file_bases_;
  copy->edited_ = edited_;
  copy->children_.reserve(children_.size());
  for (const auto& c : children_) {
    auto cc = c->Clone();
    cc->parent_ = copy.get();
    copy->children_.push_back(std::move(cc));
  }
  return copy;
}

std::optional<std::string> Element::ResolvedFile(std::string_view name) const {
  const Attribute* a = FindAttr(name);
  if (!a || !a->spec || a->spec->type != ValueType::kFile) return std::nullopt;
  if (!file_bases_) return a->value;
  return file_bases_->Resolve(a->value, a->spec->file_base);
}

std::string Element::Describe() const {
  std::string out = "<" + tag_;
  const std::string n = Name();
  if (!n.empty()) out += " '" + n + "'";
  out += ">";
  const std::string where = location_.str();
  if (!where.empty()) out += " at " + where;
  return out;
}

Namespace ReferencedNamespace(const Element& e, const Attribute& a) {
  if (!a.spec || !a.spec->IsReference()) return Namespace::kNone;
  if (e.spec() && e.spec()->name_space == Namespace::kClass && a.name == "class") {
    return Namespace::kNone;
  }
  if (a.spec->ref_selector.empty()) return a.spec->ref;
  const std::string* sel = e.Get(a.spec->ref_selector);
  return sel ? NamespaceFromObjType(*sel) : Namespace::kNone;
}

std::string FormatReal(double v) {
  char buf[64];
  // Whole numbers in plain digits ("5000000", not "5e+06"): MuJoCo reads integer attributes with
  // strtol, which would stop at the exponent.
  if (v == std::floor(v) && std::abs(v) < 1e15) {
    auto [p, ec] = std::to_chars(buf, buf + sizeof(buf), v, std::chars_format::fixed);
    if (ec == std::errc()) return std::string(buf, p);
  }
  auto [p, ec] = std::to_chars(buf, buf + sizeof(buf), v);
  if (ec != std::errc()) return std::to_string(v);
  return std::string(buf, p);
}

std::string FormatReals(std::span<const double> v) {
  std::string out;
  for (size_t i = 0; i < v.size(); ++i) {
    if (i) out += ' ';
    out += FormatReal(v[i]);
  }
  return out;
}

namespace {
bool IsSpace(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}
}  // namespace

std::optional<std::vector<double>> ParseReals(std::string_view text) {
  std::vector<double> out;
  size_t i = 0;
  std::string token;
  while (i < text.size()) {
    while (i < text.size() && IsSpace(text[i])) ++i;
    if (i >= text.size()) break;
    size_t j = i;
    while (j < text.size() && !IsSpace(text[j])) ++j;
    token.assign(text.substr(i, j - i));
    char* end = nullptr;
    const double v = std::strtod(token.c_str(), &end);
    if (end != token.c_str() + token.size()) return std::nullopt;
    out.push_back(v);
    i = j;
  }
  return out;
}

namespace {
// True when every whitespace-separated token is [+-]digits.
bool PlainIntegers(std::string_view text) {
  bool in_token = false, has_digit = false;
  for (size_t i = 0; i <= text.size(); ++i) {
    const char c = i < text.size() ? text[i] : ' ';
    if (IsSpace(c)) {
      if (in_token && !has_digit) return false;
      in_token = has_digit = false;
      continue;
    }
    if ((c == '+' || c == '-') && !in_token) {
      in_token = true;
      continue;
    }
    if (c < '0' || c > '9') return false;
    in_token = has_digit = true;
  }
  return true;
}

// "6 numbers", "1 integer".
std::string CountText(int n, const AttributeSpec& spec) {
  const char* unit = spec.type == ValueType::kInt ? " integer" : " number";
  return std::to_string(n) + unit + (n == 1 ? "" : "s");
}

// "> 0 and finite", "-1 to 2147483647".
std::string RangeText(const AttributeSpec& spec) {
  const bool finite_max = spec.max_value == std::numeric_limits<double>::max();
  const std::string lo = (spec.min_exclusive ? "> " : ">= ") + FormatReal(spec.min_value);
  if (finite_max) return lo + " and finite";
  return FormatReal(spec.min_value) + (spec.min_exclusive ? " (exclusive)" : "") + " to " +
         FormatReal(spec.max_value);
}
}  // namespace

// -O3: a false -Wrestrict inside std::string's operator+ (GCC PR 105329 / 105651).
URLAB_GCC_IGNORE("-Wrestrict")
std::string CheckValue(const AttributeSpec& spec, std::string_view value) {
  switch (spec.type) {
    case ValueType::kReal:
    case ValueType::kInt: {
      auto v = ParseReals(value);
      if (!v) return "'" + std::string(value) + "' is not a list of numbers";
      for (double x : *v) {
        if (std::isnan(x)) return "'" + std::string(value) + "' contains NaN";
      }
      if (spec.type == ValueType::kInt) {
        // MuJoCo reads ints with strtol: "5e+06" would silently be 5, "0x10" 0. Only plain
        // decimal digits are integers.
        if (!PlainIntegers(value)) {
          return "'" + std::string(value) + "' is not a list of integers (plain decimal digits)";
        }
        for (double x : *v) {
          if (x != std::floor(x)) return "'" + std::string(value) + "' is not a list of integers";
          if (x < std::numeric_limits<int>::min() || x > std::numeric_limits<int>::max()) {
            return "'" + std::string(value) + "' is out of the range of an int";
          }
        }
      }
      if (spec.HasRange()) {
        for (double x : *v) {
          const bool low = spec.min_exclusive ? !(x > spec.min_value) : !(x >= spec.min_value);
          if (low || !(x <= spec.max_value)) {
            return FormatReal(x) + " is out of range (expected " + RangeText(spec) + ")";
          }
        }
      }
      // Infinity is refused like NaN: MuJoCo 2.2.2 takes it and computes garbage (an infinite
      // size, mass or range) instead of an error.
      for (double x : *v) {
        if (std::isinf(x)) return "'" + std::string(value) + "' contains an infinite value";
      }
      const int n = static_cast<int>(v->size());
      if (spec.max_count >= 0 && n > spec.max_count) {
        return "expected at most " + CountText(spec.max_count, spec) + ", got " + std::to_string(n);
      }
      // MuJoCo refuses an empty value even where any number of values is allowed.
      if (const int lo = std::max(spec.min_count, 1); n < lo) {
        return "expected at least " + CountText(lo, spec) + ", got " + std::to_string(n);
      }
      return "";
    }
    case ValueType::kKeyword: {
      for (const std::string& k : spec.keywords) {
        if (k == value) return "";
      }
      std::string allowed;
      for (const std::string& k : spec.keywords) allowed += (allowed.empty() ? "" : ", ") + k;
      return "invalid keyword '" + std::string(value) + "' (expected one of: " + allowed + ")";
    }
    case ValueType::kString:
    case ValueType::kFile:
      return "";
  }
  return "";
}
URLAB_GCC_RESTORE

}  // namespace urlab::document
