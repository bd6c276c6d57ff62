// The dialect bridge's last passes: 3.x attributes no construct pass consumed, decided by the
// attribute-policy table (bridge_rules.cc), and leftovers that cannot be expressed (refused).

#include <algorithm>
#include <cmath>

#include "mjcf/bridge_pass.h"
#include "urlab/document/orientation.h"

namespace urlab::mjcf::bridge {

namespace {

using document::Attribute;
using document::Element;
using document::FormatReal;
using document::ParseReals;
using Kind = BridgeChange::Kind;

class AttributesPasses : public Pass {
 public:
  using Pass::Pass;

  // ---- remaining 3.x attributes: drop what has no effect, approximate, refuse ----
  void GenericAttributes() {
    doc_.root().Visit([&](Element& e) {
      std::vector<std::string> names;
      for (const Attribute& a : e.attributes()) {
        if (IsDialect(a)) names.push_back(a.name);
      }
      for (const std::string& n : names) GenericAttribute(e, n);
    });
  }

  // Whether an attribute policy's `elements` list covers `e`.
  static bool PolicyCovers(const AttributePolicy& p, const Element& e) {
    for (std::string_view tag : Words(p.elements)) {
      if (tag == "<sensor>" && e.parent() && e.parent()->tag() == "sensor") return true;
      if (tag == "<actuator>" && IsActuatorTag(e.tag())) return true;
      if (tag == e.tag()) return true;
    }
    return false;
  }
  static std::vector<std::string_view> Words(std::string_view s) {
    std::vector<std::string_view> out;
    while (!s.empty()) {
      const size_t b = s.find_first_not_of(" |");
      if (b == std::string_view::npos) break;
      s.remove_prefix(b);
      const size_t n = s.find_first_of(" |");
      out.push_back(s.substr(0, n));
      s.remove_prefix(n == std::string_view::npos ? s.size() : n);
    }
    return out;
  }

  // A 3.x attribute no translation function consumed: the first attribute policy (bridge_rules.cc)
  // covering it decides; the handful that compute something have their own functions.
  void GenericAttribute(Element& e, const std::string& n) {
    if (!e.Has(n)) return;  // handled together with an earlier attribute
    const std::string value = *e.Get(n);
    const std::string& t = e.tag();
    if (t == "light" && n == "type" && value == "directional") return LightType(e);
    if (t == "camera" && (n == "sensorsize" || n == "focal" || n == "focalpixel" ||
                          n == "resolution" || n == "principal" || n == "principalpixel")) {
      return CameraIntrinsics(e);
    }
    const std::string desc =
        (InDefault(e) ? "default " : "") + Tag(e) + " " + n + "=\"" + value + "\"";
    for (const AttributePolicy& p : AttributePolicies()) {
      if (!PolicyCovers(p, e)) continue;
      const std::vector<std::string_view> attrs = Words(p.attributes);
      if (std::find(attrs.begin(), attrs.end(), n) == attrs.end() &&
          std::find(attrs.begin(), attrs.end(), "*") == attrs.end()) {
        continue;
      }
      bool first = true;
      if (p.condition == AttributeCondition::kZero) {
        first = AllZero(ParseReals(value).value_or(std::vector<double>{1}));
      } else if (p.condition == AttributeCondition::kValueIn) {
        const std::vector<std::string_view> values = Words(p.values);
        first = std::find(values.begin(), values.end(), value) != values.end();
      }
      const char* rule = first ? p.rule_if : p.rule_else;
      const char* why = first ? p.why_if : p.why_else;
      const bool refused = FindBridgeRule(rule).kind == Kind::kRefused;
      Note(rule, e, desc + (refused ? ": " : " dropped: ") + why);
      e.Unset(n);
      return;
    }
    // Everything else is left for Leftovers() to refuse.
  }

