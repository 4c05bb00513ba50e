// The unit the tests' precompiled header is built with (tests/CMakeLists.txt,
// shatter_test_pch): CMake compiles the header beside it, with this target's
// options, and every test executable reuses that header. It defines nothing.
