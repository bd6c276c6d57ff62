// The dialect bridge's equality passes: connect/weld on sites, short polycoef lists.

#include "mjcf/bridge_pass.h"
#include "urlab/document/orientation.h"

namespace urlab::mjcf::bridge {

namespace {

using document::Element;
using document::FormatReals;
using document::ParseReals;

class ConstraintsPasses : public Pass {
 public:
  using Pass::Pass;

  // ---- equality constraints on sites ----
  // 3.x connect/weld with site1/site2 hold the two sites together (position; weld also the
  // orientation). 2.2.2 knows only bodies, and derives the second anchor (and the weld's relative
  // pose) from qpos0; the body constraint is written here and its data set from the compiled
  // sites after compilation (ApplySiteEqualities), which is exact wherever the sites start.
  // Every weld, on bodies too, differs from 3.x's in two ways 2.2.2 offers no hook for
  // (reference3x_test SiteWeldDiffersOnlyByTwoWeldChangesOfMujoco3 pins both).
  static constexpr const char* kWeldSince3 =
      "MuJoCo 3.x changed the weld after 2.2.2: 2.2.2's efc_diagApprox gives all six rows the "
      "bodies' translational inverse weight (3.0.0: the rotational rows get the rotational "
      "one), so the orientation part is regularised, hence softened, differently; and with "
      "torquescale != 1 2.2.2 scales the rotational Jacobian but not the angular residual "
      "(3.0.1 scales both). Same constraint (same pose held), different stiffness under load "
      "and transient";
  void SiteEqualities() {
    int unnamed = 0;
    for (Element* e : Find({"connect", "weld"})) {
      if (!e->parent() || e->parent()->tag() != "equality") continue;
      const std::string* a = e->Get("site1");
      const std::string* b = e->Get("site2");
      if (!a && !b && e->tag() == "weld") {
        Note("equality.weld", *e, Tag(*e) + " kept as it is: " + kWeldSince3);
      }
      if (!a && !b) continue;
      if (!a || !b) {
        Note("equality.site.refused", *e,
             Tag(*e) +
                 " needs both site1 and site2 (MuJoCo 3.x too); nearest 2.2.2 construct: "
                 "body1/body2 with anchor");
        UnsetDialect(*e, "site1");
        UnsetDialect(*e, "site2");
        continue;
      }
      const std::string s1 = *a, s2 = *b;
      const std::string b1 = SiteBody(s1), b2 = SiteBody(s2);
      if (b1.empty() || b2.empty()) continue;  // dangling site: reported by the reader
      std::string name = e->Name();
      if (name.empty()) {
        name = "site_equality" + std::to_string(unnamed++);
        e->Set("name", name);
      }
      UnsetDialect(*e, "site1");
      UnsetDialect(*e, "site2");
      std::string ignored;
      for (const char* n : {"anchor", "relpose"}) {
        if (e->Unset(n)) ignored += std::string(ignored.empty() ? "; " : ", ") + n;
      }
      if (!ignored.empty()) ignored += " ignored with sites, as in MuJoCo 3.x";
      e->Set("body1", b1);
      e->Set("body2", b2);
      if (e->tag() == "connect") e->Set("anchor", "0 0 0");  // replaced after compilation
      report_.site_equalities.push_back({name, s1, s2});
      Note(e->tag() == "weld" ? "equality.site.weld" : "equality.site", *e,
           Tag(*e) + " site1='" + s1 + "' site2='" + s2 + "' -> body1='" + b1 + "' body2='" + b2 +
               "'; anchors" + (e->tag() == "weld" ? " and relative orientation" : "") +
               " set from the sites' frames after compilation" +
               (e->tag() == "weld" ? std::string("; ") + kWeldSince3 : std::string()) + ignored);
    }
  }

  // The name of the body holding site `site` ("world" for the world body); names an unnamed one.
  std::string SiteBody(const std::string& site) {
    Element* s = FindNamed(document::Namespace::kSite, site);
    if (!s) return "";
    Element* b = s->parent();
    while (b && b->tag() != "body" && b->tag() != "worldbody") b = b->parent();
    if (!b) return "";
    if (b->tag() == "worldbody") return "world";
    if (b->Name().empty()) b->Set("name", "body_of_" + site);
    return b->Name();
  }

  // ---- equality polycoef with fewer than 5 numbers ----
  void PolyCoef() {
    for (Element* e : Find({"joint", "tendon"})) {
      if (!e->parent() || e->parent()->tag() != "equality") continue;
      const std::string* v = e->Get("polycoef");
      if (!v) continue;
      std::vector<double> c = ParseReals(*v).value_or(std::vector<double>{});
      if (c.size() >= 5 || c.empty()) continue;
      const double defaults[5] = {0, 1, 0, 0, 0};
      const std::string before = *v;
      for (size_t i = c.size(); i < 5; ++i) c.push_back(defaults[i]);
      e->SetReals("polycoef", c);
      Note("equality.polycoef", *e,
           Tag(*e) + " polycoef=\"" + before + "\" -> \"" + FormatReals(c) +
               "\" (3.x fills the missing coefficients with the defaults 0 1 0 0 0)");
    }
  }
};

}  // namespace

void SiteEqualities(State& s) { ConstraintsPasses(s).SiteEqualities(); }
void PolyCoef(State& s) { ConstraintsPasses(s).PolyCoef(); }

}  // namespace urlab::mjcf::bridge
