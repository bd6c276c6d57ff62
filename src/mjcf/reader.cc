#include "urlab/mjcf/reader.h"

#include <tinyxml2.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include "urlab/core/files.h"

namespace urlab::mjcf {

namespace fs = std::filesystem;
using document::AttributeSpec;
using document::Diagnostic;
using document::Document;
using document::Element;
using document::ElementSpec;
using document::FileBases;
using document::Namespace;

namespace {

class Reader {
 public:
  Reader(const ReadOptions& options, std::string main_path)
      : options_(options), main_path_(std::move(main_path)) {
    model_dir_ = fs::absolute(fs::path(main_path_)).parent_path().lexically_normal().string();
  }

  Document Read(const std::string& text) {
    tinyxml2::XMLDocument xml;
    const tinyxml2::XMLElement* top = Parse(xml, text, main_path_);
    if (std::string_view(top->Name()) != "mujoco") {
      throw InputError(
          {main_path_, top->GetLineNum()},
          "the top-level element must be <mujoco>, found <" + std::string(top->Name()) + ">");
    }
    Document doc;
    doc.set_source_path(main_path_);
    Element& root = doc.root();
    while (!root.attributes().empty()) root.Unset(root.attributes().front().name);
    root.set_edited(false);
    root.set_location({main_path_, top->GetLineNum()});
    doc_ = &doc;
    include_stack_.push_back(fs::weakly_canonical(main_path_).string());
    ConvertAttributes(*top, root, main_path_);
    ConvertChildren(*top, root, main_path_);
    AssignFileBases(doc);
    if (options_.check_files) ThrowFirst(FindMissingFiles, doc);
    if (options_.check_references) {
      ThrowFirst(FindDuplicateNames, doc);
      ThrowFirst(FindDanglingReferences, doc);
    }
    return doc;
  }

 private:
  // Runs one check into a fresh sink and throws its first error ("(and N more)").
  template <typename Check>
  static void ThrowFirst(Check check, const Document& doc) {
    Diagnostics sink;
    check(doc, sink, std::string());
    sink.ThrowIfErrors();
  }

  // Parses `text`; returns its single top-level element.
  static const tinyxml2::XMLElement* Parse(tinyxml2::XMLDocument& xml, const std::string& text,
                                           const std::string& file) {
    if (text.find('<') == std::string::npos) {
      throw InputError({file, 0},
                       "malformed XML: no root element (the file is empty or has no "
                       "elements)");
    }
    if (xml.Parse(text.data(), text.size()) != tinyxml2::XML_SUCCESS) {
      std::string why = xml.ErrorStr() ? xml.ErrorStr() : "parse error";
      throw InputError({file, xml.ErrorLineNum()}, "malformed XML: " + why);
    }
    const tinyxml2::XMLElement* top = xml.RootElement();
    if (!top) throw InputError({file, 0}, "malformed XML: no root element (only comments?)");
    if (const auto* second = top->NextSiblingElement()) {
      throw InputError({file, second->GetLineNum()}, "malformed XML: more than one root element");
    }
    return top;
  }

  void ConvertAttributes(const tinyxml2::XMLElement& from, Element& to, const std::string& file) {
    for (const tinyxml2::XMLAttribute* a = from.FirstAttribute(); a; a = a->Next()) {
      to.AddRawAttribute(a->Name(), a->Value());
      const AttributeSpec* spec = to.spec()->FindAttribute(a->Name());
      if (!spec) {
        doc_->diagnostics().push_back(
            Diagnostic{Diagnostic::Severity::kWarning,
                       {file, a->GetLineNum()},
                       "<" + to.tag() + "> unknown attribute '" + a->Name() +
                           "' (not in MuJoCo 2.2.2's grammar): kept verbatim"});
        continue;
      }
      const std::string problem = document::CheckValue(*spec, a->Value());
      if (!problem.empty()) {
        throw InputError({file, a->GetLineNum()},
                         "<" + to.tag() + "> attribute '" + a->Name() + "': " + problem);
      }
    }
  }

