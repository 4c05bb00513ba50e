#include "viewer_page.hpp"

#include <nlohmann/json.hpp>

#include <stdexcept>

#include "errors.hpp"
#include "json_text.hpp"

namespace shatter::cli {

namespace {

constexpr std::string_view data_marker = "<!--shatter:data-->";

// JSON inside an inline <script> must not contain "</script>": every '<' (only
// ever inside a JSON string) is written as the escape \u003c instead.
std::string script_safe_json(const nlohmann::ordered_json& value) {
  const std::string text = json_text(value);
  std::string safe;
  safe.reserve(text.size());
  for (char c : text) {
    if (c == '<') {
      safe += "\\u003c";
    } else {
      safe += c;
    }
  }
  return safe;
}

std::string page_with_data(const std::string& data_html) {
  const std::string_view page = viewer_page();
  const std::size_t at = page.find(data_marker);
  if (at == std::string_view::npos) throw std::logic_error("the built viewer page has no data marker");
  std::string out;
  out.reserve(page.size() + data_html.size());
  out.append(page.substr(0, at));
  out.append(data_html);
  out.append(page.substr(at + data_marker.size()));
  return out;
}

std::string config_script(const nlohmann::ordered_json& config) {
  return "<script id=\"shatter-config\" type=\"application/json\">" + script_safe_json(config) + "</script>";
}

}  // namespace

void require_viewer(std::string_view command) {
  if (viewer_built()) return;
  throw UsageError(std::string(command) +
                   ": this shatter was built without the viewer (CMake found no npm and node when it was "
                   "configured); install Node.js and npm (bash .ci/install-deps) and build again");
}

std::string served_viewer_page() {
  require_viewer("view");
  return page_with_data(config_script({{"mode", "served"}}));
}

std::string self_contained_viewer_page(std::string_view name, std::string_view glb,
                                       const nlohmann::ordered_json* original) {
  require_viewer("export --format html");
  // base64 never contains '<', so the model needs no escaping.
  std::string data = config_script({{"mode", "file"}, {"name", std::string(name)}}) +
                     "\n<script id=\"shatter-model\" type=\"application/octet-stream\">" + base64(glb) + "</script>";
  if (original != nullptr) {
    data += "\n<script id=\"shatter-original\" type=\"application/json\">" + script_safe_json(*original) + "</script>";
  }
  return page_with_data(data);
}

std::string base64(std::string_view bytes) {
  static constexpr char digits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const unsigned v = static_cast<unsigned char>(bytes[i]) << 16 | static_cast<unsigned char>(bytes[i + 1]) << 8 |
                       static_cast<unsigned char>(bytes[i + 2]);
    out += {digits[v >> 18], digits[(v >> 12) & 63], digits[(v >> 6) & 63], digits[v & 63]};
  }
  if (const std::size_t rest = bytes.size() - i; rest > 0) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (rest == 2) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    out += {digits[v >> 18], digits[(v >> 12) & 63], rest == 2 ? digits[(v >> 6) & 63] : '=', '='};
  }
  return out;
}

}  // namespace shatter::cli
