#include "urlab/document/document.h"

namespace urlab::document {

Document::Document(std::string model_name)
    : root_(std::make_unique<Element>(&Grammar::Get().Root(), "mujoco")) {
  if (!model_name.empty()) root_->AddRawAttribute("model", std::move(model_name));
  root_->set_file_bases(std::make_shared<FileBases>());
}

Document::Document(Document&&) noexcept = default;
Document& Document::operator=(Document&&) noexcept = default;
Document::~Document() = default;

CompilerSettings Document::Compiler() const {
  CompilerSettings s;
  for (const auto& c : root_->children()) {
    if (c->tag() != "compiler") continue;
    if (const std::string* v = c->Get("angle")) s.degree = *v != "radian";
    if (const std::string* v = c->Get("eulerseq")) s.eulerseq = *v;
    if (const std::string* v = c->Get("autolimits")) s.autolimits = *v == "true";
  }
  return s;
}

Element& Document::Section(std::string_view tag) {
  if (Element* e = root_->FirstChild(tag)) return *e;
  return root_->AddChild(tag);
}

const Element* Document::FindSection(std::string_view tag) const { return root_->FirstChild(tag); }

const Element* Document::FindNamed(Namespace ns, std::string_view name) const {
  const Element* found = nullptr;
  root_->Visit([&](const Element& e) {
    if (found || !e.spec() || e.spec()->name_space != ns) return;
    if (DefinedName(e) == name) found = &e;
  });
  return found;
}

Element* Document::FindNamed(Namespace ns, std::string_view name) {
  return const_cast<Element*>(static_cast<const Document*>(this)->FindNamed(ns, name));
}

Document Document::Clone() const {
  Document d;
  d.root_ = root_->Clone();
  d.source_path_ = source_path_;
  d.diagnostics_ = diagnostics_;
  return d;
}

std::string DefinedName(const Element& e) {
  std::string n = e.Name();
  if (!n.empty() || !e.spec()) return n;
  switch (e.spec()->name_space) {
    case Namespace::kMesh:
    case Namespace::kSkin:
    case Namespace::kHField:
    case Namespace::kTexture:
      // MuJoCo 2.2.2 (and 3.x): the file name after the last slash or backslash, up to its last '.'
      // (only `file`; a texture from six cube files has no implicit name).
      if (const std::string* f = e.Get("file")) {
        const size_t slash = f->find_last_of("/\\");
        std::string base = slash == std::string::npos ? *f : f->substr(slash + 1);
        const size_t dot = base.find_last_of('.');
        return dot == std::string::npos ? base : base.substr(0, dot);
      }
      return n;
    default:
      return n;
  }
}

}  // namespace urlab::document
