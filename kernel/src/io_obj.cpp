// Wavefront OBJ: positions (v), texture coordinates (vt), normals (vn) and
// polygons (f) with 1-based or negative (relative) indices in the forms i, i/j,
// i//k and i/j/k. Everything else (groups, materials, lines, points) is ignored.
//
// tinyobjloader resolves the face index triples. It is lenient where shatter
// must not be: its number parser is not correctly rounded (it sums digit * 0.1^k)
// and silently reads garbage as 0, atoi accepts "1x", and it drops faces with
// fewer than 3 vertices with only a warning. So a first pass over the lines
// checks every v/vt/vn/f line and reads the numbers itself with std::from_chars
// (exact, so written files read back bit for bit); tinyobjloader's own
// coordinate values are never used.
//
// Attributes are all or nothing per channel: when every face corner has a
// texture coordinate (or a normal), the mesh carries that channel per corner;
// when only some do, the channel is dropped with a warning naming the first
// face without one (a mesh has a channel on all its corners or on none, and
// inventing values for the rest would be a guess).

#include <tiny_obj_loader.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "io_internal.hpp"

namespace shatter::io_detail {

namespace {

std::string at_line(std::size_t line) { return " at line " + std::to_string(line); }

/// What the first pass learns from the file.
struct ObjContent {
  std::vector<Vec3> positions;
  std::vector<Vec2> uvs;
  std::vector<Vec3> normals;
  struct Face {
    std::size_t line;
    std::size_t corner_count;
  };
  std::vector<Face> faces;
  /// Per face corner, in file order: whether it names a texture coordinate, a normal.
  std::vector<bool> corner_has_uv, corner_has_normal;
};

/// The parts of a face corner "i", "i/j", "i//k" or "i/j/k"; valid only if
/// every present index is nonzero and fits the int tinyobjloader stores it in.
struct CornerForm {
  bool valid = false;
  bool has_uv = false;
  bool has_normal = false;
};

CornerForm parse_corner_form(std::string_view token) {
  std::array<std::string_view, 3> parts;
  std::size_t part_count = 0;
  while (true) {
    if (part_count == parts.size()) return {};
    const std::size_t slash = token.find('/');
    parts[part_count++] = token.substr(0, slash);
    if (slash == std::string_view::npos) break;
    token.remove_prefix(slash + 1);
  }
  for (std::size_t k = 0; k < part_count; ++k) {
    const bool may_be_empty = k == 1 && part_count == 3;  // the j of i//k
    int index = 0;
    if (parts[k].empty() && may_be_empty) continue;
    if (!parse_integer(parts[k], index) || index == 0) return {};
  }
  return {true, part_count >= 2 && !parts[1].empty(), part_count == 3};
}

template <std::size_t N>
void parse_numbers(const std::vector<std::string_view>& tokens, std::array<double, N>& values, std::size_t count,
                   const std::string& what) {
  for (std::size_t k = 0; k < count && k < N; ++k) {
    if (!parse_double(tokens[k + 1], values[k])) refuse(what + ": '" + std::string(tokens[k + 1].substr(0, 40)) + "' is not a finite double");
  }
}

ObjContent scan_lines(std::string_view bytes) {
  ObjContent content;
  if (bytes.find('\0') != std::string_view::npos) refuse("OBJ file contains a NUL byte");
  LineCursor lines(bytes);
  std::string_view line;
  std::vector<std::string_view> tokens;
  while (lines.next(line)) {
    const std::size_t line_number = lines.line_number();
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    // tinyobjloader also ends lines at a lone '\r'; refusing it keeps both passes on the same lines.
    if (line.find('\r') != std::string_view::npos) refuse("stray carriage return" + at_line(line_number));
    if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    split_tokens(line, tokens);
    if (tokens.empty()) continue;
    const std::string_view keyword = tokens[0];
    const std::size_t value_count = tokens.size() - 1;
    if (keyword == "v") {
      const std::string what = "vertex " + std::to_string(content.positions.size() + 1) + at_line(line_number);
      // x y z, then an optional weight or colour, which are not kept.
      if (value_count < 3 || value_count > 7) refuse(what + " has " + std::to_string(value_count) + " values, expected 3");
      std::array<double, 7> values{};
      parse_numbers(tokens, values, value_count, what);
      const Vec3 position{values[0], values[1], values[2]};
      if (!is_finite(position)) refuse("non-finite coordinate at " + what);
      content.positions.push_back(position);
    } else if (keyword == "vt") {
      const std::string what = "texture coordinate " + std::to_string(content.uvs.size() + 1) + at_line(line_number);
      if (value_count < 1 || value_count > 3) refuse(what + " has " + std::to_string(value_count) + " values, expected 1 to 3");
      std::array<double, 3> values{};
      parse_numbers(tokens, values, value_count, what);
      content.uvs.push_back({values[0], values[1]});
    } else if (keyword == "vn") {
      const std::string what = "normal " + std::to_string(content.normals.size() + 1) + at_line(line_number);
      if (value_count != 3) refuse(what + " has " + std::to_string(value_count) + " values, expected 3");
      std::array<double, 3> values{};
      parse_numbers(tokens, values, value_count, what);
      content.normals.push_back({values[0], values[1], values[2]});
    } else if (keyword == "f") {
      const std::string what = "face " + std::to_string(content.faces.size() + 1) + at_line(line_number);
      if (value_count < 3) refuse(what + " has " + std::to_string(value_count) + " vertices, at least 3 needed");
      for (std::size_t k = 1; k < tokens.size(); ++k) {
        const CornerForm form = parse_corner_form(tokens[k]);
        if (!form.valid) refuse(what + ": '" + std::string(tokens[k].substr(0, 40)) + "' is not a vertex reference");
        content.corner_has_uv.push_back(form.has_uv);
        content.corner_has_normal.push_back(form.has_normal);
      }
      content.faces.push_back({line_number, value_count});
    }
  }
  return content;
}

std::string face_name(const ObjContent& content, std::size_t face_number) {
  return "face " + std::to_string(face_number + 1) + at_line(content.faces[face_number].line);
}

/// Refuses a corner reference out of range (a negative index reaching before
/// the first element resolves below zero).
void check_range(int index, std::size_t count, const char* what, const ObjContent& content, std::size_t face_number) {
  if (index < 0 || static_cast<std::size_t>(index) >= count) {
    refuse(face_name(content, face_number) + ": " + what + " index out of range: refers to a " + what +
           " that does not exist (the file has " + std::to_string(count) + ")");
  }
}

/// Whether any corner has the attribute; then every corner must have it.
// Whether the mesh keeps a channel: every corner has a value. When only some
// corners do, the channel is dropped and `warnings` says so.
bool channel_present(const std::vector<bool>& corner_has, const ObjContent& content, const char* what,
                     std::vector<std::string>& warnings) {
  const std::size_t with = static_cast<std::size_t>(std::count(corner_has.begin(), corner_has.end(), true));
  if (with == 0) return false;
  if (with == corner_has.size()) return true;
  std::size_t corner = 0;
  std::string first_without;
  for (std::size_t face_number = 0; face_number < content.faces.size() && first_without.empty(); ++face_number) {
    for (std::size_t k = 0; k < content.faces[face_number].corner_count; ++k, ++corner) {
      if (!corner_has[corner]) {
        first_without = face_name(content, face_number);
        break;
      }
    }
  }
  warnings.push_back("OBJ: " + std::to_string(corner_has.size() - with) + " of " + std::to_string(corner_has.size()) +
                     " face corners have no " + what + " (the first: " + first_without + "): every " + what +
                     " dropped");
  return false;
}

}  // namespace

Mesh read_obj(std::string_view bytes, std::vector<std::string>& warnings) {
  ObjContent content = scan_lines(bytes);  // its positions move into the soup at the end

  tinyobj::ObjReaderConfig config;
  config.triangulate = false;  // fanned below, identically to the other formats
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  bool parsed = false;
  {
    // tinyobjloader's number parser scales by ldexp and overflows on exponents
    // past the double range; its values are discarded (the first pass read them),
    // so the flag means nothing here and is held.
    const HeldFloatingPointEnvironment held;
    parsed = reader.ParseFromString(std::string(bytes), std::string(), config);
  }
  if (!parsed) {
    std::string message = reader.Error();
    if (const std::size_t newline = message.find('\n'); newline != std::string::npos) message.resize(newline);
    refuse("OBJ: " + message);
  }

  std::vector<tinyobj::index_t> references;
  for (const tinyobj::shape_t& shape : reader.GetShapes()) {
    references.insert(references.end(), shape.mesh.indices.begin(), shape.mesh.indices.end());
  }
  std::size_t corner_total = 0;
  for (const ObjContent::Face& face : content.faces) corner_total += face.corner_count;
  if (references.size() != corner_total || reader.GetAttrib().vertices.size() != 3 * content.positions.size()) {
    refuse("OBJ: tinyobjloader and the line scan disagree on the file's faces");
  }

  const bool wants_uvs = channel_present(content.corner_has_uv, content, "texture coordinate", warnings);
  const bool wants_normals = channel_present(content.corner_has_normal, content, "normal", warnings);

  IndexedSoup soup;
  std::size_t first_corner = 0;
  for (std::size_t face_number = 0; face_number < content.faces.size(); ++face_number) {
    const ObjContent::Face& face = content.faces[face_number];
    const tinyobj::index_t* corners = references.data() + first_corner;
    for (std::size_t k = 0; k < face.corner_count; ++k) {
      // A reference is checked even in a channel that is dropped: a file that
      // names a texture coordinate it lacks is broken, not merely incomplete.
      check_range(corners[k].vertex_index, content.positions.size(), "vertex", content, face_number);
      if (content.corner_has_uv[first_corner + k]) {
        check_range(corners[k].texcoord_index, content.uvs.size(), "texture coordinate", content, face_number);
      }
      if (content.corner_has_normal[first_corner + k]) {
        check_range(corners[k].normal_index, content.normals.size(), "normal", content, face_number);
      }
    }
    first_corner += face.corner_count;
    triangulate_polygon(
        face.corner_count,
        [&](std::size_t k) { return content.positions[static_cast<std::size_t>(corners[k].vertex_index)]; },
        [&](std::size_t k) {
      soup.corner_vertices.push_back(static_cast<std::size_t>(corners[k].vertex_index));
      if (wants_uvs) soup.corners.uvs.push_back(content.uvs[static_cast<std::size_t>(corners[k].texcoord_index)]);
      if (wants_normals) soup.corners.normals.push_back(content.normals[static_cast<std::size_t>(corners[k].normal_index)]);
    });
  }
  soup.positions = std::move(content.positions);
  return weld(std::move(soup));
}

namespace {

/// Numbers distinct attribute values by first use, comparing bit patterns so
/// that every value, -0.0 included, reads back exactly as stored.
template <class Value>
class ValueTable {
 public:
  /// The 1-based OBJ index of `value`, added if new.
  std::size_t index_of(const Value& value, std::string& lines, std::string_view keyword) {
    const auto key = bits_of(value);
    const auto [entry, inserted] = index_.try_emplace(key, index_.size() + 1);
    if (inserted) {
      lines += keyword;
      append_values(lines, value);
      lines += '\n';
    }
    return entry->second;
  }

