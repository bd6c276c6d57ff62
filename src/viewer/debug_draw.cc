#include "viewer/debug_draw.h"

#include <algorithm>
#include <cmath>

namespace urlab::viewer::internal {

namespace {

constexpr int kCircleSegments = 24;
constexpr int kArcSegments = 16;

// Layer colours (RGBA).
constexpr float kContactColor[4] = {1.0f, 0.25f, 0.1f, 1};
constexpr float kCollisionColor[4] = {0.1f, 1.0f, 0.3f, 1};
constexpr float kHullColor[4] = {0.1f, 0.9f, 1.0f, 1};
constexpr float kPropColor[4] = {1.0f, 0.8f, 0.1f, 1};
constexpr float kAxisColor[4] = {1.0f, 0.1f, 1.0f, 1};
constexpr float kArcColor[4] = {1.0f, 1.0f, 0.2f, 1};
constexpr float kSiteColor[4] = {0.3f, 0.5f, 1.0f, 1};

constexpr const char* kLayerNames[kNumDebugLayers] = {"contact forces",
                                                      "visual meshes",
                                                      "collision wireframes",
                                                      "joint axes and ranges",
                                                      "prop collision wireframes",
                                                      "sites"};

// Appends decoration geoms to a scene until it is full.
class Painter {
 public:
  explicit Painter(mjvScene* scn) : scn_(scn) {}
  int added() const { return added_; }

  void Line(const mjtNum a[3], const mjtNum b[3], const float rgba[4], mjtNum width = 2) {
    mjvGeom* g = Next();
    if (!g) return;
    mjv_initGeom(g, mjGEOM_LINE, nullptr, nullptr, nullptr, rgba);
    mjv_connector(g, mjGEOM_LINE, width, a, b);
  }
  void Arrow(const mjtNum a[3], const mjtNum b[3], mjtNum width, const float rgba[4]) {
    mjvGeom* g = Next();
    if (!g) return;
    mjv_initGeom(g, mjGEOM_ARROW, nullptr, nullptr, nullptr, rgba);
    mjv_connector(g, mjGEOM_ARROW, width, a, b);
  }
  void Sphere(const mjtNum pos[3], mjtNum radius, const float rgba[4]) {
    mjvGeom* g = Next();
    if (!g) return;
    const mjtNum size[3] = {radius, radius, radius};
    mjv_initGeom(g, mjGEOM_SPHERE, size, pos, nullptr, rgba);
  }

 private:
  mjvGeom* Next() {
    if (scn_->ngeom >= scn_->maxgeom) return nullptr;
    mjvGeom* g = scn_->geoms + scn_->ngeom++;
    ++added_;
    g->category = mjCAT_DECOR;
    g->objtype = mjOBJ_UNKNOWN;
    g->objid = -1;
    return g;
  }
  mjvScene* scn_;
  int added_ = 0;
};

// World point of a local point p in a frame (pos, row-major mat).
void ToWorld(const mjtNum* pos, const mjtNum* mat, const mjtNum p[3], mjtNum out[3]) {
  mju_mulMatVec(out, mat, p, 3, 3);
  mju_addTo3(out, pos);
}

// A closed polyline through local points of one geom.
void LocalLine(Painter& p, const mjtNum* pos, const mjtNum* mat, const mjtNum a[3],
               const mjtNum b[3], const float rgba[4]) {
  mjtNum wa[3], wb[3];
  ToWorld(pos, mat, a, wa);
  ToWorld(pos, mat, b, wb);
  p.Line(wa, wb, rgba);
}

// An ellipse in the local plane spanned by axes u and v (0 x, 1 y, 2 z), centred at height h
// along axis w, from angle a0 to a1.
void LocalArc(Painter& p, const mjtNum* pos, const mjtNum* mat, int u, int v, int w, mjtNum ru,
              mjtNum rv, mjtNum h, mjtNum a0, mjtNum a1, int segments, const float rgba[4]) {
  mjtNum prev[3] = {0, 0, 0};
  for (int i = 0; i <= segments; ++i) {
    const mjtNum a = a0 + (a1 - a0) * i / segments;
    mjtNum cur[3] = {0, 0, 0};
    cur[u] = ru * std::cos(a);
    cur[v] = rv * std::sin(a);
    cur[w] = h;
    if (i > 0) LocalLine(p, pos, mat, prev, cur, rgba);
    mju_copy3(prev, cur);
  }
}

void DrawBox(Painter& p, const mjtNum* pos, const mjtNum* mat, const mjtNum* s,
             const float rgba[4]) {
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int su = -1; su <= 1; su += 2) {
      for (int sv = -1; sv <= 1; sv += 2) {
        mjtNum a[3], b[3];
        a[axis] = -s[axis];
        b[axis] = s[axis];
        a[u] = b[u] = su * s[u];
        a[v] = b[v] = sv * s[v];
        LocalLine(p, pos, mat, a, b, rgba);
      }
    }
  }
}

