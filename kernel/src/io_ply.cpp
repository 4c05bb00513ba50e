// PLY, ascii and binary (either byte order). From the "vertex" element: x, y, z
// of any numeric type, and optionally nx, ny, nz and a texture coordinate pair
// (u, v), (s, t) or (texture_u, texture_v); from the "face" element: the list
// "vertex_indices" (or "vertex_index") with any count and index types. Other
// properties and elements are read past. PLY attributes are per vertex; each
// corner takes its vertex's value. A header line that starts with no keyword is
// skipped with a warning (io.hpp).
//
// The writer emits binary little-endian positions (double) and triangles only:
// PLY cannot hold shatter's per-corner attributes without splitting vertices,
// which would break the welded topology, so attributes are dropped.

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "io_internal.hpp"

namespace shatter::io_detail {

namespace {

enum class Encoding { ascii, little_endian, big_endian };

enum class ScalarType { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

std::optional<ScalarType> scalar_type_named(std::string_view name) {
  struct Alias {
    std::string_view name;
    ScalarType type;
  };
  constexpr std::array<Alias, 16> aliases = {{{"char", ScalarType::int8},     {"int8", ScalarType::int8},
                                              {"uchar", ScalarType::uint8},   {"uint8", ScalarType::uint8},
                                              {"short", ScalarType::int16},   {"int16", ScalarType::int16},
                                              {"ushort", ScalarType::uint16}, {"uint16", ScalarType::uint16},
                                              {"int", ScalarType::int32},     {"int32", ScalarType::int32},
                                              {"uint", ScalarType::uint32},   {"uint32", ScalarType::uint32},
                                              {"float", ScalarType::float32}, {"float32", ScalarType::float32},
                                              {"double", ScalarType::float64}, {"float64", ScalarType::float64}}};
  for (const Alias& alias : aliases) {
    if (alias.name == name) return alias.type;
  }
  return std::nullopt;
}

std::size_t size_of(ScalarType type) {
  switch (type) {
    case ScalarType::int8:
    case ScalarType::uint8: return 1;
    case ScalarType::int16:
    case ScalarType::uint16: return 2;
    case ScalarType::int32:
    case ScalarType::uint32:
    case ScalarType::float32: return 4;
    case ScalarType::float64: return 8;
  }
  return 8;
}

bool is_integral(ScalarType type) { return type != ScalarType::float32 && type != ScalarType::float64; }

struct Property {
  std::string name;
  ScalarType type;                      ///< the item type of a list
  std::optional<ScalarType> list_count; ///< set for list properties
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
};

struct Header {
  Encoding encoding = Encoding::ascii;
  std::vector<Element> elements;
  std::size_t body_offset = 0;  ///< first byte after "end_header\n"
  std::size_t line_count = 0;   ///< lines in the header, for ascii line numbers
};

std::string at_line(std::size_t line) { return " at line " + std::to_string(line); }

Header parse_header(std::string_view bytes, std::vector<std::string>& warnings) {
  LineCursor lines(bytes);
  std::string_view line;
  std::vector<std::string_view> tokens;
  if (!lines.next(line) || (line != "ply" && line != "ply\r")) refuse("not a PLY file: first line must be 'ply'");
  Header header;
  bool has_format = false;
  while (true) {
    if (!lines.next(line)) refuse("PLY header has no 'end_header'");
    const std::size_t line_number = lines.line_number();
    // A NUL would cut a quoted token short in a message; the header is text.
    if (line.find('\0') != std::string_view::npos) refuse("PLY header contains a NUL byte" + at_line(line_number));
    split_tokens(line, tokens);
    if (tokens.empty()) continue;
    const std::string_view keyword = tokens[0];
    if (keyword == "end_header") break;
    if (keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "format") {
      if (tokens.size() != 3 || tokens[2] != "1.0") refuse("PLY format line must be 'format <encoding> 1.0'" + at_line(line_number));
      if (tokens[1] == "ascii") {
        header.encoding = Encoding::ascii;
      } else if (tokens[1] == "binary_little_endian") {
        header.encoding = Encoding::little_endian;
      } else if (tokens[1] == "binary_big_endian") {
        header.encoding = Encoding::big_endian;
      } else {
        refuse("unknown PLY encoding '" + std::string(tokens[1].substr(0, 40)) + "'" + at_line(line_number));
      }
      has_format = true;
    } else if (keyword == "element") {
      if (tokens.size() != 3) refuse("PLY element line must be 'element <name> <count>'" + at_line(line_number));
      Element element;
      element.name = tokens[1];
      if (!parse_integer(tokens[2], element.count)) {
        refuse("PLY element count '" + std::string(tokens[2].substr(0, 40)) + "' is not a non-negative integer" + at_line(line_number));
      }
      header.elements.push_back(std::move(element));
    } else if (keyword == "property") {
      if (header.elements.empty()) refuse("PLY property before any element" + at_line(line_number));
      Property property;
      const bool is_list = tokens.size() == 5 && tokens[1] == "list";
      if (!is_list && tokens.size() != 3) refuse("malformed PLY property line" + at_line(line_number));
      const std::string_view type_name = tokens[is_list ? 3 : 1];
      const std::optional<ScalarType> type = scalar_type_named(type_name);
      if (!type) refuse("unknown PLY type '" + std::string(type_name.substr(0, 40)) + "'" + at_line(line_number));
      property.type = *type;
      if (is_list) {
        property.list_count = scalar_type_named(tokens[2]);
        if (!property.list_count || !is_integral(*property.list_count)) {
          refuse("PLY list count type '" + std::string(tokens[2].substr(0, 40)) + "' is not an integer type" + at_line(line_number));
        }
      }
      property.name = tokens[is_list ? 4 : 2];
      header.elements.back().properties.push_back(std::move(property));
    } else {
      // Not a keyword: a remark some exporter wrote without "comment" (old
      // Blender exporters wrote "Created by Blender3D 247 - www.blender.org, ...").
      // It declares nothing, so skipping it cannot change what the body means; a
      // mistyped keyword shows up as the element or property it failed to declare.
      std::string quoted(line.substr(0, 60));
      if (!quoted.empty() && quoted.back() == '\r') quoted.pop_back();
      warnings.push_back("PLY: header line " + std::to_string(line_number) + " starts with no PLY keyword, skipped: '" +
                         quoted + (line.size() > 60 ? "...'" : "'"));
    }
  }
  if (!has_format) refuse("PLY header has no format line");
  header.body_offset = bytes.size() - lines.rest().size();
  header.line_count = lines.line_number();
  return header;
}

/// Reads property values one at a time from the body, in either encoding.
/// Integers come back exactly (as double, which holds every 32-bit value).
class ValueReader {
 public:
  ValueReader(std::string_view body, Encoding encoding, std::size_t header_lines)
      : body_(body), encoding_(encoding), tokens_(body, header_lines + 1) {}

