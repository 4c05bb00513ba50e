#include "errors.hpp"

#include <CLI/CLI.hpp>

#include <array>
#include <iostream>
#include <string_view>

#include "shatter/kernel/error.hpp"

namespace shatter::cli {

namespace {

struct ExitCodeMeaning {
  ExitCode code;
  std::string_view meaning;
};

constexpr std::array<ExitCodeMeaning, 5> exit_code_table = {{
    {ExitCode::ok, "ok"},
    {ExitCode::internal_error, "internal error"},
    {ExitCode::usage_error, "usage error"},
    {ExitCode::invalid_input, "invalid input (mesh, geometry or .shatter file)"},
    {ExitCode::io_error, "I/O error"},
}};

}  // namespace

std::string exit_codes_help() {
  std::string text = "Exit codes:";
  for (const ExitCodeMeaning& row : exit_code_table) {
    text += (row.code == ExitCode::ok ? " " : ", ") + std::to_string(static_cast<int>(row.code)) + " ";
    text += row.meaning;
  }
  return text + ".";
}

Failure failure_of(const std::exception_ptr& error) {
  try {
    std::rethrow_exception(error);
  } catch (const UsageError& e) {
    return {ExitCode::usage_error, e.what()};
  } catch (const CLI::ParseError& e) {
    return {ExitCode::usage_error, std::string(e.what()) + " (see --help)"};
  } catch (const InvalidMeshError& e) {
    return {ExitCode::invalid_input, e.what()};
  } catch (const UnsupportedGeometryError& e) {
    return {ExitCode::invalid_input, e.what()};
  } catch (const CorruptFileError& e) {
    return {ExitCode::invalid_input, e.what()};
  } catch (const IoError& e) {
    return {ExitCode::io_error, e.what()};
  } catch (const std::exception& e) {
    return {ExitCode::internal_error, std::string("internal error: ") + e.what()};
  } catch (...) {
    return {ExitCode::internal_error, "internal error: an exception of unknown type"};
  }
}

int report_failure(const Failure& failure) {
  std::string message = failure.message;
  while (!message.empty() && (message.back() == '\n' || message.back() == '\r')) message.pop_back();
  for (std::size_t at = message.find_first_of("\r\n"); at != std::string::npos;
       at = message.find_first_of("\r\n", at)) {
    const std::size_t end = message.find_first_not_of("\r\n", at);
    message.replace(at, end == std::string::npos ? std::string::npos : end - at, "; ");
  }
  std::cerr << "error: " << message << '\n';
  return static_cast<int>(failure.code);
}

}  // namespace shatter::cli