  void LightType(Element& e) {
    e.Set("directional", "true");
    Note("light.directional", e,
         (InDefault(e) ? "default " : "") + Tag(e) +
             " type=\"directional\" -> directional=\"true\"");
    e.Unset("type");
  }

  void CameraIntrinsics(Element& c) {
    auto reals = [&](const char* n) { return ResolveReals(c, n); };
    auto ss = reals("sensorsize");
    auto focal = reals("focal");
    auto focalpixel = reals("focalpixel");
    auto res = reals("resolution");
    std::string what = Tag(c) + " sensorsize/focal/resolution/principal";
    if (ss && ss->size() == 2 && (*ss)[1] > 0) {
      double fy = 0;
      if (focal && focal->size() == 2) fy = (*focal)[1];
      if (focalpixel && focalpixel->size() == 2 && res && res->size() == 2 && (*res)[1] > 0) {
        fy = (*focalpixel)[1] * (*ss)[1] / (*res)[1];
      }
      if (fy > 0) {
        const double fovy = 2 * std::atan((*ss)[1] / (2 * fy)) * 180 / kPi;
        c.SetReal("fovy", fovy);
        what += " -> fovy=" + FormatReal(fovy) + " (vertical field of view, as 3.x computes it)";
      }
    }
    const bool principal = c.Has("principal") || c.Has("principalpixel");
    for (const char* n :
         {"sensorsize", "focal", "focalpixel", "resolution", "principal", "principalpixel"}) {
      c.Unset(n);
    }
    Note(principal ? "camera.principal" : "camera.intrinsics", c,
         what + (principal ? "; the principal point offset is dropped (render-only)" : ""));
  }

  // ---- anything 3.x that is still there cannot be expressed ----
  void Leftovers() {
    for (Element* g : Find({"geom"})) {
      if (g->GetOr("type", "") == "sdf") {
        Note("refused.sdf", *g,
             Tag(*g) +
                 " type=\"sdf\": signed-distance-field geoms need engine plugins, which "
                 "MuJoCo 2.2.2 cannot load; nearest 2.2.2 construct: type=\"mesh\" (its "
                 "convex hull collides)");
        g->Set("type", "sphere");  // keeps the document writable for --bridge-report
      }
    }
    std::vector<Element*> elements;
    doc_.root().Visit([&](Element& e) {
      if (e.spec() && e.spec()->dialect) {
        elements.push_back(&e);
        return;
      }
      std::vector<std::string> names;
      for (const Attribute& a : e.attributes()) {
        if (IsDialect(a)) names.push_back(a.name);
      }
      for (const std::string& n : names) {
        Note("leftover", e,
             (InDefault(e) ? "default " : "") + Tag(e) + " attribute " + n + "=\"" + *e.Get(n) +
                 "\" (MuJoCo 3.x) has no MuJoCo 2.2.2 translation");
        e.Unset(n);
      }
    });
    for (Element* e : elements) {
      bool inside = false;  // a refused ancestor already covers it
      for (const Element* p = e->parent(); p; p = p->parent()) {
        inside = inside || std::find(elements.begin(), elements.end(), p) != elements.end();
      }
      if (inside) continue;
      const auto refused = RefusedElements();
      const auto r = std::find_if(refused.begin(), refused.end(),
                                  [&](const RefusedElement& x) { return e->tag() == x.tag; });
      if (r != refused.end()) {
        Note("refused.element", *e, Tag(*e) + ": " + r->why + "; " + r->nearest);
        continue;
      }
      Note("leftover", *e, Tag(*e) + " (MuJoCo 3.x) has no MuJoCo 2.2.2 translation");
    }
    for (auto it = elements.rbegin(); it != elements.rend(); ++it) {
      if ((*it)->parent()) (*it)->parent()->RemoveChild(*it);
    }
  }
};

}  // namespace

void GenericAttributes(State& s) { AttributesPasses(s).GenericAttributes(); }
void Leftovers(State& s) { AttributesPasses(s).Leftovers(); }

}  // namespace urlab::mjcf::bridge
