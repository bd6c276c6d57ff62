# The one MuJoCo release URLab builds and runs on (the version pinned in tools/requirements.txt).
#
# Defines the imported target mujoco::mujoco and
#   URLAB_MUJOCO_VERSION      X.Y.Z from the library's file name
#   URLAB_MUJOCO_LIBRARY      the shared library (libmujoco.so.X.Y.Z)
#   URLAB_MUJOCO_PLUGIN_DIR   the engine plugins shipped with it ("" when none)
#
# MUJOCO_ROOT (a cache variable, or the environment variable of that name) is one of:
#   - an official release tarball unpacked: include/mujoco/mujoco.h, lib/libmujoco.so*,
#     plugins in bin/mujoco_plugin (or lib/mujoco_plugin);
#   - the `mujoco` folder of PyPI's wheel: include/mujoco/mujoco.h, libmujoco.so.X.Y.Z, plugin/.
# Without it, the wheel in the project's Python environment (.venv, made by
# tools/install-deps.sh) is used. Nothing is downloaded here.
set(MUJOCO_ROOT "$ENV{MUJOCO_ROOT}" CACHE PATH
    "An official MuJoCo release (tarball or the wheel's mujoco/ folder); default: .venv's wheel")

if(NOT MUJOCO_ROOT)
  file(GLOB _urlab_wheel_dirs "${PROJECT_SOURCE_DIR}/.venv/lib/python3*/site-packages/mujoco")
  if(_urlab_wheel_dirs)
    list(GET _urlab_wheel_dirs 0 _urlab_mujoco_root)
  else()
    message(FATAL_ERROR
      "MuJoCo not found: run tools/install-deps.sh (it installs the pinned `mujoco` wheel into "
      "${PROJECT_SOURCE_DIR}/.venv), or pass -DMUJOCO_ROOT=<an official MuJoCo release>")
  endif()
else()
  set(_urlab_mujoco_root "${MUJOCO_ROOT}")
endif()
get_filename_component(_urlab_mujoco_root "${_urlab_mujoco_root}" REALPATH)

if(NOT EXISTS "${_urlab_mujoco_root}/include/mujoco/mujoco.h")
  message(FATAL_ERROR "MUJOCO_ROOT=${_urlab_mujoco_root}: no include/mujoco/mujoco.h there")
endif()
file(GLOB _urlab_mujoco_libs "${_urlab_mujoco_root}/libmujoco.so.*"
     "${_urlab_mujoco_root}/lib/libmujoco.so.*")
list(FILTER _urlab_mujoco_libs INCLUDE REGEX "libmujoco\\.so\\.[0-9]+\\.[0-9]+\\.[0-9]+$")
if(NOT _urlab_mujoco_libs)
  message(FATAL_ERROR "MUJOCO_ROOT=${_urlab_mujoco_root}: no libmujoco.so.X.Y.Z there (or in lib/)")
endif()
list(GET _urlab_mujoco_libs 0 URLAB_MUJOCO_LIBRARY)
string(REGEX MATCH "[0-9]+\\.[0-9]+\\.[0-9]+$" URLAB_MUJOCO_VERSION "${URLAB_MUJOCO_LIBRARY}")
if(URLAB_MUJOCO_VERSION VERSION_LESS 3.11)
  message(FATAL_ERROR "MuJoCo ${URLAB_MUJOCO_VERSION} at ${_urlab_mujoco_root}: URLab needs 3.11 or "
                      "newer (the pinned release is in tools/requirements.txt)")
endif()
get_filename_component(_urlab_mujoco_libdir "${URLAB_MUJOCO_LIBRARY}" DIRECTORY)
get_filename_component(_urlab_mujoco_soname "${URLAB_MUJOCO_LIBRARY}" NAME)

set(URLAB_MUJOCO_PLUGIN_DIR "")
foreach(_d plugin bin/mujoco_plugin lib/mujoco_plugin)
  if(IS_DIRECTORY "${_urlab_mujoco_root}/${_d}")
    set(URLAB_MUJOCO_PLUGIN_DIR "${_urlab_mujoco_root}/${_d}")
    break()
  endif()
endforeach()

if(NOT TARGET mujoco::mujoco)
  add_library(mujoco::mujoco SHARED IMPORTED GLOBAL)
  set_target_properties(mujoco::mujoco PROPERTIES
    IMPORTED_LOCATION "${URLAB_MUJOCO_LIBRARY}"
    IMPORTED_SONAME "${_urlab_mujoco_soname}"
    INTERFACE_INCLUDE_DIRECTORIES "${_urlab_mujoco_root}/include")
endif()
# Programs find the library without LD_LIBRARY_PATH: the build tree through its folder, an
# install through $ORIGIN/../lib, where cmake/install.cmake puts the library and its plugins.
list(APPEND CMAKE_BUILD_RPATH "${_urlab_mujoco_libdir}")
set(URLAB_MUJOCO_LIBDIR "${_urlab_mujoco_libdir}")
message(STATUS "MuJoCo ${URLAB_MUJOCO_VERSION}: ${URLAB_MUJOCO_LIBRARY} "
               "(plugins: ${URLAB_MUJOCO_PLUGIN_DIR})")