// Capsule (caps) or cylinder (flat ends) of radius r, half-length h along z.
void DrawTube(Painter& p, const mjtNum* pos, const mjtNum* mat, mjtNum r, mjtNum h, bool caps,
              const float rgba[4]) {
  constexpr mjtNum kTwoPi = 2 * mjPI;
  for (int end = -1; end <= 1; end += 2) {
    LocalArc(p, pos, mat, 0, 1, 2, r, r, end * h, 0, kTwoPi, kCircleSegments, rgba);
  }
  for (int k = 0; k < 4; ++k) {
    const mjtNum a = k * mjPI / 2;
    const mjtNum x = r * std::cos(a), y = r * std::sin(a);
    const mjtNum top[3] = {x, y, h}, bottom[3] = {x, y, -h};
    LocalLine(p, pos, mat, top, bottom, rgba);
  }
  if (!caps) return;
  // Half circles over each end in the xz and yz planes.
  for (int end = -1; end <= 1; end += 2) {
    for (int plane = 0; plane < 2; ++plane) {
      mjtNum prev[3] = {0, 0, 0};
      for (int i = 0; i <= kArcSegments; ++i) {
        const mjtNum a = mjPI * i / kArcSegments;
        mjtNum cur[3] = {0, 0, end * (h + r * std::sin(a))};
        cur[plane] = r * std::cos(a);
        if (i > 0) LocalLine(p, pos, mat, prev, cur, rgba);
        mju_copy3(prev, cur);
      }
    }
  }
}

// The convex hull's edges from the mesh graph (numvert, numface, vert_edgeadr, vert_globalid,
// edge_localid (-1 ends a vertex's list), face_globalid); the bounding box when there is none.
void DrawMeshHull(Painter& p, const mjModel* m, int mesh, const mjtNum* pos, const mjtNum* mat,
                  const float rgba[4]) {
  const int adr = m->mesh_graphadr[mesh];
  const float* vert = m->mesh_vert + 3 * m->mesh_vertadr[mesh];
  const auto local = [&](int id, mjtNum out[3]) {
    for (int k = 0; k < 3; ++k) out[k] = vert[3 * id + k];
  };
  if (adr < 0) {
    mjtNum lo[3] = {mjMAXVAL, mjMAXVAL, mjMAXVAL}, hi[3] = {-mjMAXVAL, -mjMAXVAL, -mjMAXVAL};
    for (int i = 0; i < m->mesh_vertnum[mesh]; ++i) {
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min<mjtNum>(lo[k], vert[3 * i + k]);
        hi[k] = std::max<mjtNum>(hi[k], vert[3 * i + k]);
      }
    }
    mjtNum centre[3], half[3], c[3];
    for (int k = 0; k < 3; ++k) {
      centre[k] = (lo[k] + hi[k]) / 2;
      half[k] = (hi[k] - lo[k]) / 2;
    }
    ToWorld(pos, mat, centre, c);
    DrawBox(p, c, mat, half, rgba);
    return;
  }
  const int* graph = m->mesh_graph + adr;
  const int numvert = graph[0];
  const int* vert_edgeadr = graph + 2;
  const int* vert_globalid = vert_edgeadr + numvert;
  const int* edge_localid = vert_globalid + numvert;
  for (int i = 0; i < numvert; ++i) {
    for (int e = vert_edgeadr[i]; edge_localid[e] >= 0; ++e) {
      const int j = edge_localid[e];
      if (j <= i) continue;  // each edge once
      mjtNum a[3], b[3];
      local(vert_globalid[i], a);
      local(vert_globalid[j], b);
      LocalLine(p, pos, mat, a, b, rgba);
    }
  }
}

