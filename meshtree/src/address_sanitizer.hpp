#pragma once
// SHATTER_ADDRESS_SANITIZER: 1 when this translation unit is compiled with
// AddressSanitizer (g++ says so with __SANITIZE_ADDRESS__, clang with
// __has_feature), else 0. The builder's own page mappings (the node blocks of
// build.cpp, the byte blocks of packed_shapes.cpp) stand aside there: ASan checks
// only memory that malloc makes.

#if defined(__SANITIZE_ADDRESS__)
#define SHATTER_ADDRESS_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SHATTER_ADDRESS_SANITIZER 1
#endif
#endif
#ifndef SHATTER_ADDRESS_SANITIZER
#define SHATTER_ADDRESS_SANITIZER 0
#endif
