// STL, binary and ascii. A file is binary exactly when its size is 84 + 50 n for
// the facet count n stored at byte 80: binary headers often begin with "solid"
// too, so that prefix decides nothing. Facet normals in the file are ignored;
// the geometry defines orientation. STL holds no attributes. An ascii file may
// hold several solids (one mesh of all of them, with a warning).
//
// The writer emits ascii, whose shortest round-trip decimals keep every double
// (binary STL would round positions to float).

#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <string>
#include <vector>

#include "io_internal.hpp"

namespace shatter::io_detail {

namespace {

constexpr std::size_t binary_header_size = 84;
constexpr std::size_t binary_facet_size = 50;

bool is_binary_stl(std::string_view bytes) {
  if (bytes.size() < binary_header_size) return false;
  std::array<unsigned char, 4> raw;
  std::memcpy(raw.data(), bytes.data() + 80, 4);
  const std::uint64_t facet_count = std::uint64_t{raw[0]} | std::uint64_t{raw[1]} << 8 | std::uint64_t{raw[2]} << 16 |
                                    std::uint64_t{raw[3]} << 24;
  return bytes.size() == binary_header_size + binary_facet_size * facet_count;
}

float little_endian_float(const char* data) {
  std::array<unsigned char, 4> raw;
  std::memcpy(raw.data(), data, 4);
  const std::uint32_t bits = std::uint32_t{raw[0]} | std::uint32_t{raw[1]} << 8 | std::uint32_t{raw[2]} << 16 |
                             std::uint32_t{raw[3]} << 24;
  return std::bit_cast<float>(bits);
}

Mesh read_binary(std::string_view bytes) {
  const std::size_t facet_count = (bytes.size() - binary_header_size) / binary_facet_size;
  TriangleSoup soup;
  soup.corner_positions.reserve(3 * facet_count);
  for (std::size_t facet = 0; facet < facet_count; ++facet) {
    // Skip the stored normal (12 bytes); the 2-byte attribute follows the corners.
    const char* corner = bytes.data() + binary_header_size + binary_facet_size * facet + 12;
    for (int k = 0; k < 3; ++k, corner += 12) {
      const Vec3 position{little_endian_float(corner), little_endian_float(corner + 4), little_endian_float(corner + 8)};
      if (!is_finite(position)) refuse("non-finite coordinate at STL facet " + std::to_string(facet));
      soup.corner_positions.push_back(position);
    }
  }
  return weld(std::move(soup));
}

std::string describe(std::string_view token) {
  if (token.empty()) return "end of file";
  std::string quoted = "'";
  quoted.append(token.substr(0, 40));
  quoted += '\'';
  return quoted;
}

/// Token-level reader of ascii STL, naming the line of every defect.
class AsciiStl {
 public:
  explicit AsciiStl(std::string_view bytes) : tokens_(bytes) {}

  void expect(std::string_view keyword) {
    const std::string_view token = tokens_.next();
    if (token != keyword) {
      refuse("STL: expected '" + std::string(keyword) + "', found " + describe(token) + at_line());
    }
  }
  /// The next token as a double; `element` (" facet 3") says whose it is.
  double number(const std::string& element = "") {
    const std::string_view token = tokens_.next();
    double value = 0;
    if (!parse_double(token, value)) refuse("STL" + element + ": expected a finite double, found " + describe(token) + at_line());
    return value;
  }
  std::string_view next() { return tokens_.next(); }
  void skip_rest_of_line() { tokens_.rest_of_line(); }
  bool at_end() { return tokens_.at_end(); }
  std::string at_line() const { return " at line " + std::to_string(tokens_.line_number()); }

 private:
  TokenCursor tokens_;
};

Mesh read_ascii(std::string_view bytes, std::vector<std::string>& warnings) {
  // Ascii STL is text: a NUL byte means a binary file of the wrong size (or
  // garbage), and would cut a token quoted in a message short.
  if (bytes.find('\0') != std::string_view::npos) {
    refuse("not an STL file: its size is not 84 + 50 n (binary) and it holds a NUL byte (so is not ascii)");
  }
  AsciiStl stl(bytes);
  if (const std::string_view first = stl.next(); first != "solid") {
    refuse("not an STL file: its size is not 84 + 50 n (binary) and it does not start with 'solid' (ascii), found " +
           describe(first));
  }
  // Exporters that write one block per part or per material (and files
  // concatenated with cat) hold several solids: the mesh is all of them, and
  // facets are numbered across the blocks in messages.
  TriangleSoup soup;
  std::size_t facet = 0, solids = 0;
  while (true) {
    stl.skip_rest_of_line();  // the solid's name
    ++solids;
    for (;; ++facet) {
      const std::string_view keyword = stl.next();
      if (keyword == "endsolid") break;
      if (keyword != "facet") {
        refuse("STL: expected 'facet' or 'endsolid', found " + describe(keyword) + stl.at_line());
      }
      stl.expect("normal");
      for (int k = 0; k < 3; ++k) stl.number();
      stl.expect("outer");
      stl.expect("loop");
      std::array<Vec3, 3> corners;
      for (Vec3& corner : corners) {
        stl.expect("vertex");
        const std::string element = " facet " + std::to_string(facet);
        corner.x = stl.number(element);
        corner.y = stl.number(element);
        corner.z = stl.number(element);
        if (!is_finite(corner)) refuse("non-finite coordinate at STL facet " + std::to_string(facet) + stl.at_line());
      }
      stl.expect("endloop");
      stl.expect("endfacet");
      soup.corner_positions.insert(soup.corner_positions.end(), corners.begin(), corners.end());
    }
    stl.skip_rest_of_line();  // the solid's name again
    if (stl.at_end()) break;
    if (const std::string_view next = stl.next(); next != "solid") {
      refuse("STL: expected 'solid' or the end of the file after 'endsolid', found " + describe(next) + stl.at_line());
    }
  }
  if (solids > 1) {
    warnings.push_back("STL: " + std::to_string(solids) + " solids ('solid ... endsolid' blocks) read as one mesh");
  }
  return weld(std::move(soup));
}

}  // namespace

Mesh read_stl(std::string_view bytes, std::vector<std::string>& warnings) {
  if (is_binary_stl(bytes)) return read_binary(bytes);
  return read_ascii(bytes, warnings);
}

std::string write_stl(const Mesh& mesh) {
  std::string out = "solid shatter\n";
  for (const Triangle& triangle : mesh.triangles) {
    const Vec3 a = mesh.positions[triangle[0]], b = mesh.positions[triangle[1]], c = mesh.positions[triangle[2]];
    out += "facet normal ";
    Vec3 normal;
    {
      // Facet normals are informational (readers, shatter's included, go by the
      // corners). A triangle with no area, or whose cross product passes the
      // double range (coordinates near its end), gets the non-finite normal the
      // arithmetic gives, as it always has: held, so a trapping program writes
      // the same bytes.
      const HeldFloatingPointEnvironment held;
      normal = normalized(cross(b - a, c - a));
    }
    append_vec3(out, normal);
    out += "\nouter loop\n";
    for (const Vec3& corner : {a, b, c}) {
      out += "vertex ";
      append_vec3(out, corner);
      out += '\n';
    }
    out += "endloop\nendfacet\n";
  }
  out += "endsolid shatter\n";
  return out;
}

}  // namespace shatter::io_detail