void DrawWireframe(Painter& p, const mjModel* m, const mjData* d, int g, const float rgba[4]) {
  const mjtNum* pos = d->geom_xpos + 3 * g;
  const mjtNum* mat = d->geom_xmat + 9 * g;
  const mjtNum* s = m->geom_size + 3 * g;
  constexpr mjtNum kTwoPi = 2 * mjPI;
  switch (m->geom_type[g]) {
    case mjGEOM_BOX:
      DrawBox(p, pos, mat, s, rgba);
      break;
    case mjGEOM_SPHERE:
    case mjGEOM_ELLIPSOID: {
      const bool sphere = m->geom_type[g] == mjGEOM_SPHERE;
      const mjtNum r[3] = {s[0], sphere ? s[0] : s[1], sphere ? s[0] : s[2]};
      LocalArc(p, pos, mat, 0, 1, 2, r[0], r[1], 0, 0, kTwoPi, kCircleSegments, rgba);
      LocalArc(p, pos, mat, 1, 2, 0, r[1], r[2], 0, 0, kTwoPi, kCircleSegments, rgba);
      LocalArc(p, pos, mat, 2, 0, 1, r[2], r[0], 0, 0, kTwoPi, kCircleSegments, rgba);
      break;
    }
    case mjGEOM_CAPSULE:
      DrawTube(p, pos, mat, s[0], s[1], true, rgba);
      break;
    case mjGEOM_CYLINDER:
      DrawTube(p, pos, mat, s[0], s[1], false, rgba);
      break;
    case mjGEOM_PLANE: {
      // Infinite planes (size 0) are drawn 5 m around their origin, with a 1 m grid.
      const mjtNum hx = s[0] > 0 ? s[0] : 5, hy = s[1] > 0 ? s[1] : 5;
      const int lines = 10;
      for (int i = 0; i <= lines; ++i) {
        const mjtNum x = -hx + 2 * hx * i / lines, y = -hy + 2 * hy * i / lines;
        const mjtNum a[3] = {x, -hy, 0}, b[3] = {x, hy, 0};
        const mjtNum c[3] = {-hx, y, 0}, e[3] = {hx, y, 0};
        LocalLine(p, pos, mat, a, b, rgba);
        LocalLine(p, pos, mat, c, e, rgba);
      }
      break;
    }
    case mjGEOM_MESH:
      if (m->geom_dataid[g] >= 0) DrawMeshHull(p, m, m->geom_dataid[g], pos, mat, kHullColor);
      break;
    default: {  // height fields: their bounding box
      const mjtNum half[3] = {m->geom_rbound[g], m->geom_rbound[g], m->geom_rbound[g]};
      DrawBox(p, pos, mat, half, rgba);
      break;
    }
  }
}

// A joint's axis as an arrow from its anchor, and for a limited hinge its range as an arc (with
// a spoke to the current angle); for a limited slide the range as a segment along the axis.
void DrawJoint(Painter& p, const mjModel* m, const mjData* d, int j) {
  const int type = m->jnt_type[j];
  if (type == mjJNT_FREE) return;
  const mjtNum* anchor = d->xanchor + 3 * j;
  const mjtNum* axis = d->xaxis + 3 * j;
  const mjtNum len = 0.6 * m->stat.meansize;
  if (type == mjJNT_BALL) {
    p.Sphere(anchor, 0.15 * len, kAxisColor);
    return;
  }
  mjtNum tip[3];
  mju_addScl3(tip, anchor, axis, len);
  p.Arrow(anchor, tip, 0.03 * len, kAxisColor);
  if (!m->jnt_limited[j]) return;
  const mjtNum lo = m->jnt_range[2 * j], hi = m->jnt_range[2 * j + 1];
  const mjtNum q = d->qpos[m->jnt_qposadr[j]];
  if (type == mjJNT_SLIDE) {
    mjtNum a[3], b[3];
    mju_addScl3(a, anchor, axis, lo - q);
    mju_addScl3(b, anchor, axis, hi - q);
    p.Line(a, b, kArcColor, 3);
    return;
  }
  // A direction perpendicular to the axis, fixed in the child body: the current angle's spoke.
  mjtNum ref[3] = {1, 0, 0};
  if (std::fabs(axis[0]) > 0.9) ref[0] = 0, ref[1] = 1;
  mjtNum perp[3];
  mju_addScl3(perp, ref, axis, -mju_dot3(ref, axis));
  mju_normalize3(perp);
  const mjtNum r = 0.7 * len;
  const auto at = [&](mjtNum angle, mjtNum out[3]) {  // spoke end at joint angle `angle`
    mjtNum quat[4], dir[3];
    mju_axisAngle2Quat(quat, axis, angle - q);
    mju_rotVecQuat(dir, perp, quat);
    mju_addScl3(out, anchor, dir, r);
  };
  mjtNum prev[3], cur[3];
  at(lo, prev);
  p.Line(anchor, prev, kArcColor);
  for (int i = 1; i <= kArcSegments; ++i) {
    at(lo + (hi - lo) * i / kArcSegments, cur);
    p.Line(prev, cur, kArcColor, 3);
    mju_copy3(prev, cur);
  }
  p.Line(anchor, prev, kArcColor);
  at(q, cur);
  p.Line(anchor, cur, kAxisColor, 3);
}

}  // namespace

