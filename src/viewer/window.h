#pragma once
// Window: one GLFW window with an OpenGL compatibility context (MuJoCo's mjr renderer needs
// fixed-function GL) and a Dear ImGui context drawn with the GLFW and OpenGL2 backends. Input
// events go to an InputHandler; tests call the handler directly to inject events.
//
// Threading contract: main thread only (GLFW requires it for windows and events).
#include <optional>
#include <string>
#include <vector>

struct GLFWwindow;
struct ImGuiContext;

namespace urlab::viewer::internal {

// Receives the window's input events (GLFW key, button and modifier codes).
class InputHandler {
 public:
  virtual ~InputHandler() = default;
  virtual void OnKey(int key, int action, int mods) = 0;
  virtual void OnMouseButton(int button, int action, int mods) = 0;
  virtual void OnCursor(double x, double y) = 0;
  virtual void OnScroll(double dx, double dy) = 0;
  // Files dropped on the window (paths as the system gives them).
  virtual void OnDrop(const std::vector<std::string>& /*paths*/) {}
};

// Lowers the calling thread's priority (nice + 5) for good: the thread that draws, once the
// physics thread exists (threads it creates later inherit it). False when it could not.
bool LowerRenderThreadPriority();

class Window {
 public:
  // Opens the window and makes its context current; throws Error when GLFW cannot initialise (no
  // display) or the context cannot be created.
  Window(int width, int height, const std::string& title, InputHandler* handler, bool imgui);
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  GLFWwindow* handle() const { return window_; }
  bool should_close() const;
  // Processes pending window events (callbacks run inside).
  void PollEvents();
  // ImGui frame: NewFrame before building widgets, Render after (draws into the back buffer).
  void BeginImGui();
  void EndImGui();
  bool has_imgui() const { return imgui_ != nullptr; }
  // True while ImGui uses the mouse / keyboard (over the panel, typing in a field).
  bool imgui_wants_mouse() const;
  bool imgui_wants_keyboard() const;
  // Tests: the mouse ImGui sees from the next BeginImGui on (window coordinates, left button
  // down or up), in place of the real cursor; std::nullopt gives the real cursor back.
  struct InjectedMouse {
    float x = 0, y = 0;
    bool down = false;
  };
  void InjectImGuiMouse(std::optional<InjectedMouse> mouse) { injected_mouse_ = mouse; }
  void SwapBuffers();
  // Clears the whole back buffer to a colour (the viewport and the panel draw over it).
  void Clear(float r, float g, float b);
  void FramebufferSize(int* width, int* height) const;
  void WindowSize(int* width, int* height) const;
  // The clipboard's text (copy pose writes it).
  void SetClipboard(const std::string& text);
  std::string Clipboard() const;
  // The GL version string of the context ("4.5 (Compatibility Profile) Mesa ...").
  std::string GlVersion() const;
  // True on Mesa's software rasterisers (llvmpipe, softpipe).
  bool software_renderer() const;

 private:
  GLFWwindow* window_ = nullptr;
  ImGuiContext* imgui_ = nullptr;
  InputHandler* handler_;
  std::optional<InjectedMouse> injected_mouse_;
};

}  // namespace urlab::viewer::internal