  void ConvertChildren(const tinyxml2::XMLElement& from, Element& to, const std::string& file) {
    for (const tinyxml2::XMLElement* c = from.FirstChildElement(); c; c = c->NextSiblingElement()) {
      const std::string_view tag = c->Name();
      if (tag == "include") {
        Include(*c, to, file);
        continue;
      }
      const ElementSpec* spec = to.spec()->FindChild(tag);
      if (!spec) {
        throw InputError({file, c->GetLineNum()},
                         "unknown element <" + std::string(tag) + "> inside <" + to.tag() + ">");
      }
      auto child = std::make_unique<Element>(spec, std::string(tag));
      child->set_location({file, c->GetLineNum()});
      Element& added = to.InsertChild(to.children().size(), std::move(child));
      ConvertAttributes(*c, added, file);
      ConvertChildren(*c, added, file);
    }
  }

  void Include(const tinyxml2::XMLElement& inc, Element& parent, const std::string& file) {
    const SourceLocation where{file, inc.GetLineNum()};
    const char* name = inc.Attribute("file");
    if (!name || !*name) throw InputError(where, "<include> needs a 'file' attribute");
    for (const tinyxml2::XMLAttribute* a = inc.FirstAttribute(); a; a = a->Next()) {
      if (std::string_view(a->Name()) != "file") {
        throw InputError(where, "<include> attribute '" + std::string(a->Name()) + "' is unknown");
      }
    }
    fs::path path(name);
    if (path.is_relative()) path = fs::path(model_dir_) / path;
    const std::string shown = path.lexically_normal().string();
    const std::string text = ReadInputFile(shown, "include file", where);
    const std::string key = fs::weakly_canonical(path).string();
    for (const std::string& open : include_stack_) {
      if (open == key) {
        std::string chain;
        for (const std::string& s : include_stack_)
          chain += fs::path(s).filename().string() + " -> ";
        throw InputError(where, "include cycle: " + chain + fs::path(key).filename().string());
      }
    }
    if (!included_.insert(key).second) {
      throw InputError(where, "file '" + shown + "' is included more than once");
    }
    tinyxml2::XMLDocument xml;
    const tinyxml2::XMLElement* top = Parse(xml, text, shown);
    if (!top->FirstChildElement()) {
      throw InputError({shown, top->GetLineNum()},
                       "the included file's root element is empty: nothing to insert");
    }
    include_stack_.push_back(key);
    ConvertChildren(*top, parent, shown);
    include_stack_.pop_back();
  }

  void AssignFileBases(Document& doc) {
    auto bases = std::make_shared<FileBases>();
    bases->model_dir = model_dir_;
    std::string meshdir, texturedir, assetdir;
    for (const auto& c : doc.root().children()) {
      if (c->tag() != "compiler") continue;
      if (const std::string* v = c->Get("meshdir")) meshdir = *v;
      if (const std::string* v = c->Get("texturedir")) texturedir = *v;
      if (const std::string* v = c->Get("assetdir")) assetdir = *v;  // MuJoCo 3.x
      if (const std::string* v = c->Get("strippath")) bases->strip_path = *v == "true";
    }
    auto join = [&](const std::string& dir) {
      if (dir.empty()) return model_dir_;
      fs::path p(dir);
      return (p.is_absolute() ? p : fs::path(model_dir_) / p).lexically_normal().string();
    };
    // 3.x's assetdir stands for both folders where they are not set themselves.
    bases->mesh_dir = join(meshdir.empty() ? assetdir : meshdir);
    bases->texture_dir = join(texturedir.empty() ? assetdir : texturedir);
    std::shared_ptr<const FileBases> shared = bases;
    doc.root().Visit([&](Element& e) { e.set_file_bases(shared); });
  }

