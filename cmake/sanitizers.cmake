if(URLAB_SANITIZE STREQUAL "address")
  add_compile_options(-fsanitize=address -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address)
elseif(URLAB_SANITIZE STREQUAL "address,undefined")
  add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=undefined
                      -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
elseif(URLAB_SANITIZE STREQUAL "undefined")
  add_compile_options(-fsanitize=undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer)
  add_link_options(-fsanitize=undefined)
elseif(URLAB_SANITIZE STREQUAL "thread")
  add_compile_options(-fsanitize=thread -fno-omit-frame-pointer)
  add_link_options(-fsanitize=thread)
elseif(NOT URLAB_SANITIZE STREQUAL "")
  message(FATAL_ERROR "URLAB_SANITIZE must be '', address, undefined, 'address,undefined' or thread")
endif()

# Fuzzing (clang only): every target of ours, libraries included, is instrumented for libFuzzer's
# coverage and checked by AddressSanitizer and UndefinedBehaviorSanitizer (undefined behaviour
# aborts, so the fuzzer reports it as a crash). fuzz/CMakeLists.txt links -fsanitize=fuzzer
# into the fuzz targets only; the other executables link the sanitizer runtimes alone.
if(URLAB_BUILD_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "URLAB_BUILD_FUZZ needs clang (CC=clang CXX=clang++)")
  endif()
  if(NOT URLAB_SANITIZE STREQUAL "")
    message(FATAL_ERROR "URLAB_BUILD_FUZZ already enables address and undefined: leave "
                        "URLAB_SANITIZE empty")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined
                      -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
endif()
