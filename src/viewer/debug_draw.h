#pragma once
// Debug drawing (the description's Debug Visualization): what each layer draws, its toggles
// (global and per articulation), and the functions that add the drawing to MuJoCo's abstract
// scene as decoration geoms after mjv_updateScene: contact points with force arrows, collision
// geometry as wireframe (geoms in group 3, or with contype and conaffinity both non-zero; meshes
// as the edges of their convex hull from mjModel's mesh graph), joint axes with range arcs, and
// sites. Geometry comes from the viewer's own mjData; contacts from the DebugCapture.
//
// Threading contract: main thread only.
#include <mujoco/mujoco.h>

#include <array>
#include <string>
#include <vector>

#include "viewer/debug_capture.h"

namespace urlab::viewer::internal {

// The toggleable layers, in the order of their hotkeys 1-5 (then sites).
enum class DebugLayer {
  kContacts,       // 1: contact points and force arrows
  kVisual,         // 2: visual geometry (on by default)
  kCollision,      // 3: articulation collision wireframes
  kJoints,         // 4: joint axes and range arcs
  kPropCollision,  // 5: converted props' collision wireframes
  kSites,          // sites (panel only)
};
inline constexpr int kNumDebugLayers = 6;
// "contact forces", "visual meshes", ...
const char* DebugLayerName(DebugLayer layer);

// Which layers are on: a layer is drawn for an articulation when its global toggle or the
// articulation's own is on; kVisual is the exception, drawn unless either turns it off.
struct DebugSettings {
  using Layers = std::array<bool, kNumDebugLayers>;
  Layers global{false, true, false, false, false, false};
  std::vector<Layers> articulation;  // one per articulation of the session

  bool& Global(DebugLayer l) { return global[static_cast<std::size_t>(l)]; }
  bool Global(DebugLayer l) const { return global[static_cast<std::size_t>(l)]; }
  // Whether layer `l` is drawn for articulation `art` (-1: none, e.g. the world's floor).
  bool On(DebugLayer l, int art) const;
};

// What the drawing needs to know about the model, resolved once.
struct DebugTables {
  std::vector<int> body_articulation;  // per body: owning articulation index, -1 for none
  std::vector<bool> prop_geom;         // per geom: belongs to a converted prop
};

// True for a collision geom: group 3, or contype and conaffinity both non-zero.
bool IsCollisionGeom(const mjModel* m, int geom);

// Removes visual geoms of hidden articulations from the scene (kVisual off).
void HideVisualGeoms(const mjModel* m, const DebugSettings& settings, const DebugTables& tables,
                     mjvScene* scn);
// Adds every enabled layer's decoration geoms (until the scene is full). Returns how many.
int AddDebugGeoms(const mjModel* m, const mjData* d, const DebugSettings& settings,
                  const DebugTables& tables, const std::vector<CapturedContact>& contacts,
                  mjvScene* scn);

}  // namespace urlab::viewer::internal
