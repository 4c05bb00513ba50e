#pragma once
// Whether the code under test was built with AddressSanitizer (.ci/sanitize),
// and the sizes the tests take there. Under ASan and UBSan the code runs several
// times slower and every run of the shatter binary pays about half a second of
// start-up and leak check, so the sanitized suite runs each property at a smaller
// size: what it adds is memory and undefined-behaviour checking of the same code
// paths, which a smaller sample of the same cases exercises; the Release suite
// runs the full size. The tests' own code is not instrumented in that build
// (shatter_test_code_uninstrumented in CMakeLists.txt), which says so with
// SHATTER_SANITIZED_LIBRARIES; a test compiled with the sanitizers itself also
// counts.

#include <cstddef>

namespace shatter::test {

#if defined(SHATTER_SANITIZED_LIBRARIES) || defined(__SANITIZE_ADDRESS__)  // the build's flag, or g++'s
inline constexpr bool under_address_sanitizer = true;
#elif defined(__has_feature)  // clang
#if __has_feature(address_sanitizer)
inline constexpr bool under_address_sanitizer = true;
#else
inline constexpr bool under_address_sanitizer = false;
#endif
#else
inline constexpr bool under_address_sanitizer = false;
#endif

/// `release` in an ordinary build, `sanitized` under AddressSanitizer: the size
/// (cases, seeds, a stride) a test takes in each.
constexpr std::size_t sized(std::size_t release, std::size_t sanitized) {
  return under_address_sanitizer ? sanitized : release;
}

}  // namespace shatter::test
