// Loads a scene (or one MJCF file as a scene of one articulation) through URLab's public API,
// steps it for one simulated second on this thread, and prints where each articulation's first
// body ended up, in MuJoCo and in Unreal coordinates. Built against the installed package:
// see CMakeLists.txt beside this file.
//
// Scene sections: this program links urlab::world, which parses the scene's own keys. The
// `urlab` tool's subsystem sections are parsed by their modules once registered before the first
// scene is read: urlab::net::RegisterSceneSections() (`network:`, link urlab::net),
// urlab::camera::RegisterSceneSections() (`cameras:`, urlab::camera) and
// urlab::viewer::RegisterSceneSections() (`viewer:`, `cinematic:`, urlab::viewer). Registering
// none, it refuses a scene with one of them at its line, naming the registration to add.
#include <array>
#include <cstdio>
#include <exception>
#include <string>

#include "urlab/client/client.h"
#include "urlab/client/unreal_coords.h"
#include "urlab/core/mujoco_handlers.h"
#include "urlab/core/version.h"
#include "urlab/world/scene_file.h"
#include "urlab/world/session.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s SCENE.yaml|MODEL.xml\n", argv[0]);
    return 2;
  }
  try {
    urlab::InstallMujocoHandlers();
    const urlab::world::SceneConfig scene = urlab::world::LoadSceneOrModel(argv[1]);
    const auto session = urlab::world::Session::Create(scene);
    urlab::physics::PhysicsEngine& engine = session->engine();
    const int steps = static_cast<int>(1.0 / engine.timestep() + 0.5);
    engine.StepSync(steps);  // the physics thread is not started: steps run here
    std::printf("urlab %s on MuJoCo %s: %s\n", urlab::kVersion, mj_versionString(), argv[1]);
    engine.WithLockedData([&](mjModel* m, mjData* d) {
      std::printf("nq=%d nu=%d, %d steps, t=%.3f s\n", m->nq, m->nu, steps, d->time);
      for (const urlab::world::Articulation& a : session->articulations()) {
        for (int b = 1; b < m->nbody; ++b) {
          const char* name = mj_id2name(m, mjOBJ_BODY, b);
          if (!name || std::string(name).rfind(a.prefix, 0) != 0) continue;
          const std::array<double, 3> p = {d->xpos[3 * b], d->xpos[3 * b + 1], d->xpos[3 * b + 2]};
          const std::array<double, 3> ue = urlab::client::MjToUePosition(p);
          std::printf("%s: body %s at (%.3f, %.3f, %.3f) m, Unreal (%.1f, %.1f, %.1f) cm\n",
                      a.name().c_str(), name, p[0], p[1], p[2], ue[0], ue[1], ue[2]);
          break;
        }
      }
    });
    // A client of a running simulator would connect here (urlab run serves these).
    std::printf("step server of a running urlab: %s\n",
                urlab::client::Endpoints::OnHost("127.0.0.1").rpc.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
