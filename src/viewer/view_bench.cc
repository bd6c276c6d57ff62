#include "urlab/viewer/view_bench.h"

#include <atomic>
#include <chrono>
#include <exception>
#include <thread>

#include "viewer/debug_capture.h"
#include "viewer/debug_draw.h"
#include "viewer/scene_view.h"
#include "viewer/window.h"

namespace urlab::viewer {

namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kFrame = std::chrono::microseconds(16667);

// No input in a benchmark window.
class NoInput : public internal::InputHandler {
 public:
  void OnKey(int, int, int) override {}
  void OnMouseButton(int, int, int) override {}
  void OnCursor(double, double) override {}
  void OnScroll(double, double) override {}
};

}  // namespace

ViewBenchResult RunLoopBenchWithView(const physics::Model& model, world::LoopBenchOptions options,
                                     const ViewerOptions& view) {
  NoInput input;
  internal::Window window(view.width, view.height, view.title, &input, /*imgui=*/false);
  internal::SceneView scene(model.get(), 40000);
  scene.MakeContext();
  if (window.software_renderer()) {
    scene.scene().flags[mjRND_SHADOW] = 0;
    scene.scene().flags[mjRND_REFLECTION] = 0;
  }
  internal::DebugSettings debug;
  for (auto l : {internal::DebugLayer::kContacts, internal::DebugLayer::kCollision,
                 internal::DebugLayer::kJoints, internal::DebugLayer::kSites}) {
    debug.Global(l) = true;
  }
  internal::DebugTables tables;
  tables.body_articulation.assign(static_cast<std::size_t>(model->nbody), -1);
  tables.prop_geom.assign(static_cast<std::size_t>(model->ngeom), false);

  std::shared_ptr<physics::StateSubscription> state;
  auto capture = std::make_shared<internal::DebugCapture>();
  std::atomic<bool> attached{false}, drawing{false}, done{false};
  options.attach = [&](physics::PhysicsEngine& engine) {  // worker thread, engine stopped
    state = engine.SubscribeState("viewer");
    engine.AddPostStepCallback([capture](const mjModel* m, mjData* d) { capture->Capture(m, d); });
    attached.store(true);
  };
  options.toggle = [&](bool on) { drawing.store(on); };

  ViewBenchResult result;
  std::exception_ptr error;
  std::thread worker([&] {
    try {
      result.loop = world::RunLoopBench(model, options);
    } catch (...) {
      error = std::current_exception();
    }
    done.store(true);
  });
  internal::LowerRenderThreadPriority();  // as the viewer does once the physics thread runs
  std::vector<internal::CapturedContact> contacts;
  double drawing_seconds = 0;
  auto next = Clock::now();
  while (!done.load()) {
    window.PollEvents();
    if (!attached.load() || !drawing.load()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      next = Clock::now();
      continue;
    }
    const auto start = Clock::now();
    if (const physics::StateFrame* f = state->Latest()) scene.Update(*f);
    capture->Take(&contacts);
    capture->Request();
    scene.UpdateScene();
    internal::AddDebugGeoms(scene.model(), scene.data(), debug, tables, contacts, &scene.scene());
    int w = 0, h = 0;
    window.FramebufferSize(&w, &h);
    scene.Render(mjrRect{0, 0, w, h});
    window.SwapBuffers();
    ++result.frames;
    drawing_seconds += std::chrono::duration<double>(Clock::now() - start).count();
    next += kFrame;
    if (next < Clock::now()) next = Clock::now();
    std::this_thread::sleep_until(next);
  }
  worker.join();
  if (error) std::rethrow_exception(error);
  // Frames per second of drawing time: the rate the window could sustain.
  result.fps = drawing_seconds > 0 ? static_cast<double>(result.frames) / drawing_seconds : 0;
  return result;
}

}  // namespace urlab::viewer
