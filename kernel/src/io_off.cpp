// OFF: "OFF", the counts "vertices faces edges", one vertex per line, then one
// face per line as "n i0 ... i(n-1)" with optional colour values after the indices.
// Comments run from '#' to the end of the line. The COFF/NOFF/STOFF variants add
// values to each vertex line, which are read past; 4OFF, nOFF and binary OFF
// change the layout and are refused.

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "io_internal.hpp"

namespace shatter::io_detail {

namespace {

std::string at_line(std::size_t line) { return " at line " + std::to_string(line); }

// A line's tokens: the comment cut off, then split.
void tokens_of(std::string_view line, std::vector<std::string_view>& tokens) {
  if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
  split_tokens(line, tokens);
}

/// Lines with comments removed; blank lines are skipped.
class OffLines {
 public:
  explicit OffLines(std::string_view bytes) : cursor_(bytes) {}

  bool next(std::vector<std::string_view>& tokens) {
    std::string_view line;
    while (cursor_.next(line)) {
      tokens_of(line, tokens);
      if (!tokens.empty()) return true;
    }
    return false;
  }
  std::size_t line_number() const { return cursor_.line_number(); }
  /// Bytes not yet returned as lines.
  std::string_view rest() const { return cursor_.rest(); }

 private:
  LineCursor cursor_;
};

// Below this many bytes of vertex and face lines, the body is read on one thread.
constexpr std::size_t parallel_body_bytes = std::size_t{1} << 20;

// The vertex and face lines of a large file (`body`, all after the counts) read
// on the caller's threads: cut into chunks at line ends, each chunk's data lines
// counted, then each chunk parsed knowing the index of its first data line.
// Only the plain case is read so: exactly vertex_count + face_count data lines,
// every vertex line three finite coordinates (or more where the variant allows),
// every face a triangle of indices in range. Anything else gives nullopt, and
// the sequential reader reads the file again and decides (refusing with the line
// named, skipping extra face lines with a warning, triangulating polygons): the
// same mesh or the same refusal either way.
std::optional<IndexedSoup> read_body_in_parallel(std::string_view body, std::uint64_t vertex_count,
                                                 std::uint64_t face_count, bool extras_allowed) {
  const auto threads = static_cast<std::size_t>(tbb::this_task_arena::max_concurrency());
  if (threads < 2 || body.size() < parallel_body_bytes) return std::nullopt;
  if (vertex_count > body.size() || face_count > body.size()) return std::nullopt;  // claims no file this size holds
  const std::size_t chunk_count = 8 * threads;
  std::vector<std::size_t> start(chunk_count + 1, body.size());
  start[0] = 0;
  for (std::size_t c = 1; c < chunk_count; ++c) {
    const std::size_t end_of_line = body.find('\n', std::max(start[c - 1], c * body.size() / chunk_count));
    start[c] = end_of_line == std::string_view::npos ? body.size() : end_of_line + 1;
  }
  const auto chunk = [&](std::size_t c) { return body.substr(start[c], start[c + 1] - start[c]); };

  std::vector<std::uint64_t> first_data_line(chunk_count + 1, 0);
  tbb::parallel_for(std::size_t{0}, chunk_count, [&](std::size_t c) {
    // A line has tokens exactly when its first non-blank byte is not a comment's '#'.
    LineCursor cursor(chunk(c));
    std::string_view line;
    std::uint64_t count = 0;
    while (cursor.next(line)) {
      std::size_t i = 0;
      while (i < line.size() && is_blank(line[i])) ++i;
      if (i < line.size() && line[i] != '#') ++count;
    }
    first_data_line[c + 1] = count;
  });
  for (std::size_t c = 0; c < chunk_count; ++c) first_data_line[c + 1] += first_data_line[c];
  if (first_data_line[chunk_count] != vertex_count + face_count) return std::nullopt;

  IndexedSoup soup;
  soup.positions.resize(vertex_count);
  std::vector<std::vector<std::size_t>> corners(chunk_count);
  std::atomic<bool> plain{true};
  tbb::parallel_for(std::size_t{0}, chunk_count, [&](std::size_t c) {
    LineCursor cursor(chunk(c));
    std::vector<std::string_view> tokens;
    std::string_view line;
    std::uint64_t data_line = first_data_line[c];
    while (plain.load(std::memory_order_relaxed) && cursor.next(line)) {
      tokens_of(line, tokens);
      if (tokens.empty()) continue;
      const std::uint64_t d = data_line++;
      if (d < vertex_count) {
        Vec3& position = soup.positions[d];
        if (tokens.size() < 3 || (tokens.size() > 3 && !extras_allowed) || !parse_double(tokens[0], position.x) ||
            !parse_double(tokens[1], position.y) || !parse_double(tokens[2], position.z) || !is_finite(position)) {
          plain = false;
        }
        continue;
      }
      std::int64_t corner_count = 0;
      if (!parse_integer(tokens[0], corner_count) || corner_count != 3 || tokens.size() < 4) {
        plain = false;
        continue;
      }
      for (std::size_t k = 1; k <= 3; ++k) {
        std::int64_t index = 0;
        if (!parse_integer(tokens[k], index) || index < 0 || static_cast<std::uint64_t>(index) >= vertex_count) {
          plain = false;
          break;
        }
        corners[c].push_back(static_cast<std::size_t>(index));
      }
    }
  });
  if (!plain) return std::nullopt;
  soup.corner_vertices.reserve(3 * face_count);
  for (const std::vector<std::size_t>& part : corners) {
    soup.corner_vertices.insert(soup.corner_vertices.end(), part.begin(), part.end());
  }
  return soup;
}

/// Whether vertex lines carry values beyond x y z (colour, normal, texture).
bool vertex_lines_have_extras(std::string_view keyword, std::size_t line) {
  constexpr std::array<std::string_view, 8> readable = {"OFF",   "COFF",   "NOFF",   "CNOFF",
                                                        "STOFF", "STCOFF", "STNOFF", "STCNOFF"};
  for (const std::string_view variant : readable) {
    if (keyword == variant) return variant != "OFF";
  }
  if (keyword.size() >= 3 && keyword.substr(keyword.size() - 3) == "OFF") {
    refuse("unsupported OFF variant '" + std::string(keyword.substr(0, 40)) + "'" + at_line(line) +
           " (readable: OFF, COFF, NOFF, CNOFF and their ST forms)");
  }
  refuse("not an OFF file: first line must start with 'OFF'" + at_line(line));
}

std::uint64_t parse_count(std::string_view token, const char* what, std::size_t line) {
  std::int64_t count = 0;
  if (!parse_integer(token, count)) refuse(std::string(what) + " count '" + std::string(token.substr(0, 40)) + "' is not an integer" + at_line(line));
  if (count < 0) refuse("negative " + std::string(what) + " count " + std::to_string(count) + at_line(line));
  return static_cast<std::uint64_t>(count);
}

}  // namespace

Mesh read_off(std::string_view bytes, std::vector<std::string>& warnings) {
  // OFF is text: a NUL byte means a binary file, and would cut a quoted token short.
  if (const std::size_t nul = bytes.find('\0'); nul != std::string_view::npos) {
    const std::size_t line = 1 + static_cast<std::size_t>(std::count(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(nul), '\n'));
    refuse("OFF file contains a NUL byte" + at_line(line));
  }
  OffLines lines(bytes);
  std::vector<std::string_view> tokens;
  if (!lines.next(tokens)) refuse("empty OFF file");
  const bool extras_allowed = vertex_lines_have_extras(tokens[0], lines.line_number());

  // The counts may follow the keyword on its line, or have a line of their own.
  std::vector<std::string_view> count_tokens(tokens.begin() + 1, tokens.end());
  if (count_tokens.empty()) {
    if (!lines.next(tokens)) refuse("OFF file ends before the vertex and face counts");
    count_tokens = tokens;
  }
  if (count_tokens.size() != 3) {
    if (count_tokens.size() == 1 && count_tokens[0] == "BINARY") refuse("binary OFF is not supported" + at_line(lines.line_number()));
    refuse("expected 'vertices faces edges' counts" + at_line(lines.line_number()));
  }
  const std::uint64_t vertex_count = parse_count(count_tokens[0], "vertex", lines.line_number());
  const std::uint64_t face_count = parse_count(count_tokens[1], "face", lines.line_number());
  parse_count(count_tokens[2], "edge", lines.line_number());  // unused, but must be well-formed

  if (std::optional<IndexedSoup> soup = read_body_in_parallel(lines.rest(), vertex_count, face_count, extras_allowed)) {
    return weld(std::move(*soup));
  }

  // "0 0 0" is the shortest vertex line, "3 0 0 0" the shortest face line.
  std::vector<Vec3> positions;
  positions.reserve(reserve_bound(vertex_count, bytes.size(), 6));
  for (std::uint64_t vertex = 0; vertex < vertex_count; ++vertex) {
    if (!lines.next(tokens)) {
      refuse("OFF file ends after " + std::to_string(vertex) + " of " + std::to_string(vertex_count) + " vertices");
    }
    const std::size_t line = lines.line_number();
    if (tokens.size() < 3 || (tokens.size() > 3 && !extras_allowed)) {
      refuse("vertex " + std::to_string(vertex) + at_line(line) + " has " + std::to_string(tokens.size()) +
             " values, expected 3");
    }
    Vec3 position;
    double* const coordinates[3] = {&position.x, &position.y, &position.z};
    for (std::size_t axis = 0; axis < 3; ++axis) {
      if (!parse_double(tokens[axis], *coordinates[axis])) {
        // Quoted: "1e999" (beyond double) and "1,5" are refused for different reasons.
        refuse("vertex " + std::to_string(vertex) + at_line(line) + ": coordinate '" +
               std::string(tokens[axis].substr(0, 40)) + "' is not a finite double");
      }
    }
    if (!is_finite(position)) refuse("non-finite coordinate at vertex " + std::to_string(vertex) + at_line(line));
    positions.push_back(position);
  }

  IndexedSoup soup;
  soup.corner_vertices.reserve(3 * reserve_bound(face_count, bytes.size(), 8));
  std::vector<std::size_t> polygon;
  for (std::uint64_t face = 0; face < face_count; ++face) {
    if (!lines.next(tokens)) {
      refuse("OFF file ends after " + std::to_string(face) + " of " + std::to_string(face_count) + " faces");
    }
    // Made only for a message: formatting it for every face cost as much as parsing the face.
    const std::size_t line = lines.line_number();
    const auto where = [&] { return "face " + std::to_string(face) + at_line(line); };
    std::int64_t corner_count = 0;
    if (!parse_integer(tokens[0], corner_count)) refuse(where() + ": vertex count '" + std::string(tokens[0].substr(0, 40)) + "' is not an integer");
    if (corner_count < 3) refuse(where() + " has " + std::to_string(corner_count) + " vertices, at least 3 needed");
    // Values past the indices are the optional face colour.
    if (static_cast<std::uint64_t>(corner_count) > tokens.size() - 1) {
      refuse(where() + " lists " + std::to_string(tokens.size() - 1) + " of its " + std::to_string(corner_count) + " vertex indices");
    }
    polygon.clear();
    for (std::size_t k = 1; k <= static_cast<std::size_t>(corner_count); ++k) {
      std::int64_t index = 0;
      if (!parse_integer(tokens[k], index)) refuse(where() + ": vertex index '" + std::string(tokens[k].substr(0, 40)) + "' is not an integer");
      if (index < 0 || static_cast<std::uint64_t>(index) >= vertex_count) {
        refuse(where() + ": vertex index " + std::to_string(index) + " out of range [0, " + std::to_string(vertex_count) + ")");
      }
      polygon.push_back(static_cast<std::size_t>(index));
    }
    triangulate_polygon(
        polygon.size(), [&](std::size_t k) { return positions[polygon[k]]; },
        [&](std::size_t k) { soup.corner_vertices.push_back(polygon[k]); });
  }
  // Face lines past the header's count (CGAL's prim.off: 8 under a header of 7).
  // The header's count is what the format defines and what other readers take
  // (CGAL, Manifold, MeshLab stop at it), so the mesh read is the one they show;
  // the extra lines are skipped with a warning. Anything else there means the
  // file is not laid out as its header says, and is refused.
  std::size_t extra_faces = 0, first_extra_line = 0;
  while (lines.next(tokens)) {
    const std::size_t line = lines.line_number();
    std::int64_t corner_count = 0;
    bool face_line = parse_integer(tokens[0], corner_count) && corner_count >= 3 &&
                     static_cast<std::uint64_t>(corner_count) <= tokens.size() - 1;
    for (std::size_t k = 1; face_line && k <= static_cast<std::size_t>(corner_count); ++k) {
      std::int64_t index = 0;
      face_line = parse_integer(tokens[k], index) && index >= 0 && static_cast<std::uint64_t>(index) < vertex_count;
    }
    if (!face_line) refuse("unexpected content after the last face" + at_line(line));
    if (extra_faces++ == 0) first_extra_line = line;
  }
  if (extra_faces > 0) {
    warnings.push_back("OFF: " + std::to_string(extra_faces) + (extra_faces == 1 ? " face line" : " face lines") +
                       " after the header's " + std::to_string(face_count) + " faces skipped (from line " +
                       std::to_string(first_extra_line) + "); the header's count is read, as other readers do");
  }
  soup.positions = std::move(positions);
  return weld(std::move(soup));
}

std::string write_off(const Mesh& mesh) {
  // OFF holds no per-corner attributes; they are dropped.
  std::string out = "OFF\n" + std::to_string(mesh.vertex_count()) + ' ' + std::to_string(mesh.triangle_count()) + " 0\n";
  for (const Vec3& position : mesh.positions) {
    append_vec3(out, position);
    out += '\n';
  }
  for (const Triangle& triangle : mesh.triangles) {
    out += "3 " + std::to_string(triangle[0]) + ' ' + std::to_string(triangle[1]) + ' ' + std::to_string(triangle[2]) + '\n';
  }
  return out;
}

}  // namespace shatter::io_detail
