#include "urlab/document/element.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>

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
  const std::string* text = Get(name);
  if (!text) return std::nullopt;
  auto v = ParseReals(*text);
  if (!v) {
    throw InputError(location_, tag_ + " attribute '" + std::string(name) + "': '" + *text +
                                    "' is not a list of numbers");
  }
  return v;
}

std::optional<int> Element::GetInt(std::string_view name) const {
  auto v = GetReal(name);
  if (!v) return std::nullopt;
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

std::string CheckValue(const AttributeSpec& spec, std::string_view value) {
  switch (spec.type) {
    case ValueType::kReal:
    case ValueType::kInt: {
      auto v = ParseReals(value);
      if (!v) return "'" + std::string(value) + "' is not a list of numbers";
      if (spec.type == ValueType::kInt) {
        for (double x : *v) {
          if (x != std::floor(x)) return "'" + std::string(value) + "' is not a list of integers";
        }
      }
      if (spec.max_count >= 0 && static_cast<int>(v->size()) > spec.max_count) {
        return "expected at most " + std::to_string(spec.max_count) + " number(s), got " +
               std::to_string(v->size());
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

}  // namespace urlab::document
