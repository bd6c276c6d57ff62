// Where `urlab sweep` and `urlab bench fleet` find the Python client and its interpreter.
#pragma once

#include <string>

namespace urlab::app {

// The folder holding the urlab_client package: $URLAB_PYTHON_CLIENT, else the source tree's.
std::string PythonClientDir();

// The interpreter that runs the client (it needs gymnasium and MuJoCo's wheel): $URLAB_PYTHON,
// else the project environment made by tools/install-deps.sh (the checkout's .venv), else
// /usr/bin/python3.
std::string PythonInterpreter();

}  // namespace urlab::app
