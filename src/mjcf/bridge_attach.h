#pragma once
// MuJoCo 3.x <model> assets and <attach model body prefix> (internal to the mjcf module, called by
// the dialect bridge before any other pass): the child model is read and bridged on its own, its
// angles converted to the parent's compiler settings, every name prefixed and its defaults wrapped
// as class "{prefix}main" (the composer's own steps, compose_steps.h), then the named body's
// subtree (or the whole world body's contents in a <frame>) replaces the <attach>, and the child's
// assets and the elements referring into the subtree (tendons, equalities, contact pairs and
// excludes, actuators, sensors) join the parent's sections.
//
// Thread: plain function over a document the caller owns.
#include "urlab/document/document.h"
#include "urlab/mjcf/bridge.h"

namespace urlab::mjcf {

// Expands every <attach> of `doc` and removes its <model> assets; changes (and refusals) are
// added to `report`, together with the runtime needs of the attached models (software sensors,
// gravcomp, ...), their names prefixed. `depth` guards against models attaching each other.
void ExpandAttachments(document::Document& doc, BridgeReport& report, int depth = 0);

}  // namespace urlab::mjcf