  /// The next value, or nullopt if the body ends or the value is malformed.
  std::optional<double> next(ScalarType type) {
    if (encoding_ == Encoding::ascii) return next_text(type);
    return next_binary(type);
  }

  /// Where the reader is, for error messages.
  std::string location(const Element& element, std::uint64_t index) const {
    std::string where = element.name + " " + std::to_string(index);
    if (encoding_ == Encoding::ascii) where += at_line(tokens_.line_number());
    return where;
  }

  bool at_end() {
    if (encoding_ == Encoding::ascii) return tokens_.at_end();
    return position_ == body_.size();
  }

  /// Why the last next() gave nullopt: the value is missing, or (ascii) its text.
  std::string failure() const {
    if (encoding_ != Encoding::ascii || last_token_.empty()) return "is missing (the file ends)";
    return "has malformed value '" + std::string(last_token_.substr(0, 40)) + "'";
  }

 private:
  std::optional<double> next_text(ScalarType type) {
    const std::string_view token = tokens_.next();
    last_token_ = token;
    if (is_integral(type)) {
      std::int64_t value = 0;
      if (!parse_integer(token, value) || !fits(value, type)) return std::nullopt;
      return static_cast<double>(value);
    }
    double value = 0;
    if (!parse_double(token, value)) return std::nullopt;
    return value;
  }

  static bool fits(std::int64_t value, ScalarType type) {
    const unsigned bits = static_cast<unsigned>(8 * size_of(type));
    const bool is_signed = type == ScalarType::int8 || type == ScalarType::int16 || type == ScalarType::int32;
    if (is_signed) return value >= -(std::int64_t{1} << (bits - 1)) && value < (std::int64_t{1} << (bits - 1));
    return value >= 0 && value < (std::int64_t{1} << bits);
  }

  std::optional<double> next_binary(ScalarType type) {
    const std::size_t size = size_of(type);
    if (body_.size() - position_ < size) return std::nullopt;
    std::array<unsigned char, 8> raw{};
    std::memcpy(raw.data(), body_.data() + position_, size);
    position_ += size;
    const bool file_is_little = encoding_ == Encoding::little_endian;
    if (file_is_little != (std::endian::native == std::endian::little)) {
      for (std::size_t k = 0; k < size / 2; ++k) std::swap(raw[k], raw[size - 1 - k]);
    }
    switch (type) {
      case ScalarType::int8: return decode<std::int8_t>(raw);
      case ScalarType::uint8: return decode<std::uint8_t>(raw);
      case ScalarType::int16: return decode<std::int16_t>(raw);
      case ScalarType::uint16: return decode<std::uint16_t>(raw);
      case ScalarType::int32: return decode<std::int32_t>(raw);
      case ScalarType::uint32: return decode<std::uint32_t>(raw);
      case ScalarType::float32: return decode<float>(raw);
      case ScalarType::float64: return decode<double>(raw);
    }
    return std::nullopt;
  }

