#include "net/dialect_2026.h"

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "urlab/ops/error.h"

namespace urlab::net::dialect2026 {
namespace {

TEST(Dialect2026Test, ChosenByTheClientVersionPrefix) {
  EXPECT_TRUE(Speaks(Json{{"op", "hello"}, {"client_version", "urlab_bridge/0.9.1"}}));
  EXPECT_FALSE(Speaks(Json{{"op", "hello"}, {"client_version", "urlab_client/1.0"}}));
  EXPECT_FALSE(Speaks(Json{{"op", "hello"}, {"client_version", 3}}));
  EXPECT_FALSE(Speaks(Json{{"op", "hello"}}));
}

TEST(Dialect2026Test, TablesAreOneToOne) {
  for (const auto* table : {&kModes, &kControlSources, &kIntegrators, &kCones, &kSolvers}) {
    std::set<std::string_view> ours, theirs;
    for (const Rename& r : *table) {
      EXPECT_TRUE(ours.insert(r.ours).second) << r.ours;
      EXPECT_TRUE(theirs.insert(r.theirs).second) << r.theirs;
      EXPECT_EQ(Ours(*table, r.theirs), r.ours);
      EXPECT_EQ(Theirs(*table, r.ours), r.theirs);
    }
  }
  EXPECT_EQ(Ours(kModes, "stepped"), "direct");
  EXPECT_EQ(Theirs(kModes, "live"), "freerun");
  EXPECT_EQ(Theirs(kModes, "puppet"), "statepushed");
  EXPECT_FALSE(Ours(kModes, "direct").has_value());  // ours is not a 2026 name
}

TEST(Dialect2026Test, ModesTranslateInAndEchoOut) {
  Json request{{"op", "set_mode"}, {"mode", "stepped"}};
  TranslateRequest(request);
  EXPECT_EQ(request["mode"], "direct");
  Json reply{{"op", "set_mode_ok"}, {"previous_mode", "live"}, {"current_mode", "direct"}};
  TranslateReply("set_mode", request, reply);
  EXPECT_EQ(reply["previous_mode"], "freerun");
  EXPECT_EQ(reply["current_mode"], "stepped");
  // A name of neither vocabulary is left for the operation to refuse.
  Json odd{{"op", "set_mode"}, {"mode", "warp"}};
  TranslateRequest(odd);
  EXPECT_EQ(odd["mode"], "warp");
}

TEST(Dialect2026Test, StepTakesArtsAndCtrlByName) {
  Json request{
      {"op", "step"},
      {"n_steps", 3},
      {"arts",
       {{"dog",
         {{"ctrl", {{"FR_hip", 0.1}, {"FL_hip", -0.1}}}, {"control_mode", "ue_controller"}}}}}};
  TranslateRequest(request);
  ASSERT_TRUE(request.contains("per_articulation"));
  EXPECT_FALSE(request.contains("arts"));
  const Json& dog = request["per_articulation"]["dog"];
  EXPECT_FALSE(dog.contains("ctrl"));
  EXPECT_EQ(dog["ctrl_map"]["FR_hip"], 0.1);
  EXPECT_EQ(dog["control_mode"], "ue_controller");
  // A ctrl vector stays a vector.
  Json vector{{"op", "step"}, {"per_articulation", {{"arm", {{"ctrl", {1.0, 2.0}}}}}}};
  TranslateRequest(vector);
  EXPECT_TRUE(vector["per_articulation"]["arm"]["ctrl"].is_array());
}

TEST(Dialect2026Test, GainsAsPerNameMapsWithDefaults) {
  Json request{{"op", "configure_controller"},
               {"articulation", "dog"},
               {"params",
                {{"kp", {{"FR_hip", 50.0}}},
                 {"kv", {{"FR_hip", 1.5}, {"FL_hip", 2.5}}},
                 {"default_kp", 30.0},
                 {"default_torque_limit", 20.0}}}};
  const Json original = request;
  TranslateRequest(request);
  const Json& p = request["params"];
  EXPECT_EQ(p["kp"], 30.0);  // the defaults: every actuator first
  EXPECT_EQ(p["torque_limit"], 20.0);
  EXPECT_FALSE(p.contains("kv"));
  EXPECT_EQ(p["gains"]["FR_hip"]["kp"], 50.0);  // then the names
  EXPECT_EQ(p["gains"]["FR_hip"]["kv"], 1.5);
  EXPECT_EQ(p["gains"]["FL_hip"]["kv"], 2.5);
  EXPECT_FALSE(p["gains"]["FL_hip"].contains("kp"));

  Json reply{{"op", "configure_controller_ok"},
             {"articulation", "dog"},
             {"params",
              {{"gains",
                {{"FR_hip", {{"kp", 50.0}, {"kv", 1.5}, {"torque_limit", 20.0}}},
                 {"FL_hip", {{"kp", 30.0}, {"kv", 2.5}, {"torque_limit", 20.0}}}}}}}};
  TranslateReply("configure_controller", original, reply);
  const Json& echo = reply["params"];
  EXPECT_EQ(echo["kp"], (Json{{"FR_hip", 50.0}, {"FL_hip", 30.0}}));
  EXPECT_EQ(echo["kv"], (Json{{"FR_hip", 1.5}, {"FL_hip", 2.5}}));
  EXPECT_EQ(echo["torque_limit"], (Json{{"FR_hip", 20.0}, {"FL_hip", 20.0}}));
  EXPECT_EQ(echo["default_kp"], 30.0);
  EXPECT_EQ(echo["default_torque_limit"], 20.0);
  EXPECT_FALSE(echo.contains("default_kv"));
  EXPECT_FALSE(echo.contains("gains"));
}

TEST(Dialect2026Test, FieldRenamesInAndOut) {
  Json qpos{{"op", "set_qpos"}, {"target", "dog"}, {"target_by", "actor_name"}, {"qpos", {0.0}}};
  TranslateRequest(qpos);
  EXPECT_EQ(qpos["articulation"], "dog");
  EXPECT_FALSE(qpos.contains("target"));
  EXPECT_FALSE(qpos.contains("target_by"));
  Json by_id{{"op", "set_qpos"}, {"target", "dog"}, {"target_by", "guid"}, {"qpos", {0.0}}};
  EXPECT_THROW(TranslateRequest(by_id), ops::OpError);

  Json source{{"op", "set_control_source"}, {"source", "zmq"}};
  TranslateRequest(source);
  EXPECT_EQ(source["source"], "network");
  Json echoed{{"op", "set_control_source_ok"}, {"source", "network"}};
  TranslateReply("set_control_source", source, echoed);
  EXPECT_EQ(echoed["source"], "zmq");

  Json active{{"op", "replay_set_active"}, {"name", "r2"}};
  TranslateRequest(active);
  EXPECT_EQ(active["session"], "r2");

  Json stop{{"op", "recording_stop_ok"}, {"frames", 7}, {"duration", 0.014}};
  TranslateReply("recording_stop", Json(), stop);
  EXPECT_EQ(stop["frame_count"], 7);
  EXPECT_EQ(stop["sim_duration_s"], 0.014);
  EXPECT_EQ(stop["frames"], 7);  // ours stays beside

  Json contacts{{"op", "get_contacts_ok"}, {"count", 4}, {"matched", 4}};
  TranslateReply("get_contacts", Json(), contacts);
  EXPECT_EQ(contacts["n_contacts"], 4);

  Json list{{"op", "replay_list_sessions_ok"},
            {"sessions", {{{"session", "r1"}, {"frames", 3}}, {{"session", "r2"}}}}};
  TranslateReply("replay_list_sessions", Json(), list);
  EXPECT_EQ(list["sessions"], (Json{"r1", "r2"}));

  Json start{{"op", "replay_start_ok"}, {"session", "r1"}, {"frames", 9}};
  TranslateReply("replay_start", Json(), start);
  EXPECT_EQ(start["active_session"], "r1");
  EXPECT_EQ(start["total_frames"], 9);
}

TEST(Dialect2026Test, OptionEnumsByName) {
  Json request{{"op", "set_sim_options"},
               {"options", {{"integrator", "rk4"}, {"solver", "newton"}, {"cone", "elliptic"}}}};
  TranslateRequest(request);
  EXPECT_EQ(request["options"]["integrator"], "RK4");
  EXPECT_EQ(request["options"]["solver"], "Newton");
  EXPECT_EQ(request["options"]["cone"], "elliptic");
  Json reply{{"op", "set_sim_options_ok"},
             {"options", {{"timestep", 0.002}, {"integrator", 2}, {"cone", 0}, {"solver", 1}}}};
  TranslateReply("set_sim_options", request, reply);
  EXPECT_EQ(reply["options"]["integrator"], "implicit");
  EXPECT_EQ(reply["options"]["cone"], "pyramidal");
  EXPECT_EQ(reply["options"]["solver"], "cg");
  EXPECT_EQ(reply["options"]["timestep"], 0.002);
}

TEST(Dialect2026Test, ErrorRepliesAreLeftAlone) {
  Json error{{"op", "error"}, {"code", "not_driver"}, {"count", 1}};
  const Json before = error;
  TranslateReply("get_contacts", Json(), error);
  EXPECT_EQ(error, before);
}

TEST(Dialect2026Test, EditorOperationsAreNamed) {
  for (const char* op :
       {"begin_pie", "stop_pie", "pie_status", "list_levels", "load_level", "list_actors",
        "spawn_actor", "outliner_tree", "viewport_screenshot", "set_viewport_camera",
        "debug_draw_line", "clear_debug_markers", "upload_model_manifest", "upload_model_chunk",
        "upload_model_commit", "render_farm_submit"}) {
    const std::optional<std::string> why = EditorOnly(op);
    ASSERT_TRUE(why.has_value()) << op;
    EXPECT_NE(why->find("Unreal editor"), std::string::npos) << *why;
  }
  for (const char* op : {"step", "reset", "get_contacts", "replay_load", "set_twist", "frobnicate",
                         "configure_controller", "recording_start"}) {
    EXPECT_FALSE(EditorOnly(op).has_value()) << op;
  }
}

TEST(Dialect2026Test, EveryOperationHasANamespaceTheClientKnowsOrNone) {
  const std::set<std::string_view> known = {"scene", "sim",      "runtime", "outliner",
                                            "debug", "viewport", "session", "batch"};
  for (const OpPlace& p : kOpPlaces) EXPECT_TRUE(known.count(p.ns)) << p.op;
  EXPECT_EQ(PlaceOf("step").ns, "sim");
  EXPECT_EQ(PlaceOf("recording_start").category, "recording");
  EXPECT_EQ(PlaceOf("replay_load").category, "replay");
  EXPECT_EQ(PlaceOf("hello").ns, "session");
}

}  // namespace
}  // namespace urlab::net::dialect2026
