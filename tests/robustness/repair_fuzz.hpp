#pragma once
// shatter-fuzz's repair cases (issue 21, item 4): valid meshes of the pool damaged
// the ways real files are (unwelded, duplicated, flipped, holed, nested with the
// wrong orientation, touching, overlapping, several at once), given to
// repair_mesh, and every promise of the repair checked: what it must give back
// exactly, that it never changes a valid mesh, that it is deterministic, and
// that a repaired solid cuts into valid pieces. A mesh the repair cannot make
// valid is a refusal (counted, with the defect validate_mesh names), not a
// failure, except for the classes whose damage repair_mesh promises to undo.
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "robustness/robustness.hpp"
#include "shatter/kernel/mesh.hpp"

namespace shatter::robust {

/// How a valid mesh is damaged. Each class names what a repair must give back.
enum class DamageClass : std::uint8_t {
  unwelded,     ///< every triangle on its own vertex copies, triangles shuffled: back exactly
  duplicated,   ///< triangles repeated (rotated), back-to-back pairs and repeated-index triangles added: back exactly
  flipped,      ///< a random share of the triangles reversed: back exactly
  holes,        ///< triangles removed (scattered or one patch): closed again, every kept triangle kept
  nested,       ///< a shell inside a shell, both outward: the inner reversed into a cavity, exactly
  touching,     ///< two lattice boxes sharing exactly one vertex or one edge (non-manifold): separated, every
                ///< triangle away from the shared positions kept, the volume lost within the moves' bound
  overlapping,  ///< the mesh and a shifted copy of it: the surfaces cross (self-intersecting)
  mixed,        ///< unwelded, duplicated, flipped and holed at once: closed again, every kept triangle kept
  stray,        ///< triangles stuck on edges (zero-area: an edge and its exact midpoint; fins: a point off the
                ///< edge's line), reversed and repeated copies of triangles: back exactly
};
inline constexpr int damage_class_count = 9;
std::string_view damage_name(DamageClass kind);

struct DamageCase {
  DamageClass kind = DamageClass::unwelded;
  std::string mesh_name;
  std::uint64_t seed = 0;
  Mesh original;  ///< the valid mesh (for nested: the exact expected repair)
  Mesh damaged;   ///< what repair_mesh is given
  /// Oriented triangles (as position triples) the repair must keep: every one of
  /// the original's for the classes repaired exactly, the ones not removed for
  /// holes and mixed.
  std::vector<std::array<Vec3, 3>> kept;
  bool exact = false;  ///< the repair must give `original` back as a set of oriented triangles
  Plane plane;         ///< the cut made in a repaired solid
};

struct DamageOutcome {
  std::vector<std::string> failures;  ///< broken promises; empty when every check held
  bool valid = false;                 ///< the repaired mesh passed validate_mesh
  std::string refusal;                ///< when not valid: validate_mesh's summary after repair
  std::size_t changes = 0;            ///< repair steps the report names
  double volume_change = 0;           ///< |volume after - original's| / original's, repaired solids only
  std::size_t pieces = 0, unroundable = 0, pinched = 0;  ///< the cut of a repaired solid
};

/// Case `index` of a repair run seeded with `seed`: its class is index mod
/// damage_class_count, the rest drawn from (seed, index) alone. Meshes come from
/// `pool` (those of at most 6,000 triangles) or, for touching and nested, from
/// lattice boxes and ellipsoids. Deterministic.
DamageCase make_damage_case(const MeshPool& pool, std::uint64_t seed, std::uint64_t index);

/// Repairs the case's damaged mesh and checks every promise (see the file
/// comment). Never throws: an unexpected exception is a failure.
DamageOutcome run_damage_case(const DamageCase& c);

}  // namespace shatter::robust
