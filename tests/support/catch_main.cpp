// Catch2's main for every test executable, with floating-point traps on: an
// invalid operation (a NaN made from numbers), a division by zero or an overflow
// raises SIGFPE at the instruction that did it, and Catch2 reports the signal as
// a failure of the running test case. So a NaN or an infinity fails loudly where
// it is made instead of flowing quietly into a comparison that happens to pass.
// Library code that raises one of these on purpose (the decimal reader's strtod
// of "1e999", a filter on extreme coordinates) holds the floating-point
// environment around just that code (kernel/fp_environment.hpp), so the traps
// stay on everywhere else. Inexact and underflow stay untrapped: rounding and
// gradual underflow are the normal life of doubles.
//
// Threads the tests start inherit the traps (a new thread starts with its
// creator's floating-point environment); programs they run (the shatter binary)
// do not: execve gives every new program the default environment. With
// SHATTER_PRINT_FP_TRAPS set, the main prints the traps it started with and
// exits, which tests/kernel/test_fp_environment.cpp uses to check that.

#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include <cfenv>
#include <cstdio>
#include <cstdlib>

int main(int argc, char* argv[]) {
  if (std::getenv("SHATTER_PRINT_FP_TRAPS") != nullptr) {
    std::printf("%d\n", fegetexcept());
    return 0;
  }
  feenableexcept(FE_INVALID | FE_DIVBYZERO | FE_OVERFLOW);
  return Catch::Session().run(argc, argv);
}
