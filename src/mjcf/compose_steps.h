#pragma once
// Steps of the composer (compose.cc) that the dialect bridge reuses for MuJoCo 3.x <attach>
// (bridge_attach.cc): the same prefixing, default-class wrapping and angle conversion a scene
// applies to each articulation, and its naming of unnamed elements. Internal to the mjcf module.
//
// Thread: pure functions over documents the caller owns.
#include <memory>
#include <string>

#include "urlab/document/document.h"

namespace urlab::mjcf {

// Gives unnamed bodies, joints, sites, tendons, actuators and sensors a stable generated name
// "{tag}{index}" (made unique with _1, _2 when a real name already uses it).
void NameUnnamed(document::Document& doc);

// Gives every name and every attribute naming another element the prefix (references to the
// world body excepted).
void PrefixNames(document::Document& doc, const std::string& prefix);

// Detaches the document's top-level <default> as class "{prefix}main"; elements that used the
// implicit main class name it (top-level bodies through childclass). nullptr without defaults.
std::unique_ptr<document::Element> WrapDefaultsAsClass(document::Document& doc,
                                                       const std::string& prefix);

// Rewrites angle-dependent values so the document means the same under compiler settings `to`.
void ConvertAngleUnits(document::Document& doc, const document::CompilerSettings& from,
                       const document::CompilerSettings& to);

}  // namespace urlab::mjcf
