# `cmake --install BUILD --prefix P`: the urlab binary, the module libraries, the public headers
# (with the generated version.h) and a CMake package, so that another project can write
#   find_package(urlab REQUIRED)
#   target_link_libraries(app PRIVATE urlab::world urlab::client)
# (see examples/find_package). The libraries are static: their private dependencies travel in
# the exported link interface as $<LINK_ONLY:...>, so urlabConfig.cmake finds those too.
include(CMakePackageConfigHelpers)

# The MuJoCo release URLab was built with travels with it: its library (found by the installed
# programs through $ORIGIN/../lib), its C headers (the public headers include them) and its engine
# plugins (lib/mujoco_plugin, loaded at start).
install(FILES ${URLAB_MUJOCO_LIBRARY} DESTINATION ${CMAKE_INSTALL_LIBDIR})
get_target_property(_urlab_mujoco_include mujoco::mujoco INTERFACE_INCLUDE_DIRECTORIES)
install(DIRECTORY ${_urlab_mujoco_include}/mujoco DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
if(URLAB_MUJOCO_PLUGIN_DIR)
  install(DIRECTORY ${URLAB_MUJOCO_PLUGIN_DIR}/ DESTINATION ${CMAKE_INSTALL_LIBDIR}/mujoco_plugin
          FILES_MATCHING PATTERN "*.so*")
endif()
set_target_properties(urlab urlab_batch PROPERTIES INSTALL_RPATH "$ORIGIN/../${CMAKE_INSTALL_LIBDIR}")

get_property(urlab_modules GLOBAL PROPERTY URLAB_MODULES)
set_target_properties(urlab PROPERTIES EXPORT_NAME urlab)
install(TARGETS ${urlab_modules} urlab
        EXPORT urlabTargets
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
# liburlab_batch.so, the in-process batch's C interface (the Python client's in-process backend
# finds it beside bin/urlab, in ../lib).
install(TARGETS urlab_batch LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/urlab DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        FILES_MATCHING PATTERN "*.h")
install(FILES ${PROJECT_BINARY_DIR}/generated/urlab/core/version.h
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/urlab/core)

set(URLAB_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/urlab)
install(EXPORT urlabTargets NAMESPACE urlab:: DESTINATION ${URLAB_CMAKE_DIR})
get_filename_component(URLAB_MUJOCO_SONAME ${URLAB_MUJOCO_LIBRARY} NAME)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/urlabConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/urlabConfig.cmake
                              INSTALL_DESTINATION ${URLAB_CMAKE_DIR})
# 0.x: a minor version may break the API.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/urlabConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/urlabConfig.cmake ${PROJECT_BINARY_DIR}/urlabConfigVersion.cmake
        DESTINATION ${URLAB_CMAKE_DIR})
