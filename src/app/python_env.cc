#include "app/python_env.h"

#include <cstdlib>
#include <filesystem>

namespace urlab::app {

std::string PythonClientDir() {
  if (const char* env = std::getenv("URLAB_PYTHON_CLIENT"); env && *env) return env;
  return URLAB_PYTHON_CLIENT_DIR;
}

std::string PythonInterpreter() {
  if (const char* env = std::getenv("URLAB_PYTHON"); env && *env) return env;
  std::error_code ec;
  const std::filesystem::path venv = std::filesystem::path(URLAB_SOURCE_DIR) / ".venv/bin/python";
  if (std::filesystem::exists(venv, ec)) return venv.string();
  return "/usr/bin/python3";
}

}  // namespace urlab::app
