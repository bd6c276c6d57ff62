#pragma once
// Silencing one GCC diagnostic around the smallest region where a known GCC 12 false positive
// fires at -O3 (Release). Each use names the GCC bug. Other compilers see nothing (clang does
// not know some of these warnings and would warn about the pragma).
//
//   URLAB_GCC_IGNORE("-Wrestrict")  // GCC PR 105329
//   ...one statement...
//   URLAB_GCC_RESTORE
#if defined(__GNUC__) && !defined(__clang__)
#define URLAB_GCC_PRAGMA_(x) _Pragma(#x)
#define URLAB_GCC_IGNORE(warning) \
  _Pragma("GCC diagnostic push") URLAB_GCC_PRAGMA_(GCC diagnostic ignored warning)
#define URLAB_GCC_RESTORE _Pragma("GCC diagnostic pop")
#else
#define URLAB_GCC_IGNORE(warning)
#define URLAB_GCC_RESTORE
#endif
