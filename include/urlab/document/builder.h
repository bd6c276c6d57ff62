#pragma once
// Building an articulation from scratch in C++ (the description's "user-built" path): bodies,
// geoms, joints, sites, actuators, sensors and default classes, producing the same document an
// import would. Names are made unique within their namespace by appending _1, _2, ...
//
// Thread: plain value, one owning thread.
#include <initializer_list>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "urlab/document/document.h"

namespace urlab::document {

class ArticulationBuilder {
 public:
  // Starts an empty model named `model_name` (radian angles, so numbers mean what they say).
  explicit ArticulationBuilder(std::string model_name);

  // A default class under `parent` ("main" is the top class, created on demand). Its element
  // templates are added with Template().
  Element& DefaultClass(const std::string& name, const std::string& parent = "main");
  // A template for elements of `tag` (geom, joint, motor, ...) in default class `cls`.
  Element& Template(const std::string& cls, const std::string& tag);

  // A body under `parent` (nullptr: the world body) at `pos`.
  Element& Body(Element* parent, const std::string& name, std::initializer_list<double> pos = {});
  // A geom of `type` with `size` in `body` (nullptr: world).
  Element& Geom(Element* body, const std::string& type, std::initializer_list<double> size,
                const std::string& name = "");
  // A joint of `type` (hinge, slide, ball, free) in `body` about `axis`.
  Element& Joint(Element& body, const std::string& name, const std::string& type = "hinge",
                 std::initializer_list<double> axis = {});
  Element& Site(Element& body, const std::string& name, std::initializer_list<double> pos = {});
  // An actuator of kind `tag` (motor, position, velocity, general, ...) on a joint.
  Element& Actuator(const std::string& tag, const std::string& name, const std::string& joint);
  // A sensor of kind `tag` with its object attribute (e.g. "jointpos", "joint", "hip").
  Element& Sensor(const std::string& tag, const std::string& name, const std::string& object_attr,
                  const std::string& object_name);
  // A named keyframe with qpos (and optional ctrl).
  Element& Keyframe(const std::string& name, std::initializer_list<double> qpos,
                    std::initializer_list<double> ctrl = {});

  // `base` if unused in namespace `ns`, else base_1, base_2, ...
  std::string UniqueName(Namespace ns, const std::string& base);

  Document& document() { return doc_; }
  // Hands the finished document over (the builder is empty afterwards).
  Document Build();

 private:
  Element& Named(Element& e, Namespace ns, const std::string& name);

  Document doc_;
  std::unordered_map<int, std::unordered_set<std::string>> used_;
};

}  // namespace urlab::document
