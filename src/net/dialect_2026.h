#pragma once
// The 2026 dialect of the step server (docs/protocol.md, "The 2026 dialect"): the vocabulary the
// URLab plugin's 2026 Python client speaks, spoken per session by a client whose hello carries a
// `client_version` beginning `urlab_bridge/`. Requests are translated into our vocabulary before
// dispatch and replies out of it after the operation ran, here and only here; the renamings are
// the tables below (data), the few behaviours that differ are the functions after them.
// Operations that belong to the Unreal editor are listed here too (both vocabularies answer them
// unknown_op with a message saying so).
// Thread: any (pure).
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "net/msgpack_codec.h"

namespace urlab::net::dialect2026 {

// A hello whose client_version begins with this speaks the 2026 dialect.
inline constexpr std::string_view kClientVersionPrefix = "urlab_bridge/";
bool Speaks(const Json& hello);

// One name in our vocabulary and in the 2026 one.
struct Rename {
  std::string_view ours, theirs;
};
// Step modes (set_mode, its echo, hello's mode, a puppet step's `mode`).
extern const std::vector<Rename> kModes;
// set_control_source's source.
extern const std::vector<Rename> kControlSources;
// set_sim_options' enum fields: ours are the names MuJoCo's XML uses; theirs are lower case.
extern const std::vector<Rename> kIntegrators, kCones, kSolvers;

// A field of one operation's request or reply under another name.
struct Field {
  std::string_view op, ours, theirs;
};
// Request fields the 2026 client sends under its own name (moved to ours when ours is absent).
extern const std::vector<Field> kRequestFields;
// Reply fields the 2026 client reads under its own name (copied beside ours: both are sent).
extern const std::vector<Field> kReplyFields;

// Where `meta` files an operation for the 2026 client: its category, and the namespace it builds
// `client.runtime.<op>` for (scene, sim, runtime; session and batch get none).
struct OpPlace {
  std::string_view op, category, ns;
};
extern const std::vector<OpPlace> kOpPlaces;
// The category and namespace of `op` (ours: "runtime" when the table has no row).
OpPlace PlaceOf(std::string_view op);

// Names in `table`: ours for theirs (nothing when `theirs` is not a 2026 name).
std::optional<std::string_view> Ours(const std::vector<Rename>& table, std::string_view theirs);
// Theirs for ours (nothing when `ours` has no row).
std::optional<std::string_view> Theirs(const std::vector<Rename>& table, std::string_view ours);

// Rewrites a 2026 request into our vocabulary, in place: the field renames above, modes,
// control source, option enums, `arts` for per_articulation and a step's `ctrl` given as a map
// for `ctrl_map`, set_qpos's target, configure_controller's per-name maps and defaults. A shape
// it cannot translate is left for the operation to refuse with its own message; a 2026 field
// with a wrong value is refused here (ops::OpError).
void TranslateRequest(Json& body);

// Rewrites our reply to operation `op` for a 2026 client, in place (the request as the client sent
// it, for what the reply echoes in its shape): the field copies above, modes and sources echoed
// by their 2026 names, option enums by name, replay session lists as names, controller gains as
// per-name maps. An error reply is left as it is.
void TranslateReply(std::string_view op, const Json& request, Json& reply);

// Operations of the Unreal editor (play sessions, levels, actors, outliner, viewport, debug
// markers, model upload, render farm): the message an unknown_op reply gives for `op`, nothing
// when `op` is not one of them.
std::optional<std::string> EditorOnly(std::string_view op);

}  // namespace urlab::net::dialect2026