const char* DebugLayerName(DebugLayer layer) { return kLayerNames[static_cast<int>(layer)]; }

bool DebugSettings::On(DebugLayer l, int art) const {
  const auto i = static_cast<std::size_t>(l);
  const bool own = art >= 0 && static_cast<std::size_t>(art) < articulation.size() &&
                   articulation[static_cast<std::size_t>(art)][i];
  if (l == DebugLayer::kVisual) {
    const bool own_on = art < 0 || static_cast<std::size_t>(art) >= articulation.size() ||
                        articulation[static_cast<std::size_t>(art)][i];
    return global[i] && own_on;
  }
  return global[i] || own;
}

bool IsCollisionGeom(const mjModel* m, int g) {
  return m->geom_group[g] == 3 || (m->geom_contype[g] != 0 && m->geom_conaffinity[g] != 0);
}

void HideVisualGeoms(const mjModel* m, const DebugSettings& settings, const DebugTables& tables,
                     mjvScene* scn) {
  int kept = 0;
  for (int i = 0; i < scn->ngeom; ++i) {
    const mjvGeom& g = scn->geoms[i];
    bool keep = true;
    if (g.objtype == mjOBJ_GEOM && g.objid >= 0 && g.objid < m->ngeom &&
        !IsCollisionGeom(m, g.objid)) {
      const int art = tables.body_articulation[static_cast<std::size_t>(m->geom_bodyid[g.objid])];
      keep = settings.On(DebugLayer::kVisual, art);
    }
    if (keep) scn->geoms[kept++] = g;
  }
  scn->ngeom = kept;
}

int AddDebugGeoms(const mjModel* m, const mjData* d, const DebugSettings& settings,
                  const DebugTables& tables, const std::vector<CapturedContact>& contacts,
                  mjvScene* scn) {
  Painter p(scn);
  const auto art_of_body = [&](int body) {
    return tables.body_articulation[static_cast<std::size_t>(body)];
  };
  for (int g = 0; g < m->ngeom; ++g) {
    const bool prop = static_cast<std::size_t>(g) < tables.prop_geom.size() &&
                      tables.prop_geom[static_cast<std::size_t>(g)];
    if (prop) {
      if (settings.Global(DebugLayer::kPropCollision)) DrawWireframe(p, m, d, g, kPropColor);
      continue;
    }
    if (!IsCollisionGeom(m, g)) continue;
    if (settings.On(DebugLayer::kCollision, art_of_body(m->geom_bodyid[g]))) {
      DrawWireframe(p, m, d, g, kCollisionColor);
    }
  }
  for (int j = 0; j < m->njnt; ++j) {
    if (settings.On(DebugLayer::kJoints, art_of_body(m->jnt_bodyid[j]))) DrawJoint(p, m, d, j);
  }
  for (int s = 0; s < m->nsite; ++s) {
    if (!settings.On(DebugLayer::kSites, art_of_body(m->site_bodyid[s]))) continue;
    p.Sphere(d->site_xpos + 3 * s, std::max<mjtNum>(m->site_size[3 * s], 0.01), kSiteColor);
  }
  // Contacts: a point, and the contact force (world frame) as an arrow scaled like MuJoCo's own
  // (vis.map.force per mean body mass, vis.scale.forcewidth thick).
  const mjtNum scale = m->vis.map.force / std::max<mjtNum>(m->stat.meanmass, mjMINVAL);
  const mjtNum radius = 0.04 * m->stat.meansize;
  // As thick as MuJoCo's own force arrows (vis.scale.forcewidth of the mean body size).
  const mjtNum width = m->vis.scale.forcewidth * m->stat.meansize;
  for (const CapturedContact& c : contacts) {
    if (c.geom1 < 0 || c.geom1 >= m->ngeom || c.geom2 < 0 || c.geom2 >= m->ngeom) continue;
    const bool on = settings.On(DebugLayer::kContacts, art_of_body(m->geom_bodyid[c.geom1])) ||
                    settings.On(DebugLayer::kContacts, art_of_body(m->geom_bodyid[c.geom2]));
    if (!on) continue;
    p.Sphere(c.pos, radius, kContactColor);
    mjtNum world[3];
    mju_mulMatTVec(world, c.frame, c.force, 3, 3);  // frame rows are the contact axes
    mjtNum tip[3];
    mju_addScl3(tip, c.pos, world, scale);
    if (mju_dist3(tip, c.pos) > radius) p.Arrow(c.pos, tip, width, kContactColor);
  }
  return p.added();
}

}  // namespace urlab::viewer::internal