  template <class T>
  static double decode(const std::array<unsigned char, 8>& raw) {
    T value;
    std::memcpy(&value, raw.data(), sizeof value);
    return static_cast<double>(value);
  }

  std::string_view body_;
  Encoding encoding_;
  TokenCursor tokens_;
  std::string_view last_token_;
  std::size_t position_ = 0;
};

/// Indices into an element's properties of the values the mesh keeps.
struct VertexLayout {
  std::array<std::optional<std::size_t>, 3> position, normal;
  std::array<std::optional<std::size_t>, 2> uv;
};

std::optional<std::size_t> find_property(const Element& element, std::string_view name) {
  for (std::size_t k = 0; k < element.properties.size(); ++k) {
    if (element.properties[k].name == name && !element.properties[k].list_count) return k;
  }
  return std::nullopt;
}

VertexLayout vertex_layout(const Element& vertex) {
  VertexLayout layout;
  const std::array<std::string_view, 3> position_names = {"x", "y", "z"}, normal_names = {"nx", "ny", "nz"};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    layout.position[axis] = find_property(vertex, position_names[axis]);
    if (!layout.position[axis]) refuse("PLY vertex element has no scalar property '" + std::string(position_names[axis]) + "'");
    layout.normal[axis] = find_property(vertex, normal_names[axis]);
  }
  if (!layout.normal[0] || !layout.normal[1] || !layout.normal[2]) layout.normal = {};
  constexpr std::array<std::array<std::string_view, 2>, 3> uv_names = {{{"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}}};
  for (const auto& names : uv_names) {
    layout.uv = {find_property(vertex, names[0]), find_property(vertex, names[1])};
    if (layout.uv[0] && layout.uv[1]) break;
    layout.uv = {};
  }
  return layout;
}

/// The minimum bytes one element occupies in the body: its scalars and list
/// counts in binary, and at least two characters per value in ascii.
std::size_t minimum_element_size(const Element& element, Encoding encoding) {
  std::size_t size = 0;
  for (const Property& property : element.properties) {
    size += encoding == Encoding::ascii ? 2 : size_of(property.list_count.value_or(property.type));
  }
  return size;
}

struct FaceLists {
  std::vector<std::size_t> indices;       ///< every face's vertex indices, concatenated
  std::vector<std::size_t> corner_counts;
};

}  // namespace

Mesh read_ply(std::string_view bytes, std::vector<std::string>& warnings) {
  const Header header = parse_header(bytes, warnings);
  const Element* vertex_element = nullptr;
  const Element* face_element = nullptr;
  for (const Element& element : header.elements) {
    if (element.name == "vertex" && !vertex_element) vertex_element = &element;
    if (element.name == "face" && !face_element) face_element = &element;
  }
  if (!vertex_element) refuse("PLY file has no vertex element");
  if (!face_element) refuse("PLY file has no face element");
  const VertexLayout layout = vertex_layout(*vertex_element);
  std::optional<std::size_t> index_list;
  for (std::size_t k = 0; k < face_element->properties.size(); ++k) {
    const Property& property = face_element->properties[k];
    if ((property.name == "vertex_indices" || property.name == "vertex_index") && property.list_count) {
      if (!is_integral(property.type)) refuse("PLY face property '" + property.name + "' must hold integers");
      index_list = k;
      break;
    }
  }
  if (!index_list) refuse("PLY face element has no list property 'vertex_indices'");

  const std::string_view body = bytes.substr(header.body_offset);
  if (const std::size_t nul = body.find('\0'); header.encoding == Encoding::ascii && nul != std::string_view::npos) {
    const auto line = header.line_count + 1 + static_cast<std::size_t>(std::count(body.begin(), body.begin() + static_cast<std::ptrdiff_t>(nul), '\n'));
    refuse("PLY ascii body contains a NUL byte" + at_line(line));
  }
  ValueReader reader(body, header.encoding, header.line_count);
  std::vector<Vec3> positions, normals;
  std::vector<Vec2> uvs;
  FaceLists faces;
  std::vector<double> values;

  for (const Element& element : header.elements) {
    const bool is_vertex = &element == vertex_element, is_face = &element == face_element;
    const std::size_t minimum_size = minimum_element_size(element, header.encoding);
    // An element without properties occupies no bytes, so however many the
    // header claims there is nothing to read (and no time to spend on them).
    if (minimum_size == 0) continue;
    const std::size_t expected = reserve_bound(element.count, body.size(), minimum_size);
    if (is_vertex) {
      positions.reserve(expected);
      if (layout.normal[0]) normals.reserve(expected);
      if (layout.uv[0]) uvs.reserve(expected);
    }
    for (std::uint64_t index = 0; index < element.count; ++index) {
      values.clear();
      for (std::size_t p = 0; p < element.properties.size(); ++p) {
        const Property& property = element.properties[p];
        const auto value_or_refuse = [&](ScalarType type) {
          const std::optional<double> value = reader.next(type);
          if (!value) refuse("PLY " + reader.location(element, index) + ": property '" + property.name.substr(0, 40) + "' " + reader.failure());
          return *value;
        };
        if (!property.list_count) {
          values.push_back(value_or_refuse(property.type));
          continue;
        }
        const double length = value_or_refuse(*property.list_count);
        if (length < 0) refuse("PLY " + reader.location(element, index) + ": negative list length");
        const bool is_index_list = is_face && p == *index_list;
        if (is_index_list && length < 3) {
          refuse("PLY " + reader.location(element, index) + " has " + std::to_string(static_cast<std::int64_t>(length)) +
                 " vertices, at least 3 needed");
        }
        for (std::uint64_t item = 0; item < static_cast<std::uint64_t>(length); ++item) {
          const double vertex_index = value_or_refuse(property.type);
          if (!is_index_list) continue;
          if (vertex_index < 0 || vertex_index >= static_cast<double>(vertex_element->count)) {
            refuse("PLY " + reader.location(element, index) + ": vertex index " +
                   std::to_string(static_cast<std::int64_t>(vertex_index)) + " out of range [0, " +
                   std::to_string(vertex_element->count) + ")");
          }
          faces.indices.push_back(static_cast<std::size_t>(vertex_index));
        }
        if (is_index_list) faces.corner_counts.push_back(static_cast<std::size_t>(length));
        values.push_back(0);  // keeps values[p] aligned with property p
      }
      if (!is_vertex) continue;
      const auto value_at = [&](const std::optional<std::size_t>& slot) { return values[*slot]; };
      const Vec3 position{value_at(layout.position[0]), value_at(layout.position[1]), value_at(layout.position[2])};
      if (!is_finite(position)) refuse("non-finite coordinate at PLY " + reader.location(element, index));
      positions.push_back(position);
      if (layout.normal[0]) normals.push_back({value_at(layout.normal[0]), value_at(layout.normal[1]), value_at(layout.normal[2])});
      if (layout.uv[0]) uvs.push_back({value_at(layout.uv[0]), value_at(layout.uv[1])});
    }
  }
  if (!reader.at_end()) refuse("PLY file has data after its last element");

  IndexedSoup soup;
  std::size_t first = 0;
  for (const std::size_t corner_count : faces.corner_counts) {
    const std::size_t* polygon = faces.indices.data() + first;
    first += corner_count;
    triangulate_polygon(corner_count, [&](std::size_t k) { return positions[polygon[k]]; }, [&](std::size_t k) {
      const std::size_t vertex = polygon[k];
      soup.corner_vertices.push_back(vertex);
      if (!normals.empty()) soup.corners.normals.push_back(normals[vertex]);
      if (!uvs.empty()) soup.corners.uvs.push_back(uvs[vertex]);
    });
  }
  soup.positions = std::move(positions);
  return weld(std::move(soup));
}

namespace {

template <class T>
void append_little_endian(std::string& out, T value) {
  std::array<char, sizeof(T)> raw;
  std::memcpy(raw.data(), &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(raw.begin(), raw.end());
  out.append(raw.data(), raw.size());
}

}  // namespace

std::string write_ply(const Mesh& mesh) {
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment written by shatter\n";
  out += "element vertex " + std::to_string(mesh.vertex_count()) + "\n";
  out += "property double x\nproperty double y\nproperty double z\n";
  out += "element face " + std::to_string(mesh.triangle_count()) + "\n";
  out += "property list uchar uint vertex_indices\nend_header\n";
  for (const Vec3& position : mesh.positions) {
    append_little_endian(out, position.x);
    append_little_endian(out, position.y);
    append_little_endian(out, position.z);
  }
  for (const Triangle& triangle : mesh.triangles) {
    append_little_endian(out, std::uint8_t{3});
    for (const VertexIndex vertex : triangle) append_little_endian(out, vertex);
  }
  return out;
}

}  // namespace shatter::io_detail
