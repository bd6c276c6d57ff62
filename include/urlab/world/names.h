#pragma once
// Names users give for elements of a composed scene (the command line, the scene file, the step
// server, the viewer's panel), resolved by one set of functions so that every place accepts the
// same forms and reports the same errors.
//
// Composition names every element of articulation `dog` "dog_{name}" (mjcf/compose.h). A user
// may give either form:
//   - the short name, as written in the articulation's own MJCF ("home", "shoulder"), or
//   - the full composed name ("dog_home"), which is always accepted.
// Where the articulation is known (a scene entry, an articulation's panel, a per-articulation
// request) only its own elements are candidates. Where it is not (the step server's `reset
// {keyframe_name}`), a short name that several articulations share is ambiguous: an Error lists
// the candidates' full names. Names are reported in the short form beside their articulation.
//
// Thread: any (reads the immutable model only).
#include <mujoco/mujoco.h>

#include <string>
#include <string_view>
#include <vector>

namespace urlab::world {

// The articulation name a bare MJCF file gets (when a command runs one file as a scene): the
// folder's name when the file is `scene.xml` (as every public robot ships its scene), else the
// model's `<mujoco model="...">`, else the file stem. Characters other than letters and digits
// become '_' (leading and trailing ones dropped); "model" when nothing is left.
std::string ModelArticulationName(const std::string& mjcf_path);
// The same from the parts: `model_attribute` may be empty.
std::string ModelArticulationName(const std::string& mjcf_path, std::string_view model_attribute);

// Human word for an object type in messages: "keyframe", "joint", "actuator", ...
const char* ObjectWord(mjtObj type);

// Elements of `type` whose names `name` may mean within the articulation of `prefix` ("dog_"):
// the full name itself when it carries the prefix, and prefix + name. Ids in increasing order,
// no repeats.
std::vector<int> NameCandidates(const mjModel* m, mjtObj type, std::string_view prefix,
                                std::string_view name);
// Within the articulations of `prefixes` (the whole scene: props and launchers included when
// their prefixes are given); an exact full name is always a candidate.
std::vector<int> NameCandidates(const mjModel* m, mjtObj type,
                                const std::vector<std::string>& prefixes, std::string_view name);

// The one element `name` means within the articulation of `prefix`; -1 when none. Throws Error
// listing the candidates when it could mean two.
int FindNamed(const mjModel* m, mjtObj type, std::string_view prefix, std::string_view name);
int FindNamed(const mjModel* m, mjtObj type, const std::vector<std::string>& prefixes,
              std::string_view name);

// As FindNamed, but a missing element is an Error too, naming `owner` (e.g. "articulation
// 'dog'") and the names it has (short form).
int RequireNamed(const mjModel* m, mjtObj type, std::string_view prefix, std::string_view name,
                 std::string_view owner);
int RequireNamed(const mjModel* m, mjtObj type, const std::vector<std::string>& prefixes,
                 std::string_view name);

// The short name of element `id` within the articulation of `prefix` (its full name when it does
// not carry the prefix; "" when unnamed).
std::string ShortNameOf(const mjModel* m, mjtObj type, int id, std::string_view prefix);

// Every short name of `type` in the articulation of `prefix`, in id order.
std::vector<std::string> ShortNames(const mjModel* m, mjtObj type, std::string_view prefix);

}  // namespace urlab::world
