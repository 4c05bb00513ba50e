#pragma once
// Mesh readers and writers: OFF, OBJ, PLY (ascii and binary), STL (ascii and binary).
//
// Readers never repair: they weld corners whose positions are equal (so -0.0 and
// +0.0 weld, and nothing within a tolerance does), triangulate polygons (by the
// fan from their first corner where its triangles all turn the polygon's way,
// else by ear clipping decided exactly in a projection: io_internal.hpp), keep
// every face as written (a degenerate face stays, for validation to name), drop
// vertices no face uses, and throw on anything malformed, including a file with no
// faces. Vertices are numbered in order of first use by the triangles. Writers print
// coordinates as shortest round-trip decimals (text) or as IEEE doubles (binary PLY),
// so a mesh read back is the mesh written (positions bit for bit) whenever its
// vertices are numbered as a reader numbers them, as every mesh read is.
//
// Per format:
// - OFF: plain OFF, and COFF/NOFF/CNOFF/ST* (extra vertex values ignored); face
//   colours ignored; 4OFF, nOFF and binary OFF refused. Face lines after the
//   header's face count are skipped with a warning (the header's count is what
//   the format defines and what CGAL, Manifold and MeshLab read; CGAL's prim.off
//   holds 8 faces under a header of 7); other content there is refused. Writes
//   no attributes.
// - OBJ: v/vt/vn/f with negative indices; a channel (uv or normal) present on
//   some corners but not on all of them is dropped, with a warning (other tools
//   write such files: a face added without texture coordinates). Writes uvs and
//   normals (each distinct value once); tangents are not written.
// - PLY: ascii and both binary byte orders; per-vertex nx/ny/nz and u,v (or s,t,
//   texture_u,texture_v) become per-corner attributes. A header line that starts
//   with no PLY keyword (old Blender exporters wrote "Created by Blender3D ..."
//   without "comment") is skipped with a warning. Writes binary little-endian
//   positions and triangles only: per-corner attributes do not fit PLY's
//   per-vertex layout without splitting the welded vertices.
// - STL: ascii and binary (binary exactly when the size is 84 + 50 n); an ascii
//   file of several `solid ... endsolid` blocks is one mesh of all of them (with
//   a warning). Written as ascii, which keeps doubles; holds no attributes.
//
// Warnings: what a reader accepted that the format's letter does not allow, one
// line each ("PLY: header line 3 starts with no PLY keyword, skipped: ..."),
// appended to `warnings` when the caller passes a vector. Nothing is accepted
// that changes the geometry the format's letter defines: a warning only ever
// drops an attribute channel, skips text that holds none, or skips OFF face
// lines beyond the header's count.

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "shatter/kernel/mesh.hpp"

namespace shatter {

enum class MeshFormat { off, obj, ply, stl };

/// The format named by a file's extension (case-insensitive), or nullopt.
std::optional<MeshFormat> format_from_extension(const std::filesystem::path& path);
/// The format named "off", "obj", "ply" or "stl", or nullopt.
std::optional<MeshFormat> parse_mesh_format(std::string_view name);
/// The lower-case name and file extension (without dot) of a format.
std::string_view format_name(MeshFormat format);

/// Reads a mesh from `path`, choosing the format by its extension. `warnings`
/// (nullptr: not wanted) gets one line per liberty taken (see above), in file order.
/// Throws IoError when the file cannot be opened or read, InvalidMeshError when
/// its content is malformed (the message names the line or element at fault),
/// including an unknown extension. Guarantees the BasicMesh invariants.
Mesh read_mesh(const std::filesystem::path& path, std::vector<std::string>* warnings = nullptr);

/// Reads a mesh held in memory; the entry point of the fuzz targets. `warnings`
/// as read_mesh.
/// Throws InvalidMeshError on malformed content; never allocates more than a
/// small multiple of `bytes.size()` whatever the header claims.
Mesh read_mesh_from_bytes(std::string_view bytes, MeshFormat format, std::vector<std::string>* warnings = nullptr);

/// Serialises a mesh. Deterministic: the same mesh gives the same bytes.
std::string write_mesh_to_bytes(const Mesh& mesh, MeshFormat format);

/// Writes a mesh atomically: to a temporary file beside `path`, then renamed over
/// it, so `path` is either untouched or complete. Throws IoError on failure, and
/// then leaves no temporary file behind.
void write_mesh(const Mesh& mesh, const std::filesystem::path& path, MeshFormat format);

/// Writes `bytes` to `path` atomically, as write_mesh does. Throws IoError.
void write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

}  // namespace shatter
