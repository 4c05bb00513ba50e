#pragma once
// Helpers shared by the mesh readers and writers; private to the kernel.

#include <array>
#include <charconv>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/fp_environment.hpp"
#include "shatter/kernel/mesh.hpp"

namespace shatter::io_detail {

/// What every reader produces before welding: triangles as three corner
/// positions each, with per-corner attributes in the layout of the final mesh.
/// Keeping positions per corner lets one welding rule serve all formats, whether
/// the file was indexed (OFF, OBJ, PLY) or not (STL).
struct TriangleSoup {
  std::vector<Vec3> corner_positions;  ///< corner c of triangle t at 3*t + c
  CornerAttributes corners;

  std::size_t triangle_count() const { return corner_positions.size() / 3; }
};

/// Merges corners whose positions are equal as numbers (so -0.0 and +0.0 merge,
/// and nothing merges within a tolerance), numbering vertices by first use.
/// Every triangle gets original_surface. A soup without triangles is refused:
/// no shatter operation has anything to do with it. Positions must be finite: the readers
/// refuse non-finite coordinates where they can still name the vertex.
Mesh weld(TriangleSoup soup);

/// A soup whose corners index a file's own vertex list (OFF, PLY and OBJ
/// faces do): corner c of triangle t is vertex corner_vertices[3t + c] of
/// `positions`. Indices are in range (the readers refuse others).
struct IndexedSoup {
  std::vector<Vec3> positions;  ///< the file's vertices, in its order
  std::vector<std::size_t> corner_vertices;
  CornerAttributes corners;

  std::size_t triangle_count() const { return corner_vertices.size() / 3; }
};

/// weld of the TriangleSoup whose corner c lies at positions[corner_vertices[c]]:
/// the same mesh to the bit (vertices numbered by first use, each keeping the
/// bits of its first corner, the same refusals), looking each file vertex up
/// once instead of each corner, and without copying a position per corner.
Mesh weld(IndexedSoup soup);

/// The corners (a, b, c) of each triangle of a polygon over `corners` (its
/// positions, in the file's order), each triangle in the polygon's orientation.
/// The fan (0, 1, 2), (0, 2, 3), ... whenever every fan triangle turns the way
/// the polygon does in its projection (every convex polygon, and every polygon
/// star-shaped from its first corner): what the readers have always made, so
/// their meshes stay as they were. Otherwise (a non-convex polygon whose fan
/// folds over itself or has a zero-area triangle: CGAL's mpi.off, 23 of whose 52
/// polygons are not convex, 22 fans unsound, reading as 141 pairs of intersecting
/// and 2 zero-area triangles) ear clipping in the projection along the
/// largest component of the polygon's Newell normal: an ear is a corner turning
/// the polygon's way with no other corner inside or on its triangle, all decided
/// by exact orient2d. Where no ear is left (a polygon not simple in projection)
/// the rest is fanned; above `kMaxClippedCorners` corners the fan is kept (ear
/// clipping is cubic). The projection axis is chosen in doubles; it only picks
/// among triangulations, and validation decides the mesh.
std::vector<std::array<std::size_t, 3>> polygon_triangles(const std::vector<Vec3>& corners);
inline constexpr std::size_t kMaxClippedCorners = 256;

/// Calls emit(k) for the corners k of each triangle polygon_triangles makes of
/// the polygon with `corner_count` corners, position(k) giving corner k's
/// position. A triangle goes as is, with no allocation.
template <class Position, class EmitCorner>
void triangulate_polygon(std::size_t corner_count, Position&& position, EmitCorner&& emit) {
  if (corner_count == 3) {
    emit(std::size_t{0});
    emit(std::size_t{1});
    emit(std::size_t{2});
    return;
  }
  std::vector<Vec3> corners(corner_count);
  for (std::size_t k = 0; k < corner_count; ++k) corners[k] = position(k);
  for (const auto& [a, b, c] : polygon_triangles(corners)) {
    emit(a);
    emit(b);
    emit(c);
  }
}

[[noreturn]] inline void refuse(const std::string& message) { throw InvalidMeshError(message); }

/// Reads a whole token as a double: correctly rounded, so printing with
/// append_shortest and reading back is exact. Accepts a leading '+', which
/// std::from_chars does not; "nan" and "inf" parse, for the caller to refuse
/// with the vertex named. A decimal beyond the double range rounds as any
/// decimal does: past the largest double to infinity (so "1e999" is refused as
/// a non-finite coordinate, like "inf"), below the smallest to a subnormal or
/// zero. Fails on anything that is not a decimal number.
inline bool parse_double(std::string_view token, double& value) {
  if (token.size() > 1 && token.front() == '+' && token[1] != '-') token.remove_prefix(1);
  const char* const end = token.data() + token.size();
  const auto [stop, error] = std::from_chars(token.data(), end, value);
  if (stop != end) return false;
  if (error == std::errc::result_out_of_range) {
    // from_chars leaves `value` untouched here; glibc's strtod rounds correctly
    // (to infinity, a subnormal or zero). The token is ASCII digits, a point and
    // an exponent, which every locale's strtod reads alike except for the point:
    // shatter never calls setlocale, so it is the C locale's '.'. Rounding to
    // infinity signals overflow, as it should: held, so a trapping program
    // reads "1e999" as every other one does (and refuses it as non-finite).
    const HeldFloatingPointEnvironment held;
    value = std::strtod(std::string(token).c_str(), nullptr);
    return true;
  }
  return error == std::errc{};
}

/// Reads a whole token as an integer of type Integer, failing on overflow.
template <class Integer>
bool parse_integer(std::string_view token, Integer& value) {
  if (token.size() > 1 && token.front() == '+' && token[1] != '-') token.remove_prefix(1);
  const char* const end = token.data() + token.size();
  const auto [stop, error] = std::from_chars(token.data(), end, value);
  return error == std::errc{} && stop == end;
}

/// Appends the shortest decimal that reads back as exactly `value`.
inline void append_shortest(std::string& out, double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.append(buffer, result.ptr);
}

inline void append_vec3(std::string& out, Vec3 value) {
  append_shortest(out, value.x);
  out += ' ';
  append_shortest(out, value.y);
  out += ' ';
  append_shortest(out, value.z);
}

inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// Splits a line into whitespace-separated tokens.
inline void split_tokens(std::string_view line, std::vector<std::string_view>& tokens) {
  tokens.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_blank(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !is_blank(line[i])) ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
}

/// Walks text line by line ('\n' ends a line; a trailing '\r' is whitespace),
/// counting lines from 1 for error messages.
class LineCursor {
 public:
  explicit LineCursor(std::string_view text) : text_(text) {}

