#pragma once
// Inside the meshtree library only: who may make a TreeCertificate (tree.hpp).
// A certificate says "validate_tree(tree) passes, caches included", bound to
// the tree's content by a digest. build_mesh_tree makes one for the tree it
// built, whose invariants hold by construction (README "Certificates carried,
// not re-checked" gives the argument, invariant by invariant); certify_tree
// makes one after validate_tree passed; pack_leaves carries one across its
// lossless repacking. Nothing else may, so a certificate is never made on trust
// by a caller.

#include <array>
#include <cstdint>

#include "shatter/meshtree/tree.hpp"

namespace shatter::detail {

struct TreeCertifier {
  /// The digest of everything validate_tree reads of `tree`: the recipe, every
  /// node's fields, mesh, hull and solid (caches included), the leaf list, the
  /// bonds, the input geometry (caches included), the cut planes and the
  /// packed nodes; every array with its length. Not shatter_version nor
  /// input_repair, which validate_tree does not read (encode_shatter checks
  /// their text rules on every call). Four lanes of word-wise multiply-rotate
  /// chains (word k in lane k mod 4), each step a bijection of the lane for a
  /// fixed word and of the word for a fixed lane, folded into two outputs by
  /// bijections of each lane; the nodes, the bonds and the packed nodes are
  /// hashed in runs of a fixed length, each run by a chain of its own, whose
  /// final state goes into the main chain as five words. A change confined to
  /// one 64-bit word always changes the digest, and any other change leaves it
  /// equal with probability about 2^-128 (a guard against accidents, not
  /// against a forger in the process, who could write the file's bytes
  /// directly anyway). The value does not depend on the threads.
  /// Cost: one pass over the tree's memory (a packed node's bytes, not
  /// unpacked), the runs in parallel on the caller's task arena. Never throws.
  static std::array<std::uint64_t, 2> digest(const MeshTree& tree);

  /// Certifies `tree` as it is now. Precondition: validate_tree(tree) passes
  /// (caches on), established by the caller: checked, or true by construction;
  /// with `masses_derived`, also that every node's mass is mass_properties of
  /// its mesh bit for bit (TreeCertificate::masses_derived).
  static void certify(MeshTree& tree, bool masses_derived);

  /// Whether `tree` has a certificate and its digest is the tree's now.
  static bool holds(const MeshTree& tree);

  static void clear(MeshTree& tree) { tree.certificate = TreeCertificate(); }
};

}  // namespace shatter::detail
