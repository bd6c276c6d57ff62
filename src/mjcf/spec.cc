#include "urlab/mjcf/spec.h"

#include <tinyxml2.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <set>
#include <span>
#include <sstream>
#include <vector>

#include "urlab/core/files.h"

namespace urlab::mjcf {

namespace {

constexpr int kErrorSize = 4096;

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Whitespace-separated numbers of `text`; Error unless there are exactly `n` finite ones.
std::vector<double> Numbers(const std::string& key, const std::string& text, std::size_t n) {
  std::vector<double> out;
  std::istringstream in(text);
  std::string word;
  while (in >> word) {
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(word.c_str(), &end);
    if (end == word.c_str() || *end != '\0' || errno == ERANGE || !std::isfinite(v)) {
      throw Error("option " + key + "=\"" + text + "\": '" + word + "' is not a finite number");
    }
    out.push_back(v);
  }
  if (out.size() != n) {
    throw Error("option " + key + "=\"" + text + "\": needs " + std::to_string(n) +
                " number(s), has " + std::to_string(out.size()));
  }
  return out;
}

int Integer(const std::string& key, const std::string& text) {
  const double v = Numbers(key, text, 1)[0];
  if (v != std::floor(v) || v < 0 || v > 1e9) {
    throw Error("option " + key + "=\"" + text + "\": needs a whole number from 0 to 1e9");
  }
  return static_cast<int>(v);
}

struct RealField {
  const char* name;
  std::size_t count;
  std::function<mjtNum*(mjOption&)> at;
};

const std::vector<RealField>& RealFields() {
  static const std::vector<RealField> table = {
      {"timestep", 1, [](mjOption& o) { return &o.timestep; }},
      {"impratio", 1, [](mjOption& o) { return &o.impratio; }},
      {"tolerance", 1, [](mjOption& o) { return &o.tolerance; }},
      {"ls_tolerance", 1, [](mjOption& o) { return &o.ls_tolerance; }},
      {"noslip_tolerance", 1, [](mjOption& o) { return &o.noslip_tolerance; }},
      {"ccd_tolerance", 1, [](mjOption& o) { return &o.ccd_tolerance; }},
      {"sleep_tolerance", 1, [](mjOption& o) { return &o.sleep_tolerance; }},
      {"gravity", 3, [](mjOption& o) { return o.gravity; }},
      {"wind", 3, [](mjOption& o) { return o.wind; }},
      {"magnetic", 3, [](mjOption& o) { return o.magnetic; }},
      {"density", 1, [](mjOption& o) { return &o.density; }},
      {"viscosity", 1, [](mjOption& o) { return &o.viscosity; }},
      {"o_margin", 1, [](mjOption& o) { return &o.o_margin; }},
      {"o_solref", mjNREF, [](mjOption& o) { return o.o_solref; }},
      {"o_solimp", mjNIMP, [](mjOption& o) { return o.o_solimp; }},
      {"o_friction", 5, [](mjOption& o) { return o.o_friction; }},
  };
  return table;
}

struct IntField {
  const char* name;
  std::vector<const char*> words;  // the MJCF keywords by value; empty: a number
  std::function<int*(mjOption&)> at;
};

const std::vector<IntField>& IntFields() {
  static const std::vector<IntField> table = {
      {"integrator",
       {"Euler", "RK4", "implicit", "implicitfast", "discrete"},
       [](mjOption& o) { return &o.integrator; }},
      {"cone", {"pyramidal", "elliptic"}, [](mjOption& o) { return &o.cone; }},
      {"jacobian", {"dense", "sparse", "auto"}, [](mjOption& o) { return &o.jacobian; }},
      {"solver", {"PGS", "CG", "Newton"}, [](mjOption& o) { return &o.solver; }},
      {"iterations", {}, [](mjOption& o) { return &o.iterations; }},
      {"ls_iterations", {}, [](mjOption& o) { return &o.ls_iterations; }},
      {"noslip_iterations", {}, [](mjOption& o) { return &o.noslip_iterations; }},
      {"ccd_iterations", {}, [](mjOption& o) { return &o.ccd_iterations; }},
      {"sdf_iterations", {}, [](mjOption& o) { return &o.sdf_iterations; }},
      {"sdf_initpoints", {}, [](mjOption& o) { return &o.sdf_initpoints; }},
  };
  return table;
}

std::string Format(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  // The shortest text that reads back as the same double.
  for (int precision = 1; precision <= 17; ++precision) {
    char shorter[64];
    std::snprintf(shorter, sizeof(shorter), "%.*g", precision, v);
    if (std::strtod(shorter, nullptr) == v) return shorter;
  }
  return buf;
}

}  // namespace

std::string SpecString(const mjString* s) {
  const char* c = s ? mjs_getString(s) : nullptr;
  return c ? c : "";
}

std::string ResolveAssetPath(const mjSpec* spec, const std::string& file, const mjString* dir) {
  namespace fs = std::filesystem;
  if (file.empty()) return file;
  fs::path p(file);
  if (p.is_absolute()) return p.lexically_normal().string();
  if (spec->strippath) p = p.filename();  // <compiler strippath="true">: the folder goes
  fs::path base(SpecString(spec->modelfiledir));
  const std::string d = SpecString(dir);
  if (!d.empty()) base = fs::path(d).is_absolute() ? fs::path(d) : base / d;
  return (base / p).lexically_normal().string();
}

namespace {

void Absolute(mjSpec* spec, mjString* file, const mjString* dir) {
  const std::string f = SpecString(file);
  if (f.empty()) return;
  const std::string resolved = ResolveAssetPath(spec, f, dir);
  if (resolved != f) mjs_setString(file, resolved.c_str());
}

// Attributes whose values are names or text, never numbers ("inf" may be a body's name).
bool NamesSomething(const std::string& attribute) {
  static const std::set<std::string> kText = {
      "name",     "class",        "childclass", "file",       "model",         "prefix",
      "suffix",   "content_type", "joint",      "joint1",     "joint2",        "body",
      "body1",    "body2",        "site",       "site1",      "site2",         "tendon",
      "tendon1",  "tendon2",      "geom",       "geom1",      "geom2",         "mesh",
      "material", "texture",      "hfield",     "skin",       "target",        "objname",
      "refname",  "actuator",     "cranksite",  "slidersite", "jointinparent", "sidesite",
      "plugin",   "instance",     "key",        "data",       "type",          "objtype",
      "reftype",  "meshdir",      "texturedir", "assetdir",   "subtree1",      "subtree2",
      "node",     "vertex",       "element",    "nodebody",   "bodyname",      "flex",
      "parent"};
  return kText.count(attribute) != 0;
}

// The first attribute of `xml` (read from `path`) holding a number that is not finite (NaN, an
// infinity, or one too large for a double): MuJoCo would take some of them.
void RefuseNonFiniteNumbers(const std::string& path, const std::string& xml) {
  tinyxml2::XMLDocument doc;
  if (doc.Parse(xml.c_str(), xml.size()) != tinyxml2::XML_SUCCESS) return;  // MuJoCo says why
  std::vector<const tinyxml2::XMLElement*> stack;
  if (doc.RootElement()) stack.push_back(doc.RootElement());
  while (!stack.empty()) {
    const tinyxml2::XMLElement* e = stack.back();
    stack.pop_back();
    for (const tinyxml2::XMLAttribute* a = e->FirstAttribute(); a; a = a->Next()) {
      if (NamesSomething(a->Name())) continue;
      std::istringstream words(a->Value());
      std::string word;
      while (words >> word) {
        char* end = nullptr;
        const double v = std::strtod(word.c_str(), &end);
        if (end == word.c_str() || *end != '\0' || std::isfinite(v)) continue;
        throw InputError({path, e->GetLineNum()}, std::string("<") + e->Name() + "> " + a->Name() +
                                                      "=\"" + a->Value() + "\": '" + word +
                                                      "' is not a finite number");
      }
    }
    for (auto* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) stack.push_back(c);
  }
}

}  // namespace

void RefuseAssetsThatAreNotFiles(mjSpec* spec, const std::string& path) {
  namespace fs = std::filesystem;
  for (mjtObj type : {mjOBJ_MESH, mjOBJ_HFIELD, mjOBJ_SKIN, mjOBJ_TEXTURE}) {
    for (mjsElement* e = mjs_firstElement(spec, type); e; e = mjs_nextElement(spec, e)) {
      const std::string f = SpecString(type == mjOBJ_MESH     ? mjs_asMesh(e)->file
                                       : type == mjOBJ_HFIELD ? mjs_asHField(e)->file
                                       : type == mjOBJ_SKIN   ? mjs_asSkin(e)->file
                                                              : mjs_asTexture(e)->file);
      std::error_code ec;
      if (f.empty() || !fs::exists(f, ec) || fs::is_regular_file(f, ec)) continue;
      const char* what = fs::is_directory(f, ec) ? "is a folder" : "is a device or FIFO";
      const char* tag = type == mjOBJ_MESH     ? "mesh"
                        : type == mjOBJ_HFIELD ? "hfield"
                        : type == mjOBJ_SKIN   ? "skin"
                                               : "texture";
      throw InputError(
          {path, LineContaining(path, fs::path(f).filename().string() + "\"")},
          std::string("<") + tag + "> file '" + f + "' " + what + ", not a file MuJoCo can read");
    }
  }
}

void AbsoluteAssetPaths(mjSpec* spec) {
  const mjString* meshdir = spec->compiler.meshdir;
  const mjString* texturedir = spec->compiler.texturedir;
  for (mjsElement* e = mjs_firstElement(spec, mjOBJ_MESH); e; e = mjs_nextElement(spec, e)) {
    Absolute(spec, mjs_asMesh(e)->file, meshdir);
  }
  for (mjsElement* e = mjs_firstElement(spec, mjOBJ_HFIELD); e; e = mjs_nextElement(spec, e)) {
    Absolute(spec, mjs_asHField(e)->file, meshdir);
  }
  for (mjsElement* e = mjs_firstElement(spec, mjOBJ_SKIN); e; e = mjs_nextElement(spec, e)) {
    Absolute(spec, mjs_asSkin(e)->file, meshdir);
  }
  for (mjsElement* e = mjs_firstElement(spec, mjOBJ_TEXTURE); e; e = mjs_nextElement(spec, e)) {
    Absolute(spec, mjs_asTexture(e)->file, texturedir);
  }
}

namespace {

// The six separate files of a cube texture, as MuJoCo's parser orders them in
// mjsTexture::cubefiles.
constexpr const char* kCubeAttributes[6] = {"fileright", "fileleft",  "fileup",
                                            "filedown",  "filefront", "fileback"};

struct XmlTexture {
  std::string name;
  std::array<std::string, 6> cube;  // "" where not given
};

// Every <texture> of the MJCF file `path`, in the order MuJoCo's parser makes them (document
// order, each <include> in its place, its file relative to the main file's folder).
void CollectTextures(const std::string& main_folder, const std::string& file, int depth,
                     std::vector<XmlTexture>* out) {
  namespace fs = std::filesystem;
  if (depth > 32) return;  // MuJoCo refuses an include cycle before we get here
  tinyxml2::XMLDocument doc;
  const std::string text = ReadInputFile(file, "model file");
  if (doc.Parse(text.c_str(), text.size()) != tinyxml2::XML_SUCCESS) return;
  const auto walk = [&](const auto& self, const tinyxml2::XMLElement* e) -> void {
    const std::string tag = e->Name();
    if (tag == "include" && e->Attribute("file")) {
      CollectTextures(main_folder,
                      (fs::path(main_folder) / e->Attribute("file")).lexically_normal().string(),
                      depth + 1, out);
      return;
    }
    if (tag == "texture") {
      XmlTexture t;
      if (const char* n = e->Attribute("name")) t.name = n;
      for (int i = 0; i < 6; ++i) {
        if (const char* v = e->Attribute(kCubeAttributes[i]))
          t.cube[static_cast<std::size_t>(i)] = v;
      }
      out->push_back(std::move(t));
    }
    for (auto* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) self(self, c);
  };
  if (doc.RootElement()) walk(walk, doc.RootElement());
}

}  // namespace

void AbsoluteCubeFiles(mjSpec* spec, const std::string& path) {
  namespace fs = std::filesystem;
  // MuJoCo's C API sets the entries of a string vector (mjs_setInStringVec) but offers no way to
  // read one before the spec is compiled, so the six names come from the file MuJoCo parsed.
  std::vector<XmlTexture> xml;
  const std::string main = fs::absolute(path).lexically_normal().string();
  CollectTextures(fs::path(main).parent_path().string(), main, 0, &xml);
  std::vector<mjsTexture*> textures;
  for (mjsElement* e = mjs_firstElement(spec, mjOBJ_TEXTURE); e; e = mjs_nextElement(spec, e)) {
    textures.push_back(mjs_asTexture(e));
  }
  const bool in_order = xml.size() == textures.size();
  for (std::size_t k = 0; k < textures.size(); ++k) {
    mjsTexture* t = textures[k];
    const std::string name = SpecString(mjs_getName(t->element));
    const XmlTexture* source = nullptr;
    if (in_order && xml[k].name == name) {
      source = &xml[k];
    } else if (!name.empty()) {  // not in step with the file: a named texture is still found
      for (const XmlTexture& x : xml) {
        if (x.name == name) source = &x;
      }
    }
    if (!source) continue;
    for (int i = 0; i < 6; ++i) {
      const std::string& f = source->cube[static_cast<std::size_t>(i)];
      if (f.empty()) continue;
      const std::string resolved = ResolveAssetPath(spec, f, spec->compiler.texturedir);
      mjs_setInStringVec(t->cubefiles, i, resolved.c_str());  // always 6 entries
    }
  }
}

std::string MapAssetPaths(const std::string& xml,
                          const std::function<std::string(const std::string&)>& rename) {
  tinyxml2::XMLDocument doc;
  if (doc.Parse(xml.c_str(), xml.size()) != tinyxml2::XML_SUCCESS) {
    throw Error(std::string("MJCF text MuJoCo wrote does not parse: ") + doc.ErrorStr());
  }
  std::vector<tinyxml2::XMLElement*> stack;
  if (doc.RootElement()) stack.push_back(doc.RootElement());
  while (!stack.empty()) {
    tinyxml2::XMLElement* e = stack.back();
    stack.pop_back();
    for (const char* attr :
         {"file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback"}) {
      const char* v = e->Attribute(attr);
      if (!v || !*v) continue;
      e->SetAttribute(attr, rename(v).c_str());
    }
    for (auto* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) stack.push_back(c);
  }
  tinyxml2::XMLPrinter printer;
  doc.Print(&printer);
  return printer.CStr();
}

std::string RelativeAssetPaths(const std::string& xml, const std::string& folder) {
  namespace fs = std::filesystem;
  const fs::path base = fs::absolute(folder).lexically_normal();
  return MapAssetPaths(xml, [&](const std::string& v) {
    return fs::path(v).is_absolute() ? fs::path(v).lexically_relative(base).string() : v;
  });
}

std::vector<std::string> ModelInputFiles(const std::string& path) {
  namespace fs = std::filesystem;
  std::set<std::string> files;
  const std::string main = fs::absolute(path).lexically_normal().string();
  files.insert(main);
  // Includes, as MuJoCo resolves them (from the main file's folder), read without MuJoCo.
  std::vector<std::string> todo = {main};
  while (!todo.empty()) {
    const std::string file = todo.back();
    todo.pop_back();
    tinyxml2::XMLDocument doc;
    try {
      const std::string text = ReadInputFile(file, "model file");
      if (doc.Parse(text.c_str(), text.size()) != tinyxml2::XML_SUCCESS) continue;
    } catch (const Error&) {
      continue;
    }
    std::vector<const tinyxml2::XMLElement*> stack;
    if (doc.RootElement()) stack.push_back(doc.RootElement());
    while (!stack.empty()) {
      const tinyxml2::XMLElement* e = stack.back();
      stack.pop_back();
      if (std::string(e->Name()) == "include" && e->Attribute("file")) {
        const std::string inc =
            (fs::path(main).parent_path() / e->Attribute("file")).lexically_normal().string();
        if (files.insert(inc).second) todo.push_back(inc);
      }
      for (auto* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) stack.push_back(c);
    }
  }
  try {
    SpecPtr spec = ParseFile(path);
    for (mjtObj type : {mjOBJ_MESH, mjOBJ_HFIELD, mjOBJ_SKIN, mjOBJ_TEXTURE}) {
      for (mjsElement* e = mjs_firstElement(spec.get(), type); e;
           e = mjs_nextElement(spec.get(), e)) {
        const mjString* f = type == mjOBJ_MESH     ? mjs_asMesh(e)->file
                            : type == mjOBJ_HFIELD ? mjs_asHField(e)->file
                            : type == mjOBJ_SKIN   ? mjs_asSkin(e)->file
                                                   : mjs_asTexture(e)->file;
        if (!SpecString(f).empty()) files.insert(SpecString(f));
      }
    }
    std::vector<XmlTexture> textures;  // a cube texture's six files
    CollectTextures(fs::path(main).parent_path().string(), main, 0, &textures);
    for (const XmlTexture& t : textures) {
      for (const std::string& f : t.cube) {
        if (!f.empty()) files.insert(ResolveAssetPath(spec.get(), f, spec->compiler.texturedir));
      }
    }
  } catch (const Error&) {
  }
  return {files.begin(), files.end()};
}

int LineContaining(const std::string& path, const std::string& text) {
  std::string content;
  try {
    content = ReadInputFile(path, "model file");
  } catch (const Error&) {
    return 0;
  }
  const std::size_t at = content.find(text);
  if (at == std::string::npos) return 0;
  return 1 + static_cast<int>(std::count(content.begin(),
                                         content.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
}

int LineOfMujocoMessage(const std::string& message) {
  const std::size_t at = message.rfind("line ");
  if (at == std::string::npos) return 0;
  return std::atoi(message.c_str() + at + 5);
}

std::string TidyMujocoMessage(const std::string& message) {
  std::string m = message;
  for (const char* prefix : {"XML Error: ", "Error: "}) {
    if (m.rfind(prefix, 0) == 0) m = m.substr(std::string(prefix).size());
  }
  while (!m.empty() && (m.back() == '\n' || m.back() == ' ')) m.pop_back();
  std::string out;
  for (char c : m) out += c == '\n' ? ' ' : c;
  // "message  Element 'joint', line 5" reads as one line.
  std::string::size_type twice;
  while ((twice = out.find("  ")) != std::string::npos) out.erase(twice, 1);
  return out;
}

SpecPtr ParseFile(const std::string& path) {
  RefuseNonFiniteNumbers(path, ReadInputFile(path, "model file"));
  char error[kErrorSize] = "";
  SpecPtr spec(mj_parseXML(path.c_str(), nullptr, error, kErrorSize));
  if (!spec) {
    const std::string message = error[0] ? error : "MuJoCo could not parse the model";
    throw InputError({path, LineOfMujocoMessage(message)}, TidyMujocoMessage(message));
  }
  AbsoluteAssetPaths(spec.get());
  AbsoluteCubeFiles(spec.get(), path);
  RefuseAssetsThatAreNotFiles(spec.get(), path);
  return spec;
}

SpecPtr ParseString(const std::string& xml, const SourceLocation& label) {
  char error[kErrorSize] = "";
  SpecPtr spec(mj_parseXMLString(xml.c_str(), nullptr, error, kErrorSize));
  if (!spec) {
    throw InputError(label, TidyMujocoMessage(error[0] ? error : "MuJoCo could not parse it"));
  }
  return spec;
}

std::string SaveXml(const mjSpec* spec) {
  char error[kErrorSize] = "";
  std::string xml(1 << 16, '\0');
  for (;;) {
    const int rc =
        mj_saveXMLString(spec, xml.data(), static_cast<int>(xml.size()), error, kErrorSize);
    if (rc == 0) break;
    if (rc < 0) throw Error(std::string("MuJoCo could not write the model: ") + error);
    xml.assign(static_cast<std::size_t>(rc) + 1, '\0');  // the size it needs
  }
  xml.resize(std::char_traits<char>::length(xml.c_str()));
  return xml;
}

void SetOption(mjOption* option, const std::string& key, const std::string& value) {
  if (key.rfind("flag.", 0) == 0) {
    const std::string flag = key.substr(5);
    const std::string v = Lower(value);
    if (v != "enable" && v != "disable") {
      throw Error("option " + key + "=\"" + value + "\": needs enable or disable");
    }
    for (int i = 0; i < mjNDISABLE; ++i) {
      if (Lower(mjDISABLESTRING[i]) != flag) continue;
      if (v == "disable") option->disableflags |= 1 << i;
      if (v == "enable") option->disableflags &= ~(1 << i);
      return;
    }
    for (int i = 0; i < mjNENABLE; ++i) {
      if (Lower(mjENABLESTRING[i]) != flag) continue;
      if (v == "enable") option->enableflags |= 1 << i;
      if (v == "disable") option->enableflags &= ~(1 << i);
      return;
    }
    throw Error("option flag '" + flag + "' is not one of MuJoCo " +
                std::string(mj_versionString()) + "'s flags");
  }
  for (const RealField& f : RealFields()) {
    if (key != f.name) continue;
    const std::vector<double> v = Numbers(key, value, f.count);
    std::copy(v.begin(), v.end(), f.at(*option));
    return;
  }
  for (const IntField& f : IntFields()) {
    if (key != f.name) continue;
    if (f.words.empty()) {
      *f.at(*option) = Integer(key, value);
      return;
    }
    for (std::size_t i = 0; i < f.words.size(); ++i) {
      if (Lower(f.words[i]) == Lower(value)) {
        *f.at(*option) = static_cast<int>(i);
        return;
      }
    }
    std::string words;
    for (const char* w : f.words) words += std::string(words.empty() ? "" : ", ") + w;
    throw Error("option " + key + "=\"" + value + "\": needs one of " + words);
  }
  throw Error("'" + key + "' is not an option attribute of MuJoCo " +
              std::string(mj_versionString()));
}

std::map<std::string, std::string> OptionText(const mjOption& option) {
  std::map<std::string, std::string> out;
  mjOption o = option;
  for (const RealField& f : RealFields()) {
    const std::span<const mjtNum> v(f.at(o), f.count);
    std::string text;
    for (mjtNum x : v) text += (text.empty() ? "" : " ") + Format(x);
    out[f.name] = text;
  }
  for (const IntField& f : IntFields()) {
    const int v = *f.at(o);
    out[f.name] = f.words.empty() || v < 0 || v >= static_cast<int>(f.words.size())
                      ? std::to_string(v)
                      : f.words[static_cast<std::size_t>(v)];
  }
  for (int i = 0; i < mjNDISABLE; ++i) {
    out["flag." + Lower(mjDISABLESTRING[i])] =
        (option.disableflags & (1 << i)) ? "disable" : "enable";
  }
  for (int i = 0; i < mjNENABLE; ++i) {
    out["flag." + Lower(mjENABLESTRING[i])] =
        (option.enableflags & (1 << i)) ? "enable" : "disable";
  }
  return out;
}

}  // namespace urlab::mjcf
