# Precompiled headers: the standard library and the third-party headers most translation units
# include are parsed once per target instead of once per file (an average file here is ~110,000
# preprocessed lines, most of them these headers). A build-time aid only: every source should
# still include what it uses. CI checks that for the installed headers alone (its install stage
# compiles each one on its own); elsewhere a -DURLAB_PCH=OFF build shows a missing include.
option(URLAB_PCH "Precompile common standard and third-party headers" ON)

set(URLAB_PCH_STD
    <algorithm> <array> <atomic> <chrono> <cmath> <cstdint> <cstring> <filesystem> <fstream>
    <functional> <map> <memory> <mutex> <optional> <span> <string> <string_view> <thread>
    <unordered_map> <vector>)

# urlab_pch(TARGET [TEST] [JSON] [MSGPACK] [ZMQ] [CLI]): precompiles the common standard headers
# and <mujoco/mujoco.h>, plus GoogleTest for a test program and the named header-only libraries
# for targets that use them (each target's own flags and definitions, so any mix is valid).
function(urlab_pch target)
  if(NOT URLAB_PCH)
    return()
  endif()
  cmake_parse_arguments(P "TEST;JSON;MSGPACK;ZMQ;CLI" "" "" ${ARGN})
  set(headers ${URLAB_PCH_STD} <mujoco/mujoco.h>)
  if(P_TEST)
    list(APPEND headers <gtest/gtest.h> <gmock/gmock.h>)
  endif()
  if(P_JSON)
    list(APPEND headers <nlohmann/json.hpp>)
  endif()
  if(P_MSGPACK)
    # The codec builds msgpack-cxx without Boost (src/net/msgpack_codec.h defines the same).
    target_compile_definitions(${target} PRIVATE MSGPACK_NO_BOOST=1)
    list(APPEND headers <msgpack.hpp>)
  endif()
  if(P_ZMQ)
    list(APPEND headers <zmq.hpp> <zmq_addon.hpp>)
  endif()
  if(P_CLI)
    list(APPEND headers <CLI/CLI.hpp>)
  endif()
  target_precompile_headers(${target} PRIVATE ${headers})
  # <mujoco/mujoco.h> is precompiled for every target, also those that do not link MuJoCo (wire,
  # client): they see the pinned release's headers, never another copy on the system.
  target_include_directories(${target} SYSTEM PRIVATE
                             $<TARGET_PROPERTY:mujoco::mujoco,INTERFACE_INCLUDE_DIRECTORIES>)
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
    # GCC 12's flow-based buffer warnings misfire on std::string's inlined copies (string
    # concatenation: PR 105651 and its kin) once <string> comes from a precompiled header, where
    # it no longer counts as a system header. They stay on in builds without precompiled headers
    # and in clang builds (CI's asan stage).
    target_compile_options(${target} PRIVATE -Wno-array-bounds -Wno-stringop-overflow
                                             -Wno-stringop-overread -Wno-restrict)
  endif()
endfunction()