 private:
  static std::array<std::uint64_t, 3> bits_of(Vec2 v) {
    return {std::bit_cast<std::uint64_t>(v.x), std::bit_cast<std::uint64_t>(v.y), 0};
  }
  static std::array<std::uint64_t, 3> bits_of(Vec3 v) {
    return {std::bit_cast<std::uint64_t>(v.x), std::bit_cast<std::uint64_t>(v.y), std::bit_cast<std::uint64_t>(v.z)};
  }
  static void append_values(std::string& out, Vec2 v) {
    out += ' ';
    append_shortest(out, v.x);
    out += ' ';
    append_shortest(out, v.y);
  }
  static void append_values(std::string& out, Vec3 v) {
    out += ' ';
    append_vec3(out, v);
  }

  std::map<std::array<std::uint64_t, 3>, std::size_t> index_;
};

}  // namespace

std::string write_obj(const Mesh& mesh) {
  // OBJ has no tangents; they are dropped. Attribute lines are written once per
  // distinct value, in order of first use, so the output is small and stable.
  std::string out = "# shatter\n";
  for (const Vec3& position : mesh.positions) {
    out += "v ";
    append_vec3(out, position);
    out += '\n';
  }
  const bool with_uvs = mesh.corners.has_uvs(), with_normals = mesh.corners.has_normals();
  ValueTable<Vec2> uv_table;
  ValueTable<Vec3> normal_table;
  std::string attribute_lines, face_lines;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    face_lines += 'f';
    for (std::size_t c = 0; c < 3; ++c) {
      face_lines += ' ';
      face_lines += std::to_string(std::size_t{mesh.triangles[t][c]} + 1);
      if (!with_uvs && !with_normals) continue;
      face_lines += '/';
      if (with_uvs) face_lines += std::to_string(uv_table.index_of(mesh.corners.uvs[3 * t + c], attribute_lines, "vt"));
      if (with_normals) {
        face_lines += '/';
        face_lines += std::to_string(normal_table.index_of(mesh.corners.normals[3 * t + c], attribute_lines, "vn"));
      }
    }
    face_lines += '\n';
  }
  return out + attribute_lines + face_lines;
}

}  // namespace shatter::io_detail
