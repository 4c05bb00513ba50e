#pragma once
// Running the shatter binary from a test: its exit code and what it printed.
// Header-only because the binary's path, SHATTER_EXE, is defined per test target.

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "scratch.hpp"

#ifndef SHATTER_EXE
#error "define SHATTER_EXE (the shatter binary's path) for this test target"
#endif
#ifndef SHATTER_TEST_NAME
#error "define SHATTER_TEST_NAME (tests/CMakeLists.txt's shatter_test does) for this test target"
#endif

namespace shatter::test {

struct Run {
  int exit_code;  ///< -1 when killed by a signal
  std::string out;
  std::string err;
};

/// The whole file as bytes ("" when it cannot be read).
inline std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

/// A fresh path `name` in this process's own scratch folder for `tag`
/// (process_scratch_folder: removed at exit), emptied if it existed, the folder
/// above it created.
inline std::filesystem::path scratch_path(const std::string& tag, const std::string& name) {
  const std::filesystem::path dir = process_scratch_folder(tag) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir.parent_path());
  return dir;
}

/// Runs the shatter binary with `arguments` (already shell-quoted), stdin empty,
/// stdout and stderr captured through files in the `tag` scratch folder.
inline Run run_shatter_binary(const std::string& tag, const std::string& arguments) {
  const std::filesystem::path out = scratch_path(tag, "stdout.txt"), err = scratch_path(tag, "stderr.txt");
  const std::string command = std::string("'") + SHATTER_EXE + "' " + arguments + " >'" + out.string() + "' 2>'" +
                              err.string() + "' </dev/null";
  const int status = std::system(command.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

/// scratch_path in this test binary's own folder (tagged with its name).
inline std::filesystem::path scratch(const std::string& name) { return scratch_path(SHATTER_TEST_NAME, name); }

/// run_shatter_binary with this test binary's own scratch folder.
inline Run run_shatter(const std::string& arguments) { return run_shatter_binary(SHATTER_TEST_NAME, arguments); }

/// True when `err` is exactly one line starting "error: ", as every refusal of
/// the command prints it.
inline bool is_one_error_line(const std::string& err) {
  return err.rfind("error: ", 0) == 0 && err.find('\n') == err.size() - 1;
}

/// A path quoted for the shell. Appended piece by piece: GCC 12 warns falsely
/// (-Wrestrict, its bug 105651) on `"'" + std::string`.
inline std::string quoted(const std::filesystem::path& p) {
  std::string text = "'";
  text += p.string();
  text += '\'';
  return text;
}

}  // namespace shatter::test
