#pragma once
// MuJoCo's binary skin format (.skn) read into an inline <skin>: the bones of an SKN file name
// bodies inside the binary file, where composition cannot prefix them, so the composer writes
// the skin's data (vertices, texture coordinates, faces, bones) as MJCF attributes instead.
// Thread: any (pure function over one element).
#include "urlab/document/element.h"

namespace urlab::mjcf::internal {

// Replaces `skin`'s `file` by the file's contents as inline attributes and <bone> children,
// keeping its implicit name (the file name) as an explicit one. The values are the file's
// float32 numbers written exactly, so the compiled skin is the same. Throws InputError (at the
// skin) when the file cannot be read or its size does not match its header, as 2.2.2 checks.
void InlineSkinFile(document::Element& skin);

}  // namespace urlab::mjcf::internal
