#pragma once
// Exports: the composed scene as MJCF with the physics options in effect now. MuJoCo 2.2.2 saves
// the XML it loaded, so options changed at run time (the viewer's panel, set_sim_options) would
// be lost; the export writes them into the document's <option> element and its <flag> child.
//
// Threading: SceneXml on any thread but not from inside a physics callback (it copies the model
// under the step mutex); WriteOptionChanges touches only its arguments.
#include <mujoco/mujoco.h>

#include <string>
#include <vector>

#include "urlab/document/document.h"
#include "urlab/mjcf/writer.h"
#include "urlab/world/session.h"

namespace urlab::ops {

// Writes every option of `now` that differs from `compiled` into doc's <option> (created when
// absent; flags into <option><flag>), as MJCF attributes. Returns the attributes written, e.g.
// "timestep", "flag.contact" (empty when nothing changed: the document is left untouched).
std::vector<std::string> WriteOptionChanges(const mjOption& compiled, const mjOption& now,
                                            document::Document& doc);

// The composed scene's MJCF with the options in effect now (the viewer's Save XML). `changed`,
// when given, receives the attributes written (see WriteOptionChanges).
std::string SceneXml(world::Session& session, const mjcf::WriteOptions& options,
                     std::vector<std::string>* changed = nullptr);

}  // namespace urlab::ops