  const ReadOptions& options_;
  std::string main_path_;
  std::string model_dir_;
  Document* doc_ = nullptr;
  std::vector<std::string> include_stack_;
  std::unordered_set<std::string> included_;
};

// Names defined per namespace.
using NameTable =
    std::array<std::unordered_set<std::string>, static_cast<size_t>(Namespace::kCount)>;

NameTable CollectNames(const Document& doc, std::vector<std::string>* composite_prefixes) {
  NameTable names;
  names[static_cast<size_t>(Namespace::kBody)].insert("world");
  names[static_cast<size_t>(Namespace::kClass)].insert("main");
  doc.root().Visit([&](const Element& e) {
    if (e.tag() == "composite") composite_prefixes->push_back(e.GetOr("prefix", ""));
    if (!e.spec() || e.spec()->name_space == Namespace::kNone) return;
    const std::string n = document::DefinedName(e);
    if (!n.empty()) names[static_cast<size_t>(e.spec()->name_space)].insert(n);
  });
  return names;
}

}  // namespace

void FindDanglingReferences(const Document& doc, Diagnostics& sink, const std::string& label) {
  std::vector<std::string> composite_prefixes;
  const NameTable names = CollectNames(doc, &composite_prefixes);
  doc.root().Visit([&](const Element& e) {
    if (!e.spec()) return;
    for (const document::Attribute& a : e.attributes()) {
      const Namespace ns = document::ReferencedNamespace(e, a);
      if (ns == Namespace::kNone || a.value.empty()) continue;
      if (names[static_cast<size_t>(ns)].count(a.value)) continue;
      // <composite> generates bodies, joints, geoms, sites, tendons and skins named after its
      // prefix; names that may come from one cannot be checked without running the generator.
      bool maybe_generated = false;
      for (const std::string& p : composite_prefixes) {
        maybe_generated = maybe_generated || a.value.compare(0, p.size(), p) == 0;
      }
      if (maybe_generated) continue;
      sink.Error(e.location(), label + "<" + e.tag() + "> attribute " + a.name + "=\"" + a.value +
                                   "\": dangling reference, no " +
                                   std::string(document::NamespaceName(ns)) + " named '" + a.value +
                                   "' in this model");
    }
  });
}

void FindDuplicateNames(const Document& doc, Diagnostics& sink, const std::string& label) {
  std::array<std::unordered_map<std::string, const Element*>,
             static_cast<size_t>(Namespace::kCount)>
      seen;
  doc.root().Visit([&](const Element& e) {
    if (!e.spec() || e.spec()->name_space == Namespace::kNone) return;
    const std::string n = e.Name();
    if (n.empty()) return;
    auto [it, fresh] = seen[static_cast<size_t>(e.spec()->name_space)].emplace(n, &e);
    if (!fresh) {
      sink.Error(e.location(),
                 label + "duplicate " + std::string(document::NamespaceName(e.spec()->name_space)) +
                     " name '" + n + "' (first defined at " + it->second->location().str() + ")");
    }
  });
}

void FindMissingFiles(const Document& doc, Diagnostics& sink, const std::string& label) {
  doc.root().Visit([&](const Element& e) {
    for (const document::Attribute& a : e.attributes()) {
      if (!a.spec || a.spec->type != document::ValueType::kFile) continue;
      const std::optional<std::string> path = e.ResolvedFile(a.name);
      std::error_code ec;
      if (!path || fs::is_regular_file(*path, ec)) continue;
      if (!fs::exists(*path, ec)) {
        sink.Error(e.location(), label + "<" + e.tag() + "> " + a.name + " '" + a.value +
                                     "' not found (looked for " + *path + ")");
        continue;
      }
      // It exists but is a folder, a device, a FIFO...: say what it is (CheckInputFile's words).
      try {
        CheckInputFile(*path, "<" + e.tag() + "> " + a.name, e.location(),
                       std::numeric_limits<std::uintmax_t>::max());
      } catch (const InputError& problem) {
        sink.Error(e.location(), label + problem.message());
      }
    }
  });
}

std::vector<std::string> InputFiles(const Document& doc) {
  std::set<std::string> files;
  if (!doc.source_path().empty()) files.insert(doc.source_path());
  doc.root().Visit([&](const Element& e) {
    if (!e.location().file.empty()) files.insert(e.location().file);  // main file and includes
    for (const document::Attribute& a : e.attributes()) {
      if (!a.spec || a.spec->type != document::ValueType::kFile) continue;
      if (std::optional<std::string> path = e.ResolvedFile(a.name)) files.insert(*path);
    }
  });
  return {files.begin(), files.end()};
}

Document ReadFile(const std::string& path, const ReadOptions& options) {
  const std::string text = ReadInputFile(path, "model file");
  Reader reader(options, path);
  return reader.Read(text);
}

Document ReadString(const std::string& xml, const std::string& virtual_path,
                    const ReadOptions& options) {
  Reader reader(options, virtual_path);
  return reader.Read(xml);
}

}  // namespace urlab::mjcf
