#include "viewer/window.h"

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl2.h>
#include <imgui.h>
#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>

#include "render/render_thread.h"
#include "urlab/core/error.h"

namespace urlab::viewer::internal {

namespace {

// GLFW is initialised once per process and terminated when the last window closes.
int& OpenWindows() {
  static int count = 0;
  return count;
}
std::string& LastGlfwError() {
  static std::string text;
  return text;
}

void OnGlfwError(int code, const char* text) {
  LastGlfwError() = text ? text : "";
  spdlog::debug("GLFW error {}: {}", code, LastGlfwError());
}

// Mesa's software rasteriser (llvmpipe) draws on threads of its own, created with the context
// and inheriting the creating thread's nice value. So that drawing never takes the physics
// thread's core, they run at a lower priority (the creating thread's nice + kRenderNice, only
// while the context is made), and by default one fewer than the cores.
constexpr int kRenderNice = 5;

class LowerPriorityScope {
 public:
  LowerPriorityScope() {
    errno = 0;
    const int now = getpriority(PRIO_PROCESS, static_cast<id_t>(gettid()));
    if (errno == 0 &&
        setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), now + kRenderNice) == 0) {
      saved_ = now;
      lowered_ = true;
    }
  }
  ~LowerPriorityScope() {
    // Raising it back may need privileges a lowered thread lacks; then it stays lower.
    if (lowered_) setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), saved_);
  }

 private:
  int saved_ = 0;
  bool lowered_ = false;
};

InputHandler* HandlerOf(GLFWwindow* w) {
  return static_cast<InputHandler*>(glfwGetWindowUserPointer(w));
}

}  // namespace

bool LowerRenderThreadPriority() { return render::LowerThreadPriority(kRenderNice); }

Window::Window(int width, int height, const std::string& title, InputHandler* handler, bool imgui)
    : handler_(handler) {
  if (OpenWindows() == 0) {
    glfwSetErrorCallback(OnGlfwError);
    if (!glfwInit()) {
      throw Error("viewer: cannot open a window (GLFW: " + LastGlfwError() +
                  "); is DISPLAY set? Under no display, run it with xvfb-run");
    }
  }
  // Default hints: a compatibility context, as MuJoCo's fixed-function renderer needs.
  glfwDefaultWindowHints();
  glfwWindowHint(GLFW_SAMPLES, 0);
  render::LimitSoftwareRasterThreads();
  {
    LowerPriorityScope lower;
    window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
    if (window_) glfwMakeContextCurrent(window_);
  }
  if (!window_) {
    if (OpenWindows() == 0) glfwTerminate();
    throw Error("viewer: cannot create a " + std::to_string(width) + "x" + std::to_string(height) +
                " window with an OpenGL context (GLFW: " + LastGlfwError() + ")");
  }
  ++OpenWindows();
  glfwSwapInterval(0);  // the host paces frames; never wait for a vertical blank
  glfwSetWindowUserPointer(window_, handler_);
  // Ours first: ImGui's backend chains to the callbacks installed before it.
  glfwSetKeyCallback(window_, [](GLFWwindow* w, int key, int, int action, int mods) {
    if (InputHandler* h = HandlerOf(w)) h->OnKey(key, action, mods);
  });
  glfwSetMouseButtonCallback(window_, [](GLFWwindow* w, int button, int action, int mods) {
    if (InputHandler* h = HandlerOf(w)) h->OnMouseButton(button, action, mods);
  });
  glfwSetCursorPosCallback(window_, [](GLFWwindow* w, double x, double y) {
    if (InputHandler* h = HandlerOf(w)) h->OnCursor(x, y);
  });
  glfwSetScrollCallback(window_, [](GLFWwindow* w, double dx, double dy) {
    if (InputHandler* h = HandlerOf(w)) h->OnScroll(dx, dy);
  });
  glfwSetDropCallback(window_, [](GLFWwindow* w, int count, const char** paths) {
    std::vector<std::string> files(paths, paths + std::max(0, count));
    if (InputHandler* h = HandlerOf(w)) h->OnDrop(files);
  });
  if (imgui) {
    IMGUI_CHECKVERSION();
    imgui_ = ImGui::CreateContext();
    ImGui::SetCurrentContext(imgui_);
    ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini next to the user's files
    ImGui::StyleColorsDark();
    ImGui_ImplGlfw_InitForOpenGL(window_, true);
    ImGui_ImplOpenGL2_Init();
  }
}

