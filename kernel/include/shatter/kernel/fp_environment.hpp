#pragma once
// Code that raises a floating-point exception on purpose: reading the decimal
// "1e999" (strtod rounds it to infinity and signals overflow), a filter that lets
// a product overflow to infinity and then takes its exact path. Such code holds
// the floating-point environment for its duration, so a program that traps
// invalid operations, division by zero or overflow (the test suite does, to catch
// NaNs where they are made) is not stopped by an exception the code expects.
//
// Scope it tightly, around the statement that raises by design: everywhere else
// the traps must stay on. Without traps (the default environment, and so in the
// shatter command) it does nothing at all, and the code behaves as it always did.

#include <cfenv>

namespace shatter {

/// Holds the floating-point environment for its lifetime: on construction saves
/// it, clears the exception flags and turns every trap off (feholdexcept); on
/// destruction restores the saved environment (fesetenv), traps and flags as they
/// were, discarding the flags raised meanwhile. Both are skipped when no trap is
/// on (the usual case outside the tests), so a hot path pays one read of the
/// control register. Not copyable; one thread's environment only.
class HeldFloatingPointEnvironment {
 public:
  HeldFloatingPointEnvironment() : held_(fegetexcept() != 0) {
    if (held_) std::feholdexcept(&saved_);
  }
  ~HeldFloatingPointEnvironment() {
    if (held_) std::fesetenv(&saved_);
  }
  HeldFloatingPointEnvironment(const HeldFloatingPointEnvironment&) = delete;
  HeldFloatingPointEnvironment& operator=(const HeldFloatingPointEnvironment&) = delete;

 private:
  bool held_;
  std::fenv_t saved_{};
};

}  // namespace shatter
