#pragma once
// MuJoCo's editable model (mjSpec) as URLab uses it: MJCF files and text parsed by MuJoCo's own
// parser into specs, errors turned into urlab::InputError with the file and line MuJoCo names,
// options applied from MJCF attribute text, and a spec saved back as MJCF.
//
// Thread: pure functions; a spec is used by one thread at a time (the main thread builds and
// recompiles scenes).
#include <mujoco/mujoco.h>

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "urlab/core/error.h"

namespace urlab::mjcf {

struct SpecDeleter {
  void operator()(mjSpec* s) const { mj_deleteSpec(s); }
};
using SpecPtr = std::unique_ptr<mjSpec, SpecDeleter>;

// Parses the MJCF file at `path` with MuJoCo's parser (includes and assets resolve as MuJoCo
// resolves them, from the file's folder). The file must be a regular file of at most
// kMaxTextInputBytes, and no number in it may be NaN or infinite (MuJoCo would take some).
// Throws InputError at path:line with MuJoCo's message (or ours).
SpecPtr ParseFile(const std::string& path);

// The text of one of MuJoCo's spec strings ("" for none). Read them only through this (or
// mjs_getString): mjString is MuJoCo's own std::string, built against another C++ library.
std::string SpecString(const mjString* s);

// `file` (as a <mesh>, <texture>, ... names it) resolved as MuJoCo resolves it from `spec`: the
// model's folder, <compiler strippath>, then `dir` (the compiler's meshdir or texturedir).
std::string ResolveAssetPath(const mjSpec* spec, const std::string& file, const mjString* dir);

// Every asset file of `spec` (meshes, textures, height fields, skins) rewritten as the absolute
// path MuJoCo resolves it to (the model's folder, then meshdir or texturedir), so that the spec
// can be attached to another and saved anywhere. ParseFile does it.
void AbsoluteAssetPaths(mjSpec* spec);

// The six separate files of every cube texture (fileright ... fileback, mjsTexture::cubefiles)
// of `spec`, parsed from the MJCF file `path`, made absolute as AbsoluteAssetPaths makes `file`
// (the names are read from `path` and its includes: MuJoCo's C API cannot read a string vector
// back before compiling). ParseFile does it.
void AbsoluteCubeFiles(mjSpec* spec, const std::string& path);

// Throws InputError (at `path`'s line that names it) for an asset file of `spec` that exists
// but is not a regular file (a folder, a device, a FIFO: MuJoCo would block or read forever).
// ParseFile does it, after AbsoluteAssetPaths.
void RefuseAssetsThatAreNotFiles(mjSpec* spec, const std::string& path);

// `xml` (MJCF text with absolute asset paths) with every asset file attribute (file, and a cube
// texture's fileright ... fileback) replaced by `rename(path)`.
std::string MapAssetPaths(const std::string& xml,
                          const std::function<std::string(const std::string&)>& rename);

// `xml` (MJCF text with absolute asset paths) with every asset `file` written relative to
// `folder`, where the text will be saved.
std::string RelativeAssetPaths(const std::string& xml, const std::string& folder);

// Every file the model at `path` reads: the file, its includes and its asset files (absolute,
// sorted, each once); just the file when it cannot be parsed. Outputs must never overwrite one.
std::vector<std::string> ModelInputFiles(const std::string& path);

// Parses MJCF text; `label` names it in messages (a generated document: its scene entry). Asset
// paths in it should be absolute. Throws InputError.
SpecPtr ParseString(const std::string& xml, const SourceLocation& label);

// The first line of the file at `path` that holds `text`, 0 when none (or the file is unreadable):
// where an element MuJoCo does not locate is written.
int LineContaining(const std::string& path, const std::string& text);

// The line MuJoCo's message names ("line N"), 0 when none.
int LineOfMujocoMessage(const std::string& message);

// MuJoCo's message without the "XML Error: " / "Error: " prefix and trailing blank lines.
std::string TidyMujocoMessage(const std::string& message);

// The spec written as MJCF by MuJoCo (mj_saveXMLString; MuJoCo writes only a spec it has
// compiled). Throws Error with MuJoCo's reason.
std::string SaveXml(const mjSpec* spec);

// Sets one <option> attribute of `option` from its MJCF text ("timestep" = "0.002", "gravity" =
// "0 0 -9.81", "integrator" = "implicitfast", "flag.contact" = "disable", ...). Throws Error
// naming the attribute for an unknown name or a value MuJoCo would not take.
void SetOption(mjOption* option, const std::string& key, const std::string& value);

// Every option attribute SetOption knows, as MJCF text of `option`'s value (for reports and the
// scene's exported options), keyed as SetOption takes them.
std::map<std::string, std::string> OptionText(const mjOption& option);

}  // namespace urlab::mjcf
