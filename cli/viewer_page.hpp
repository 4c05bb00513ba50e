#pragma once
// The viewer page (viewer/, issue 13) as the shatter command serves it and
// writes it: one HTML file with three.js and the viewer inline, built by CMake
// from viewer/src when npm is found and compiled into the command. A build
// without npm has no page: viewer_built() says so and the commands that need
// it refuse with one line saying why.

#include <nlohmann/json.hpp>

#include <string>
#include <string_view>

namespace shatter::cli {

/// Whether this shatter was built with the viewer page (CMake found npm and
/// node when it was configured; SHATTER_BUILD_VIEWER).
bool viewer_built();

/// The built page, with its `<!--shatter:data-->` marker where the data goes;
/// empty when !viewer_built().
std::string_view viewer_page();

/// Throws UsageError "this shatter was built without the viewer ..." (naming
/// `command` and how to get it) unless viewer_built().
void require_viewer(std::string_view command);

/// The page as `shatter view` serves it: it fetches its data from the server
/// (api/session, model.glb). Throws as require_viewer.
std::string served_viewer_page();

/// The page as `shatter export --format html` writes it: self-contained, the
/// GLB `glb` inline (base64), shown under the name `name`, so it opens from
/// disk (file://) with no server. `original`, when given, is the answer `view
/// --original` serves as GET /api/original (original_json), inline too: the
/// page then has the same "Original input" panel. Throws as require_viewer.
std::string self_contained_viewer_page(std::string_view name, std::string_view glb,
                                       const nlohmann::ordered_json* original = nullptr);

/// `bytes` in base64 (RFC 4648, with padding, no line breaks).
std::string base64(std::string_view bytes);

}  // namespace shatter::cli
