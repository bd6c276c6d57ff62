#include "viewer/render_quality.h"

#include <GL/gl.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace urlab::viewer::internal {

RenderQuality ResolveQuality(const ViewerOptions& cli, const QualitySettings& scene,
                             bool software_renderer) {
  RenderQuality q;
  q.shadows = cli.shadows.value_or(scene.shadows.value_or(true));
  q.reflections = cli.reflections.value_or(scene.reflections.value_or(true));
  q.skybox = cli.skybox.value_or(scene.skybox.value_or(true));
  q.scale = std::clamp(cli.render_scale.value_or(scene.render_scale.value_or(1.0)), 0.25, 2.0);
  q.shadow_size = software_renderer ? kSoftwareShadowSize : 0;
  return q;
}

void ApplyQuality(const RenderQuality& q, mjvScene* scn) {
  scn->flags[mjRND_SHADOW] = q.shadows;
  scn->flags[mjRND_REFLECTION] = q.reflections;
  scn->flags[mjRND_SKYBOX] = q.skybox;
}

bool HasSkyboxTexture(const mjModel* m) {
  for (int t = 0; t < m->ntex; ++t) {
    if (m->tex_type[t] == mjTEXTURE_SKYBOX) return true;
  }
  return false;
}

int SeparateCoplanarPlanes(mjModel* m) {
  constexpr mjtNum kStep = 0.002;
  std::vector<int> planes;
  int moved = 0;
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->geom_type[g] != mjGEOM_PLANE || m->geom_bodyid[g] != 0) continue;
    mjtNum mat[9], n[3];
    mju_quat2Mat(mat, m->geom_quat + 4 * g);
    n[0] = mat[2], n[1] = mat[5], n[2] = mat[8];  // the plane's normal: its frame's z axis
    const mjtNum d = mju_dot3(n, m->geom_pos + 3 * g);
    int same = 0;
    for (int o : planes) {
      mjtNum omat[9], on[3];
      mju_quat2Mat(omat, m->geom_quat + 4 * o);
      on[0] = omat[2], on[1] = omat[5], on[2] = omat[8];
      if (mju_dot3(n, on) > 1 - 1e-9 && std::abs(mju_dot3(on, m->geom_pos + 3 * o) - d) < 1e-3) {
        ++same;
      }
    }
    planes.push_back(g);
    if (same == 0) continue;
    mju_addToScl3(m->geom_pos + 3 * g, n, -kStep * same);
    ++moved;
  }
  return moved;
}

void DrawGradientSky(const mjrRect& vp) {
  glPushAttrib(GL_ALL_ATTRIB_BITS);
  glViewport(vp.left, vp.bottom, vp.width, vp.height);
  glEnable(GL_SCISSOR_TEST);
  glScissor(vp.left, vp.bottom, vp.width, vp.height);
  glMatrixMode(GL_PROJECTION);
  glPushMatrix();
  glLoadIdentity();
  glMatrixMode(GL_MODELVIEW);
  glPushMatrix();
  glLoadIdentity();
  glDisable(GL_LIGHTING);
  glDisable(GL_TEXTURE_2D);
  glDisable(GL_TEXTURE_CUBE_MAP);
  glDisable(GL_BLEND);
  glDisable(GL_FOG);
  glDisable(GL_STENCIL_TEST);
  glDisable(GL_CULL_FACE);
  glDisable(GL_COLOR_MATERIAL);
  // Only where nothing was drawn: at the cleared depth (the far plane). MuJoCo 3 renders with a
  // reversed depth range (cleared to 0, depth = NDC z through glClipControl), 2.x with the
  // classic one (cleared to 1): the quad sits at the clear value either way.
  GLfloat clear = 1;
  glGetFloatv(GL_DEPTH_CLEAR_VALUE, &clear);
  constexpr GLenum kClipDepthMode = 0x935D, kZeroToOne = 0x935F;  // GL 4.5 / ARB_clip_control
  GLint mode = 0;
  glGetIntegerv(kClipDepthMode, &mode);
  while (glGetError() != GL_NO_ERROR) {
  }
  const GLfloat z = static_cast<GLenum>(mode) == kZeroToOne ? clear : 2 * clear - 1;
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(clear < 0.5f ? GL_GEQUAL : GL_LEQUAL);
  glDepthMask(GL_FALSE);
  glShadeModel(GL_SMOOTH);
  glBegin(GL_QUADS);
  glColor3f(0.80f, 0.85f, 0.90f);  // near the horizon
  glVertex3f(-1, -1, z);
  glVertex3f(1, -1, z);
  glColor3f(0.36f, 0.50f, 0.68f);  // overhead
  glVertex3f(1, 1, z);
  glVertex3f(-1, 1, z);
  glEnd();
  glPopMatrix();
  glMatrixMode(GL_PROJECTION);
  glPopMatrix();
  glMatrixMode(GL_MODELVIEW);
  glPopAttrib();
}

}  // namespace urlab::viewer::internal
