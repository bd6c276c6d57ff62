// The dialect bridge's asset and render passes: discardvisual, render-only elements, mesh
// inertia.

#include "mjcf/bridge_pass.h"
#include "urlab/document/orientation.h"

namespace urlab::mjcf::bridge {

namespace {

using document::Element;

class AssetsPasses : public Pass {
 public:
  using Pass::Pass;

  void KeepVisualGeoms() {
    for (const auto& c : doc_.root().children()) {
      if (c->tag() != "compiler" || c->GetOr("discardvisual", "") != "true") continue;
      c->Set("discardvisual", "false");
      Note("compiler.discardvisual", *c,
           "compiler discardvisual=\"true\" -> \"false\": MuJoCo 3.x weighs bodies with their "
           "visual geoms before discarding them (and keeps those contact pairs use), 2.2.2 "
           "discards them first; keeping them gives 3.x's masses and contacts, with more geoms "
           "in the model (visual geoms do not collide)");
    }
  }

  // ---- render-only elements of 3.x ----
  void VisualOnly() {
    for (Element* l : Find({"layer"})) {
      if (!l->parent() || l->parent()->tag() != "material") continue;
      Note("material.layer", *l,
           "<material><layer> (physically based texture layer) dropped: render-only");
      l->parent()->RemoveChild(l);
    }
  }

  // ---- mesh inertia ----
  // MuJoCo 3.x (since 3.0.1) takes a mesh's mass from its volume; 2.2.2's default
  // (exactmeshinertia false) from the volume of the mesh's equivalent inertia box, which differs
  // even for a convex mesh (a wedge weighs 2/sqrt(3) of its mass). 3.x's per-mesh modes: legacy
  // (the default; tetrahedra from the mesh centre: exact for convex meshes, overcounts others),
  // convex (the hull), exact, shell. 2.2.2's exactmeshinertia="true" is the exact volume: equal
  // to all of them for convex meshes, and to "exact" always.
  void MeshInertia() {
    std::vector<Element*> meshes = Find({"mesh"});
    int maybe_nonconvex = 0;  // legacy/convex meshes read from files (inline vertices: a hull)
    for (Element* m : meshes) {
      const std::string* v = Resolve(*m, "inertia");
      const std::string mode = v ? *v : "legacy";
      if (mode == "shell") {
        Note("mesh.shell", *m,
             Tag(*m) +
                 " inertia=\"shell\": set shellinertia on the geoms that use this mesh "
                 "instead (the bridge does not know which bodies infer inertia)");
      } else if (mode != "exact" && m->Has("file")) {
        ++maybe_nonconvex;
      }
      if (m->Get("inertia")) {
        Note("mesh.inertia", *m,
             Tag(*m) + " inertia=\"" + mode + "\": see the compiler's exactmeshinertia entry");
        m->Unset("inertia");
      }
    }
    for (Element* d : FindDefaults({"mesh"})) {
      if (d->Unset("inertia")) {
        Note("mesh.inertia", *d, "default " + Tag(*d) + " inertia resolved into each mesh");
      }
    }
    if (meshes.empty()) return;
    std::string before;
    bool set = false;
    for (const auto& c : doc_.root().children()) {
      if (c->tag() != "compiler" || !c->Has("exactmeshinertia")) continue;
      before = *c->Get("exactmeshinertia");
      c->Set("exactmeshinertia", "true");
      set = true;
    }
    if (!set) FirstCompiler().Set("exactmeshinertia", "true");
    if (before == "true") return;
    std::string what =
        "compiler exactmeshinertia=\"true\" written" +
        (before.empty() ? std::string() : " (was \"" + before + "\", 3.0-3.1's legacy volume)") +
        ": MuJoCo 3.x computes mesh masses from the mesh volume, 2.2.2's default from its "
        "inertia box";
    if (maybe_nonconvex == 0) {
      Note("mesh.exactmeshinertia", *doc_.root().FirstChild("compiler"), what);
    } else {
      Note("mesh.exactmeshinertia.nonconvex", *doc_.root().FirstChild("compiler"),
           what + "; exact for convex meshes, but " + std::to_string(maybe_nonconvex) +
               " mesh file(s) with inertia legacy/convex may be non-convex, where 3.x's legacy "
               "algorithm overcounts the volume (convex: takes the hull's) and 2.2.2's exact one "
               "does not");
    }
  }
};

}  // namespace

void KeepVisualGeoms(State& s) { AssetsPasses(s).KeepVisualGeoms(); }
void VisualOnly(State& s) { AssetsPasses(s).VisualOnly(); }
void MeshInertia(State& s) { AssetsPasses(s).MeshInertia(); }

}  // namespace urlab::mjcf::bridge
