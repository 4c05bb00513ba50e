#pragma once
// JSON as text for every command's output (--json, the viewer's pages and API).

#include <string>

#include <nlohmann/json.hpp>

namespace shatter::cli {

/// `value` as JSON text (`indent` as nlohmann's dump: -1 compact). Strings that
/// are not valid UTF-8, as a file name on Linux may be, have each bad byte
/// written as U+FFFD instead of stopping the command: nlohmann's default
/// throws, and `fracture --json` of such a path exited 1 after writing its
/// files (found by a sweep, 2026-12-07). Never throws but std::bad_alloc.
template <class Json>
std::string json_text(const Json& value, int indent = -1) {
  return value.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace shatter::cli
