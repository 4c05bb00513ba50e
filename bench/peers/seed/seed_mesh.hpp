#pragma once
// Between shatter's meshes and the seed's float pieces: what Unity would hold of a
// mesh read from a file, and a piece as written for shatter's validator. Shared by
// shatter-seed-peer and the robustness comparison (bench/robustness_bench.cpp).

#include "seed_modeller.hpp"
#include "shatter/kernel/mesh.hpp"

namespace seed_peer {

/// The float mesh Unity would hold: each triangle's corners rounded to floats, one
/// by one (nearest float of each double coordinate).
Piece to_piece(const shatter::Mesh& mesh);

/// A piece as an indexed mesh: corners are one vertex when `weld` (the seed's own
/// comparison, or bitwise) calls their positions equal; the position kept is the
/// group's first, exactly as a double. Every triangle keeps its corners' order.
shatter::Mesh to_mesh(const Piece& piece, Compare weld);

}  // namespace seed_peer