Window::~Window() {
  if (imgui_) {
    ImGui::SetCurrentContext(imgui_);
    ImGui_ImplOpenGL2_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext(imgui_);
  }
  glfwDestroyWindow(window_);
  if (--OpenWindows() == 0) glfwTerminate();
}

bool Window::should_close() const { return glfwWindowShouldClose(window_) != 0; }

void Window::PollEvents() { glfwPollEvents(); }

void Window::BeginImGui() {
  if (!imgui_) return;
  ImGui::SetCurrentContext(imgui_);
  ImGui_ImplOpenGL2_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  if (injected_mouse_) {
    // After the backend read the real cursor: the injected one wins (ImGui 1.86 reads io's
    // mouse fields in NewFrame).
    ImGuiIO& io = ImGui::GetIO();
    io.MousePos = ImVec2(injected_mouse_->x, injected_mouse_->y);
    io.MouseDown[0] = injected_mouse_->down;
  }
  ImGui::NewFrame();
}

void Window::EndImGui() {
  if (!imgui_) return;
  ImGui::Render();
  // MuJoCo's renderer leaves its vertex buffers bound; the OpenGL2 backend draws from client
  // memory, which a bound buffer would turn into offsets.
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, 0);
  // ... and may leave another texture unit active, with texture-coordinate generation and fog.
  for (GLenum unit : {GL_TEXTURE1, GL_TEXTURE0}) {
    glActiveTexture(unit);
    glDisable(GL_TEXTURE_GEN_S);
    glDisable(GL_TEXTURE_GEN_T);
    glDisable(GL_TEXTURE_GEN_R);
    glDisable(GL_TEXTURE_GEN_Q);
    glDisable(GL_TEXTURE_2D);
    glDisable(GL_TEXTURE_CUBE_MAP);
  }
  glDisable(GL_FOG);
  ImGui_ImplOpenGL2_RenderDrawData(ImGui::GetDrawData());
}

bool Window::imgui_wants_mouse() const { return imgui_ && ImGui::GetIO().WantCaptureMouse; }
bool Window::imgui_wants_keyboard() const { return imgui_ && ImGui::GetIO().WantCaptureKeyboard; }

void Window::SwapBuffers() { glfwSwapBuffers(window_); }

void Window::Clear(float r, float g, float b) {
  int w = 0, h = 0;
  glfwGetFramebufferSize(window_, &w, &h);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glDisable(GL_SCISSOR_TEST);
  glViewport(0, 0, w, h);
  glClearColor(r, g, b, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

void Window::FramebufferSize(int* width, int* height) const {
  glfwGetFramebufferSize(window_, width, height);
}
void Window::WindowSize(int* width, int* height) const {
  glfwGetWindowSize(window_, width, height);
}

bool Window::software_renderer() const {
  const auto* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const std::string renderer = r ? r : "";
  return renderer.find("llvmpipe") != std::string::npos ||
         renderer.find("softpipe") != std::string::npos;
}

void Window::SetClipboard(const std::string& text) {
  glfwSetClipboardString(window_, text.c_str());
}

std::string Window::Clipboard() const {
  const char* t = glfwGetClipboardString(window_);
  return t ? t : "";
}

std::string Window::GlVersion() const {
  const auto* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  const auto* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  return std::string(v ? v : "?") + " (" + (r ? r : "?") + ")";
}

}  // namespace urlab::viewer::internal
