// Builds a two-link arm from scratch with URLab's C++ document API (no XML file), compiles it
// with MuJoCo and simulates one second. Run: ./build/example_build_articulation [--print-xml]
#include <cstdio>
#include <cstring>

#include "urlab/core/mujoco_handlers.h"
#include "urlab/document/builder.h"
#include "urlab/mjcf/writer.h"
#include "urlab/physics/model.h"

int main(int argc, char** argv) {
  urlab::InstallMujocoHandlers();
  using urlab::document::ArticulationBuilder;

  ArticulationBuilder b("two_link_arm");
  // Default classes: every joint gets damping, "link" geoms are capsules of one radius.
  b.Template("main", "joint").Set("damping", "0.1");
  b.DefaultClass("link");
  b.Template("link", "geom").Set("rgba", "0.8 0.6 0.4 1");

  b.Geom(nullptr, "plane", {2, 2, 0.1}, "floor");
  auto& upper = b.Body(nullptr, "upper", {0, 0, 1});
  b.Joint(upper, "shoulder", "hinge", {0, 1, 0});
  b.Geom(&upper, "capsule", {0.05}, "link").Set("fromto", "0 0 0 0.5 0 0");
  upper.Set("childclass", "link");
  auto& lower = b.Body(&upper, "lower", {0.5, 0, 0});
  b.Joint(lower, "elbow", "hinge", {0, 1, 0});
  b.Geom(&lower, "capsule", {0.04}, "link").Set("fromto", "0 0 0 0.4 0 0");  // -> link_1
  b.Site(lower, "tip", {0.4, 0, 0});

  b.Actuator("motor", "shoulder_motor", "shoulder").Set("gear", "20");
  b.Actuator("position", "elbow_servo", "elbow").Set("kp", "30");
  b.Sensor("jointpos", "shoulder_angle", "joint", "shoulder");
  b.Sensor("framepos", "tip_pos", "objtype", "site").Set("objname", "tip");
  b.Keyframe("bent", {0.3, -0.6});

  urlab::document::Document doc = b.Build();
  const std::string xml = urlab::mjcf::WriteString(doc);
  if (argc > 1 && std::strcmp(argv[1], "--print-xml") == 0) std::fputs(xml.c_str(), stdout);

  urlab::physics::ModelPtr model = urlab::physics::CompileXmlString(xml);
  urlab::physics::DataPtr data = urlab::physics::MakeData(model.get());
  mj_resetDataKeyframe(model.get(), data.get(), 0);
  data->ctrl[1] = -0.6;
  const int steps = static_cast<int>(1.0 / model->opt.timestep);
  for (int i = 0; i < steps; ++i) mj_step(model.get(), data.get());
  std::printf("nbody=%d njnt=%d nu=%d nsensor=%d; after %.2fs: shoulder=%.4f elbow=%.4f\n",
              static_cast<int>(model->nbody), static_cast<int>(model->njnt),
              static_cast<int>(model->nu), static_cast<int>(model->nsensor), data->time,
              data->qpos[0], data->qpos[1]);
  return 0;
}
