#include "urlab/document/builder.h"

namespace urlab::document {

namespace {
std::vector<double> Vec(std::initializer_list<double> v) { return std::vector<double>(v); }
}  // namespace

ArticulationBuilder::ArticulationBuilder(std::string model_name) : doc_(std::move(model_name)) {
  doc_.Section("compiler").Set("angle", "radian");
}

std::string ArticulationBuilder::UniqueName(Namespace ns, const std::string& base) {
  auto& used = used_[static_cast<int>(ns)];
  if (used.insert(base).second) return base;
  for (int i = 1;; ++i) {
    std::string candidate = base + "_" + std::to_string(i);
    if (used.insert(candidate).second) return candidate;
  }
}

Element& ArticulationBuilder::Named(Element& e, Namespace ns, const std::string& name) {
  if (!name.empty()) e.Set(ns == Namespace::kClass ? "class" : "name", UniqueName(ns, name));
  return e;
}

Element& ArticulationBuilder::DefaultClass(const std::string& name, const std::string& parent) {
  Element& top = doc_.Section("default");
  if (name == "main") return top;
  Element* p = parent == "main" ? &top : doc_.FindNamed(Namespace::kClass, parent);
  if (!p) throw Error("default class '" + parent + "' does not exist");
  if (Element* existing = doc_.FindNamed(Namespace::kClass, name)) return *existing;
  return Named(p->AddChild("default"), Namespace::kClass, name);
}

Element& ArticulationBuilder::Template(const std::string& cls, const std::string& tag) {
  Element& d = DefaultClass(cls);
  if (Element* t = d.FirstChild(tag)) return *t;
  return d.AddChild(tag);
}

Element& ArticulationBuilder::Body(Element* parent, const std::string& name,
                                   std::initializer_list<double> pos) {
  Element& b = (parent ? *parent : doc_.Section("worldbody")).AddChild("body");
  Named(b, Namespace::kBody, name);
  if (pos.size()) b.SetReals("pos", Vec(pos));
  return b;
}

Element& ArticulationBuilder::Geom(Element* body, const std::string& type,
                                   std::initializer_list<double> size, const std::string& name) {
  Element& g = (body ? *body : doc_.Section("worldbody")).AddChild("geom");
  Named(g, Namespace::kGeom, name);
  g.Set("type", type);
  if (size.size()) g.SetReals("size", Vec(size));
  return g;
}

Element& ArticulationBuilder::Joint(Element& body, const std::string& name, const std::string& type,
                                    std::initializer_list<double> axis) {
  Element& j = body.AddChild(type == "free" ? "freejoint" : "joint");
  Named(j, Namespace::kJoint, name);
  if (type != "free") j.Set("type", type);
  if (axis.size()) j.SetReals("axis", Vec(axis));
  return j;
}

Element& ArticulationBuilder::Site(Element& body, const std::string& name,
                                   std::initializer_list<double> pos) {
  Element& s = body.AddChild("site");
  Named(s, Namespace::kSite, name);
  if (pos.size()) s.SetReals("pos", Vec(pos));
  return s;
}

Element& ArticulationBuilder::Actuator(const std::string& tag, const std::string& name,
                                       const std::string& joint) {
  Element& a = doc_.Section("actuator").AddChild(tag);
  Named(a, Namespace::kActuator, name);
  a.Set("joint", joint);
  return a;
}

Element& ArticulationBuilder::Sensor(const std::string& tag, const std::string& name,
                                     const std::string& object_attr,
                                     const std::string& object_name) {
  Element& s = doc_.Section("sensor").AddChild(tag);
  Named(s, Namespace::kSensor, name);
  s.Set(object_attr, object_name);
  return s;
}

Element& ArticulationBuilder::Keyframe(const std::string& name, std::initializer_list<double> qpos,
                                       std::initializer_list<double> ctrl) {
  Element& k = doc_.Section("keyframe").AddChild("key");
  Named(k, Namespace::kKey, name);
  k.SetReals("qpos", Vec(qpos));
  if (ctrl.size()) k.SetReals("ctrl", Vec(ctrl));
  return k;
}

Document ArticulationBuilder::Build() {
  Document out = std::move(doc_);
  doc_ = Document();
  used_.clear();
  return out;
}

}  // namespace urlab::document
