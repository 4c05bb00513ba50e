// The viewer page of a build without npm (viewer/CMakeLists.txt left the viewer
// out): there is none, and the commands that need it say so (viewer_page.hpp).
#include "viewer_page.hpp"

namespace shatter::cli {

bool viewer_built() { return false; }

std::string_view viewer_page() { return {}; }

}  // namespace shatter::cli
