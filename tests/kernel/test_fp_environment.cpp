// Floating-point traps (support/catch_main.cpp) and the code that raises an
// exception on purpose (kernel/fp_environment.hpp): the traps are on in every
// test, a NaN made from numbers stops the program, the inputs that overflow by
// design (a decimal past the double range, a filter on extreme coordinates, the
// OBJ parser's scaling) give the answers they gave without traps and leave the
// traps and flags as they were, and a program started from a test (as the CLI
// tests start `shatter`) begins with the default environment, traps off.

#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <cfenv>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/fp_environment.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/predicates.hpp"

using namespace shatter;

namespace {

constexpr int trapped = FE_INVALID | FE_DIVBYZERO | FE_OVERFLOW;

// The message a reader refuses `bytes` with ("" if it reads them).
std::string refusal(const std::string& bytes, MeshFormat format) {
  try {
    (void)read_mesh_from_bytes(bytes, format);
    return {};
  } catch (const InvalidMeshError& error) {
    return error.what();
  }
}

// Runs `body` in a forked child and returns how the child ended: its signal, or
// 0 when it exited normally. The child first gives SIGFPE back its default
// action: the handlers it inherits (Catch2's, which reports a failed case, and
// AddressSanitizer's, which turns the signal into exit code 1) would otherwise
// hide the signal this test looks for.
template <class Body>
int signal_of_child(Body&& body) {
  std::fflush(nullptr);
  const pid_t child = fork();
  if (child == 0) {
    std::signal(SIGFPE, SIG_DFL);
    body();
    std::_Exit(0);
  }
  int status = 0;
  waitpid(child, &status, 0);
  return WIFSIGNALED(status) ? WTERMSIG(status) : 0;
}

}  // namespace

TEST_CASE("the test main traps invalid, divide-by-zero and overflow: a NaN stops the program", "[fp]") {
  CHECK(fegetexcept() == trapped);
  // In a child, so the test survives to look: each of the three is fatal.
  volatile double zero = 0, big = std::numeric_limits<double>::max();
  CHECK(signal_of_child([&] { volatile double nan = zero / zero; (void)nan; }) == SIGFPE);
  CHECK(signal_of_child([&] { volatile double inf = 1 / zero; (void)inf; }) == SIGFPE);
  CHECK(signal_of_child([&] { volatile double inf = big * 2; (void)inf; }) == SIGFPE);
  // Underflow and inexact are the normal life of doubles: not trapped.
  CHECK(signal_of_child([&] { volatile double tiny = std::numeric_limits<double>::min() / 3; (void)tiny; }) == 0);
}

TEST_CASE("HeldFloatingPointEnvironment holds the traps and flags for its scope, and only when traps are on",
          "[fp]") {
  volatile double big = std::numeric_limits<double>::max(), zero = 0;
  std::feclearexcept(FE_ALL_EXCEPT);
  {
    const HeldFloatingPointEnvironment held;
    CHECK(fegetexcept() == 0);
    volatile double inf = big * 2, nan = zero / zero;
    CHECK(std::isinf(inf));
    CHECK(std::isnan(nan));
    CHECK(std::fetestexcept(FE_OVERFLOW | FE_INVALID) == (FE_OVERFLOW | FE_INVALID));
  }
  CHECK(fegetexcept() == trapped);           // traps back on
  CHECK(std::fetestexcept(FE_ALL_EXCEPT & ~FE_INEXACT) == 0);  // what was raised inside is discarded
  // Without traps it does nothing at all: the default environment is left as it is.
  fedisableexcept(trapped);
  {
    const HeldFloatingPointEnvironment held;
    volatile double inf = big * 2;
    (void)inf;
  }
  CHECK(std::fetestexcept(FE_OVERFLOW) == FE_OVERFLOW);
  std::feclearexcept(FE_ALL_EXCEPT);
  feenableexcept(trapped);
  CHECK(fegetexcept() == trapped);
}

TEST_CASE("inputs that overflow by design behave as without traps, and leave the traps on", "[fp]") {
  std::feclearexcept(FE_ALL_EXCEPT);
  // side_of_plane: products past the double range go to the exact path.
  const Plane huge{{1e200, 1e200, 0}, 0};
  CHECK(side_of_plane(huge, Vec3{1e200, -1e200, 0}) == Sign::zero);
  CHECK(side_of_plane(huge, Vec3{1e200, std::nextafter(-1e200, 0.0), 0}) == Sign::positive);
  CHECK(side_of_plane(Plane{{1, 0, 0}, -1e308}, Vec3{1e308, 0, 0}) == Sign::zero);
  CHECK(side_of_plane(Plane{{1e300, 1e300, 1e300}, 1e300}, Vec3{1e10, 1e10, 1e10}) == Sign::positive);
  // A decimal past the double range rounds to infinity (refused as non-finite),
  // in every text format; OBJ also passes through tinyobjloader's parser.
  CHECK(refusal("OFF\n3 1 0\n0 0 0\n1e999 0 0\n0 1 0\n3 0 1 2\n", MeshFormat::off).find("non-finite") !=
        std::string::npos);
  CHECK(refusal("v 0 0 0\nv 1 0 0\nv 0 1e999 0\nf 1 2 3\n", MeshFormat::obj).find("non-finite") != std::string::npos);
  CHECK(refusal("solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1e999 0\nendloop\n"
                "endfacet\nendsolid t\n",
                MeshFormat::stl)
            .find("non-finite") != std::string::npos);
  // The largest double itself reads back exactly, through both OBJ parsers.
  const Mesh max = read_mesh_from_bytes("v 0 0 0\nv 1.7976931348623157e308 0 0\nv 0 1 0\nf 1 2 3\n", MeshFormat::obj);
  CHECK(max.positions[1].x == std::numeric_limits<double>::max());
  CHECK(fegetexcept() == trapped);
  CHECK(std::fetestexcept(FE_INVALID | FE_DIVBYZERO | FE_OVERFLOW) == 0);
}

TEST_CASE("a program started from a test begins with traps off, as shatter does under test_cli", "[fp]") {
  // test_cli and the others run `shatter` through std::system (a shell, then
  // execve), which gives every new program the default floating-point
  // environment. The probe is this executable itself: with SHATTER_PRINT_FP_TRAPS
  // set, the test main prints the traps it started with and exits.
  const std::string out = "/tmp/shatter-fp-probe-" + std::to_string(getpid()) + ".txt";
  const std::string command = "SHATTER_PRINT_FP_TRAPS=1 /proc/" + std::to_string(getpid()) + "/exe >" + out;
  REQUIRE(std::system(command.c_str()) == 0);
  std::FILE* file = std::fopen(out.c_str(), "r");
  REQUIRE(file != nullptr);
  int traps = -1;
  CHECK(std::fscanf(file, "%d", &traps) == 1);
  std::fclose(file);
  std::remove(out.c_str());
  CHECK(traps == 0);
  CHECK(fegetexcept() == trapped);  // and this process keeps its own
}
