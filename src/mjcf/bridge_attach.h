#pragma once
// MuJoCo 3.x <model> assets and <attach model body prefix> (internal to the mjcf module, called by
// the dialect bridge before any other pass): the child model is read and bridged on its own, its
// angles converted to the parent's compiler settings, every name prefixed and its defaults wrapped
// as class "{prefix}main" (the composer's own steps, compose_steps.h), then the named body's
// subtree (or the whole world body's contents in a <frame>) replaces the <attach>, and the child's
// assets and the elements referring into the subtree (tendons, equalities, contact pairs and
// excludes, actuators, sensors) join the parent's sections. The child's keyframes join the
// parent's after its own keys, one set per attachment, named "{prefix}{name}" (3.x's merge):
// their values by element name are returned, and the bridge's keyframe pass writes them at those
// elements' addresses of the final model, the rest as 3.x does (qpos0, mocap body poses, zeros).
//
// Thread: plain function over a document the caller owns.
#include <map>
#include <string>
#include <vector>

#include "urlab/document/document.h"
#include "urlab/mjcf/bridge.h"

namespace urlab::mjcf {

// A keyframe of an attached model: the <key> added to the parent's <keyframe> (no values yet)
// and the child key's values by prefixed name. Names the final model lacks (joints outside the
// attached subtree, actuators that stayed in the child) are not part of the attachment.
struct AttachedKey {
  document::Element* key = nullptr;
  double time = 0;
  std::map<std::string, std::vector<double>> qpos, qvel;   // by joint
  std::map<std::string, double> ctrl, act;                 // by actuator
  std::map<std::string, std::vector<double>> mpos, mquat;  // by mocap body
};

// Expands every <attach> of `doc` and removes its <model> assets; changes (and refusals) are
// added to `report`, together with the runtime needs of the attached models (software sensors,
// gravcomp, ...), their names prefixed; the attached keyframes are added to `keys`. `depth`
// guards against models attaching each other.
void ExpandAttachments(document::Document& doc, BridgeReport& report,
                       std::vector<AttachedKey>* keys, int depth = 0);

}  // namespace urlab::mjcf
