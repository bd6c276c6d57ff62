#include "control/leg_kinematics.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

#include "urlab/core/error.h"

namespace urlab::control::legs {

namespace {

std::string BodyName(const mjModel* m, int b) {
  const char* n = mj_id2name(m, mjOBJ_BODY, b);
  return n ? n : "body " + std::to_string(b);
}

std::string JointName(const mjModel* m, int j) {
  const char* n = mj_id2name(m, mjOBJ_JOINT, j);
  return n ? n : "joint " + std::to_string(j);
}

// True when body `a` is `b` or one of its ancestors.
bool IsAncestor(const mjModel* m, int a, int b) {
  for (; b > 0; b = m->body_parentid[b]) {
    if (b == a) return true;
  }
  return a == 0;
}

}  // namespace

std::vector<Leg> FindLegs(const mjModel* m, int root, std::span<const ActuatorBinding> bindings,
                          const mjtNum* stand_qpos) {
  if (root <= 0 || root >= m->nbody || m->body_jntnum[root] < 1 ||
      m->jnt_type[m->body_jntadr[root]] != mjJNT_FREE) {
    throw Error("gait: the robot's root body " + (root > 0 ? BodyName(m, root) : std::string()) +
                " has no free joint (a gait walks a floating base)");
  }
  // Actuated joints grouped by the child of the root they hang from.
  std::map<int, std::vector<std::pair<int, int>>> groups;  // child body -> (joint, binding)
  for (std::size_t i = 0; i < bindings.size(); ++i) {
    const ActuatorBinding& b = bindings[i];
    if (b.joint_id < 0) continue;
    if (m->jnt_type[b.joint_id] != mjJNT_HINGE) {
      throw Error("gait: actuated joint '" + JointName(m, b.joint_id) +
                  "' is not a hinge (legs are chains of hinges)");
    }
    int c = m->jnt_bodyid[b.joint_id];
    while (c > 0 && m->body_parentid[c] != root) c = m->body_parentid[c];
    if (c <= 0) continue;  // not below the root
    auto& g = groups[c];
    if (std::none_of(g.begin(), g.end(), [&](auto& p) { return p.first == b.joint_id; })) {
      g.emplace_back(b.joint_id, static_cast<int>(i));
    }
  }

  std::unique_ptr<mjData, void (*)(mjData*)> d(mj_makeData(m), mj_deleteData);
  mju_copy(d->qpos, stand_qpos, m->nq);
  mj_kinematics(m, d.get());
  const mjtNum* root_pos = d->xpos + 3 * root;
  const mjtNum* root_mat = d->xmat + 9 * root;

  std::vector<Leg> legs;
  for (auto& [child, joints] : groups) {
    // Order the joints root outwards; each must lie on the chain to the deepest one.
    std::sort(joints.begin(), joints.end(), [](auto& a, auto& b) { return a.first < b.first; });
    const int end = m->jnt_bodyid[joints.back().first];
    Leg leg;
    leg.name = BodyName(m, end);
    for (auto& [j, b] : joints) {
      if (!IsAncestor(m, m->jnt_bodyid[j], end)) {
        throw Error("gait: the leg below " + BodyName(m, child) + " branches (joint '" +
                    JointName(m, j) + "' is not on the chain to " + leg.name + ")");
      }
    }
    if (joints.size() > 16) {
      throw Error("gait: the leg ending in " + leg.name + " has more than 16 hinges");
    }
    if (joints.size() < 3) {
      throw Error("gait: the leg ending in " + leg.name + " has " + std::to_string(joints.size()) +
                  " actuated hinge(s); a foot needs three to be placed");
    }
    std::vector<int> chain;
    for (int b = end; b != root; b = m->body_parentid[b]) chain.push_back(b);
    std::reverse(chain.begin(), chain.end());
    for (int b : chain) {
      ChainLink link;
      mju_copy3(link.pos, m->body_pos + 3 * b);
      mju_copy4(link.quat, m->body_quat + 4 * b);
      for (int j = m->body_jntadr[b]; j >= 0 && j < m->body_jntadr[b] + m->body_jntnum[b]; ++j) {
        auto it = std::find_if(joints.begin(), joints.end(), [&](auto& p) { return p.first == j; });
        if (it == joints.end()) {
          throw Error("gait: joint '" + JointName(m, j) + "' in the leg ending in " + leg.name +
                      " has no actuator of this robot");
        }
        LegJoint lj;
        lj.joint = j;
        lj.binding = it->second;
        lj.qpos_adr = m->jnt_qposadr[j];
        lj.dof_adr = m->jnt_dofadr[j];
        lj.qpos0 = m->qpos0[lj.qpos_adr];
        lj.limited = m->jnt_limited[j] != 0;
        lj.range[0] = m->jnt_range[2 * j];
        lj.range[1] = m->jnt_range[2 * j + 1];
        mju_copy3(lj.pos, m->jnt_pos + 3 * j);
        mju_copy3(lj.axis, m->jnt_axis + 3 * j);
        link.joints.push_back(static_cast<int>(leg.joints.size()));
        leg.joints.push_back(lj);
        leg.stand_q.push_back(stand_qpos[lj.qpos_adr]);
      }
      leg.links.push_back(std::move(link));
    }
    // The foot: the lowest site or geom centre of the end body's subtree in the standing pose.
    double lowest = mjMAXVAL;
    const mjtNum* foot_world = nullptr;
    const auto consider = [&](const mjtNum* p, int body) {
      if (IsAncestor(m, end, body) && p[2] < lowest) {
        lowest = p[2];
        foot_world = p;
      }
    };
    for (int s = 0; s < m->nsite; ++s) consider(d->site_xpos + 3 * s, m->site_bodyid[s]);
    for (int g = 0; g < m->ngeom; ++g) consider(d->geom_xpos + 3 * g, m->geom_bodyid[g]);
    if (!foot_world) foot_world = d->xpos + 3 * end;
    double nearest = mjMAXVAL;
    for (int g = 0; g < m->ngeom; ++g) {
      if (!IsAncestor(m, end, m->geom_bodyid[g])) continue;
      if (m->geom_contype[g] == 0 && m->geom_conaffinity[g] == 0) continue;
      const double dist = mju_dist3(d->geom_xpos + 3 * g, foot_world);
      if (dist < nearest) {
        nearest = dist;
        leg.foot_geom = g;
      }
    }
    mjtNum rel[3];
    mju_sub3(rel, foot_world, d->xpos + 3 * end);
    mju_mulMatTVec(leg.foot, d->xmat + 9 * end, rel, 3, 3);
    FootPosition(leg, leg.stand_q, leg.stand, nullptr);
    // The hip: the first joint's anchor in the root frame.
    mju_sub3(rel, d->xanchor + 3 * leg.joints.front().joint, root_pos);
    mju_mulMatTVec(leg.hip, root_mat, rel, 3, 3);
    legs.push_back(std::move(leg));
  }
  return legs;
}

void FootPosition(const Leg& leg, std::span<const double> q, double foot[3], double* jac) {
  mjtNum x[3] = {0, 0, 0}, r[4] = {1, 0, 0, 0}, tmp[3], qt[4];
  const std::size_t n = leg.joints.size();
  mjtNum anchors[16][3], axes[16][3];  // a leg has few joints (checked below)
  for (const ChainLink& link : leg.links) {
    mju_rotVecQuat(tmp, link.pos, r);
    mju_addTo3(x, tmp);
    mju_mulQuat(qt, r, link.quat);
    mju_copy4(r, qt);
    for (int k : link.joints) {
      const LegJoint& j = leg.joints[static_cast<std::size_t>(k)];
      mjtNum anchor[3], axis[3], qloc[4];
      mju_rotVecQuat(anchor, j.pos, r);
      mju_addTo3(anchor, x);
      mju_rotVecQuat(axis, j.axis, r);
      mju_axisAngle2Quat(qloc, j.axis, q[static_cast<std::size_t>(k)] - j.qpos0);
      mju_mulQuat(qt, r, qloc);
      mju_copy4(r, qt);
      mju_rotVecQuat(tmp, j.pos, r);
      mju_sub3(x, anchor, tmp);
      if (k < 16) {
        mju_copy3(anchors[k], anchor);
        mju_copy3(axes[k], axis);
      }
    }
  }
  mju_rotVecQuat(tmp, leg.foot, r);
  mju_add3(foot, x, tmp);
  if (!jac) return;
  for (std::size_t k = 0; k < n; ++k) {
    mjtNum lever[3], col[3] = {0, 0, 0};
    if (k < 16) {
      mju_sub3(lever, foot, anchors[k]);
      mju_cross(col, axes[k], lever);
    }
    for (int i = 0; i < 3; ++i) jac[static_cast<std::size_t>(i) * n + k] = col[i];
  }
}

double SolveIk(const Leg& leg, const double target[3], std::span<double> q) {
  const std::size_t n = leg.joints.size();
  double jac[3 * 16], foot[3], err[3];
  double dist = 0, last = mjMAXVAL;
  for (int iter = 0; iter < 12; ++iter) {
    FootPosition(leg, q, foot, jac);
    mju_sub3(err, target, foot);
    dist = mju_norm3(err);
    // Within 10 um, or stuck (a target out of reach, a joint at its limit).
    if (dist < 1e-5 || dist > 0.9 * last || n > 16) break;
    last = dist;
    // dq = J^T (J J^T + lambda^2 I)^-1 err
    mjtNum a[9];
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < 3; ++k) {
        double s = 0;
        for (std::size_t c = 0; c < n; ++c) s += jac[i * n + c] * jac[k * n + c];
        a[3 * i + k] = s + (i == k ? 1e-4 : 0);
      }
    }
    mjtNum y[3];
    mju_cholFactor(a, 3, 1e-10);
    mju_cholSolve(y, a, err, 3);
    for (std::size_t c = 0; c < n; ++c) {
      double dq = jac[c] * y[0] + jac[n + c] * y[1] + jac[2 * n + c] * y[2];
      dq = std::clamp(dq, -0.3, 0.3);
      const LegJoint& j = leg.joints[c];
      q[c] += dq;
      if (j.limited) q[c] = std::clamp(q[c], j.range[0], j.range[1]);
    }
  }
  return dist;
}

}  // namespace urlab::control::legs
