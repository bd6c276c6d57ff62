# Warnings: always on for our targets. Whether they are errors is a choice of the build:
# URLAB_WARNINGS_AS_ERRORS is ON in development builds (tools/build.sh) and in every CI stage, and
# OFF by default, so that a user's plain `cmake -DCMAKE_BUILD_TYPE=Release` builds even where a
# compiler version raises a false positive (GCC 12 -O3's -Wrestrict, PR 105329).
option(URLAB_WARNINGS_AS_ERRORS "Treat compiler warnings as errors (development and CI builds)" OFF)

function(urlab_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
                                           -Wno-missing-field-initializers)
  if(URLAB_WARNINGS_AS_ERRORS)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