  bool next(std::string_view& line) {
    if (position_ >= text_.size()) return false;
    const std::size_t end = text_.find('\n', position_);
    const std::size_t stop = end == std::string_view::npos ? text_.size() : end;
    line = text_.substr(position_, stop - position_);
    position_ = stop == text_.size() ? stop : stop + 1;
    ++line_number_;
    return true;
  }
  std::size_t line_number() const { return line_number_; }
  /// Bytes not yet returned as lines.
  std::string_view rest() const { return text_.substr(position_); }

 private:
  std::string_view text_;
  std::size_t position_ = 0;
  std::size_t line_number_ = 0;
};

/// Walks whitespace-separated tokens across lines, for formats (PLY ascii, STL
/// ascii) where line breaks carry no meaning; remembers the line of the last
/// token for error messages.
class TokenCursor {
 public:
  explicit TokenCursor(std::string_view text, std::size_t first_line = 1)
      : text_(text), line_number_(first_line) {}

  /// The next token, or an empty view at the end of the text.
  std::string_view next() {
    skip_space();
    const std::size_t start = position_;
    while (position_ < text_.size() && !is_blank(text_[position_]) && text_[position_] != '\n') ++position_;
    return text_.substr(start, position_ - start);
  }
  bool at_end() {
    skip_space();
    return position_ >= text_.size();
  }
  std::size_t line_number() const { return line_number_; }
  /// The text from the current position to the end of its line, consumed.
  std::string_view rest_of_line() {
    const std::size_t end = text_.find('\n', position_);
    const std::size_t stop = end == std::string_view::npos ? text_.size() : end;
    const std::string_view rest = text_.substr(position_, stop - position_);
    position_ = stop;
    return rest;
  }

 private:
  void skip_space() {
    while (position_ < text_.size() && (is_blank(text_[position_]) || text_[position_] == '\n')) {
      if (text_[position_] == '\n') ++line_number_;
      ++position_;
    }
  }

  std::string_view text_;
  std::size_t position_ = 0;
  std::size_t line_number_;
};

/// A reserve() bound that a hostile header count cannot inflate: no more
/// elements than the bytes could hold at `minimum_bytes_each` bytes apiece.
inline std::size_t reserve_bound(std::uint64_t claimed, std::size_t byte_count, std::size_t minimum_bytes_each) {
  const std::uint64_t possible = byte_count / minimum_bytes_each + 1;
  return static_cast<std::size_t>(claimed < possible ? claimed : possible);
}

// The readers that may take a liberty append one line per liberty to `warnings`
// (io.hpp says which).
Mesh read_off(std::string_view bytes, std::vector<std::string>& warnings);
Mesh read_obj(std::string_view bytes, std::vector<std::string>& warnings);
Mesh read_ply(std::string_view bytes, std::vector<std::string>& warnings);
Mesh read_stl(std::string_view bytes, std::vector<std::string>& warnings);

std::string write_off(const Mesh& mesh);
std::string write_obj(const Mesh& mesh);
std::string write_ply(const Mesh& mesh);
std::string write_stl(const Mesh& mesh);

}  // namespace shatter::io_detail
